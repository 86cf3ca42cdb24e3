#!/usr/bin/env bash
# Creates (once) the Python venv target/convert-venv with MediaPipe's wheel (the BlazePose
# .tflite models), TensorFlow's TFLite interpreter, the ONNX converter and OpenCV, pinned to
# versions that work together, and prints its python's path. Quick when already installed.
# Used by scripts/convert-blazepose.sh (the tests use the smaller scripts/reference-venv.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/convert-venv
# mediapipe 0.10.14's wheel ships the pose landmark models (the 1.x wheels do not); numpy < 2,
# ml-dtypes 0.3 and opencv 4.10 keep tensorflow-cpu 2.15 importable beside it.
pins=('mediapipe==0.10.14' 'tensorflow-cpu==2.15.*' 'tf2onnx==1.17.0' 'onnx==1.16.*' 'onnxruntime==1.19.*'
  'numpy<2' 'ml-dtypes~=0.3.1' 'opencv-contrib-python==4.10.0.84')
[ -x "$venv/bin/python" ] || python3 -m venv "$venv" >&2
if ! "$venv/bin/python" -c 'import importlib.metadata as m, sys; sys.exit(m.version("mediapipe") != "0.10.14")' 2>/dev/null; then
  "$venv/bin/pip" install -q "${pins[@]}" >&2
fi
echo "$PWD/$venv/bin/python"

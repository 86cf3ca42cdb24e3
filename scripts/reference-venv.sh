#!/usr/bin/env bash
# Creates (once) the small Python venv target/reference-venv for the BlazePose cross-check
# (tests/blazepose_reference.rs, tests/python/blazepose_reference.py) and prints its python's
# path. Quick when already installed.
#
# It holds only what the reference needs: MediaPipe's wheel for the pose_landmark_full.tflite it
# ships (installed without its dependencies: the model file is read, the package is never
# imported) and the TFLite runtime that runs it (tflite-runtime 2.14, the interpreter TensorFlow
# itself embeds). OpenCV and NumPy come from Debian (python3-opencv, python3-numpy, installed by
# scripts/test-all.sh) through the system site packages. The conversion's heavy venv
# (TensorFlow, tf2onnx, onnxruntime: scripts/mediapipe-venv.sh) is not needed for testing.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/reference-venv
base=python3
[ -x /usr/bin/python3 ] && base=/usr/bin/python3
[ -x "$venv/bin/python" ] || "$base" -m venv --system-site-packages "$venv" >&2
if ! "$venv/bin/python" -c 'import importlib.metadata as m, sys
sys.exit(m.version("mediapipe") != "0.10.14" or m.version("tflite-runtime") != "2.14.0")' 2>/dev/null; then
  "$venv/bin/pip" install -q 'tflite-runtime==2.14.0' >&2
  "$venv/bin/pip" install -q --no-deps 'mediapipe==0.10.14' >&2
fi
echo "$PWD/$venv/bin/python"

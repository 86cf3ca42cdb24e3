#!/usr/bin/env bash
# Converts MediaPipe's BlazePose "full" landmark model to ONNX, offline and reproducibly:
# uses the pinned venv of scripts/mediapipe-venv.sh (mediapipe 0.10.14 for the .tflite inside its
# wheel, tensorflow-cpu 2.15 for the TFLite interpreter, tf2onnx, onnx 1.16, onnxruntime), extracts
# mediapipe/modules/pose_landmark/pose_landmark_full.tflite, converts it with tf2onnx to
# assets/pose_landmark_full.onnx, checks the ONNX outputs against the TFLite original on random,
# structured and sketch 256x256 inputs (max landmark difference in px of the 256^2 crop), and prints
# the versions and sha256s that assets/pose_landmark_full.LICENSE records.
# Usage: scripts/convert-blazepose.sh [OUT.onnx]   (default assets/pose_landmark_full.onnx)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-assets/pose_landmark_full.onnx}
py=$(scripts/mediapipe-venv.sh)
venv=$(dirname "$(dirname "$py")")
tflite=$("$py" -c 'import mediapipe, os; print(os.path.join(os.path.dirname(mediapipe.__file__), "modules/pose_landmark/pose_landmark_full.tflite"))')
[ -f "$tflite" ] || { echo "missing $tflite in the mediapipe wheel" >&2; exit 1; }
work=target/convert-blazepose
mkdir -p "$work"
cp "$tflite" "$work/pose_landmark_full.tflite"
"$py" -m tf2onnx.convert --tflite "$work/pose_landmark_full.tflite" --output "$out" --opset 13 > "$work/tf2onnx.log" 2>&1 \
  || { cat "$work/tf2onnx.log" >&2; exit 1; }

"$py" - "$work/pose_landmark_full.tflite" "$out" <<'EOF'
import sys
import numpy as np
import onnxruntime as ort
import tensorflow as tf

tfl_path, onnx_path = sys.argv[1], sys.argv[2]
interp = tf.lite.Interpreter(model_path=tfl_path)
interp.allocate_tensors()
inp = interp.get_input_details()[0]
outs = {o["name"]: o for o in interp.get_output_details()}
sess = ort.InferenceSession(onnx_path, providers=["CPUExecutionProvider"])
onnx_in = sess.get_inputs()[0].name
print("tflite input", inp["name"], inp["shape"].tolist(), "outputs", {k: v["shape"].tolist() for k, v in outs.items()})
print("onnx input", onnx_in, sess.get_inputs()[0].shape, "outputs", [(o.name, o.shape) for o in sess.get_outputs()])
rng = np.random.default_rng(7)
yy, xx = np.mgrid[0:256, 0:256] / 255.0
inputs = [rng.random((1, 256, 256, 3), dtype=np.float32) for _ in range(3)]
inputs.append(np.stack([xx, yy, 1 - xx * yy], -1)[None].astype(np.float32))
inputs.append(np.ones((1, 256, 256, 3), np.float32))
import cv2
sketch = cv2.imread("assets/examples/sketch.png", cv2.IMREAD_COLOR)[:, :, ::-1]
inputs.append(cv2.resize(sketch, (256, 256), interpolation=cv2.INTER_AREA)[None].astype(np.float32) / 255.0)
worst, diffs = 0.0, []
for x in inputs:
    interp.set_tensor(inp["index"], x)
    interp.invoke()
    ref = {k: interp.get_tensor(v["index"]) for k, v in outs.items()}
    got = dict(zip([o.name for o in sess.get_outputs()], sess.run(None, {onnx_in: x})))
    lm_name = next(k for k, v in ref.items() if v.size == 195)
    a = ref[lm_name].reshape(39, 5)
    b = got[lm_name].reshape(39, 5)
    d = float(np.max(np.hypot(a[:, 0] - b[:, 0], a[:, 1] - b[:, 1])))
    worst = max(worst, d)
    print(f"  input {len(diffs)}: max landmark difference {d:.5f} px")
    diffs.append(d)
flag = next(k for k, v in ref.items() if v.size == 1)
print(f"onnx vs tflite: max landmark difference {worst:.5f} px at 256^2 over {len(inputs)} inputs; pose flag output {flag}")
# Random-noise inputs are far from the training data and amplify float rounding most; 0.1 px
# is 0.04% of the crop and 10x below the cross-check's tolerance.
assert worst < 0.1, worst
EOF

"$py" - <<'EOF'
import importlib.metadata as md
for p in ["mediapipe", "tensorflow-cpu", "tf2onnx", "onnx", "onnxruntime"]:
    print(f"{p}=={md.version(p)}")
EOF
mp_version=$("$py" -c 'import importlib.metadata as m; print(m.version("mediapipe"))')
"$venv/bin/pip" download -q --no-deps "mediapipe==$mp_version" -d "$work/wheel"
sha256sum "$work"/wheel/mediapipe-*.whl
sha256sum "$work/pose_landmark_full.tflite" "$out"
ls -l "$out"

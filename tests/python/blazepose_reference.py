"""Reference landmarks for the BlazePose cross-check (tests/blazepose_reference.rs).

Runs MediaPipe's own landmark model (the pose_landmark_full.tflite inside the mediapipe wheel,
with the TFLite interpreter: tflite-runtime's, or TensorFlow's when that is what is installed)
on the crop of each image given by the ROI the Rust side chose, with MediaPipe's pre- and
post-processing written independently of the Rust code: OpenCV warpAffine (bilinear, white
border) mapping the ROI's corners to the 256x256 tensor's corners, RGB in [0, 1], landmarks x /
256, y / 256 rotated and scaled back into the image, sigmoid of the visibility and presence
logits; and the landmarks refined from the model's heatmap output as MediaPipe's pose graph
refines them (its RefineLandmarksFromHeatmapCalculator: kernel 7, confidence 0.5), written from
the calculator's description with NumPy.

Usage: blazepose_reference.py CASES.json OUT.json
CASES.json: [{"image": path, "roi": {"cx", "cy", "size", "rotation"}}] in continuous pixel
coordinates (pixel i covers [i, i + 1)). OUT.json: [{"image", "landmarks": [[x, y, vis, pres]
x 39], "refined": [[x, y] x 39], "pose_flag"}].
"""
import importlib.util
import json
import math
import os
import sys

import cv2
import numpy as np

try:
    from tflite_runtime.interpreter import Interpreter
except ImportError:
    import tensorflow as tf

    Interpreter = tf.lite.Interpreter

SIDE = 256
KERNEL = 7
MIN_CONFIDENCE = 0.5


def crop(rgb, roi):
    """The ROI resampled to SIDE x SIDE, float32 RGB in [0, 1]."""
    s, c = math.sin(roi["rotation"]), math.cos(roi["rotation"])
    size = roi["size"]
    # Inverse map: tensor pixel (u, v) -> continuous image point -> OpenCV pixel-centre point.
    a = np.array([[size * c / SIDE, -size * s / SIDE], [size * s / SIDE, size * c / SIDE]])
    t = np.array([roi["cx"], roi["cy"]]) - a @ np.array([SIDE / 2, SIDE / 2]) - 0.5
    m = np.hstack([a, t[:, None]])
    img = rgb.astype(np.float32) / 255.0
    return cv2.warpAffine(img, m, (SIDE, SIDE), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=(1.0, 1.0, 1.0))


def refine(raw, heatmap):
    """Landmark x, y (tensor px) moved to the sigmoid-weighted mean cell index in a KERNEL-wide
    window of their heatmap channel (the window centred on the truncated cell, cut at the
    border; columns outside the map and rows above it skipped), when the window's largest
    confidence is at least MIN_CONFIDENCE."""
    hm_h, hm_w, _ = heatmap.shape
    conf = 1.0 / (1.0 + np.exp(-heatmap.astype(np.float64)))
    out = []
    half = (KERNEL - 1) // 2
    for k, (x, y) in enumerate(raw[:, :2]):
        col, row = int(x / SIDE * hm_w), int(y / SIDE * hm_h)
        if col < 0 or col >= hm_w or row < 0:
            out.append([x, y])
            continue
        rows = np.arange(max(0, row - half), min(hm_h, row + half + 1))
        cols = np.arange(max(0, col - half), min(hm_w, col + half + 1))
        w = conf[rows[:, None], cols[None, :], k]
        if w.size and w.max() >= MIN_CONFIDENCE and w.sum() > 0:
            out.append([(w * cols[None, :]).sum() / w.sum() / hm_w * SIDE,
                        (w * rows[:, None]).sum() / w.sum() / hm_h * SIDE])
        else:
            out.append([x, y])
    return np.array(out)


def main():
    cases = json.load(open(sys.argv[1]))
    # The wheel's model file; the package itself is not imported (its dependencies need not be
    # installed: scripts/reference-venv.sh installs it without them).
    package = importlib.util.find_spec("mediapipe").submodule_search_locations[0]
    model = os.path.join(package, "modules/pose_landmark/pose_landmark_full.tflite")
    interp = Interpreter(model_path=model)
    interp.allocate_tensors()
    inp = interp.get_input_details()[0]
    outs = interp.get_output_details()
    lm_out = next(o for o in outs if int(np.prod(o["shape"])) == 195)
    flag_out = next(o for o in outs if int(np.prod(o["shape"])) == 1)
    heat_out = next(o for o in outs if list(o["shape"]) == [1, 64, 64, 39])
    result = []
    for case in cases:
        bgr = cv2.imread(case["image"], cv2.IMREAD_UNCHANGED)
        if bgr.ndim == 2:
            rgb = np.repeat(bgr[:, :, None], 3, axis=2)
        elif bgr.shape[2] == 4:
            alpha = bgr[:, :, 3:4].astype(np.float32) / 255.0
            rgb = np.rint(bgr[:, :, 2::-1] * alpha + 255.0 * (1 - alpha)).astype(np.uint8)
        else:
            rgb = bgr[:, :, ::-1]
        roi = case["roi"]
        interp.set_tensor(inp["index"], crop(rgb, roi)[None])
        interp.invoke()
        raw = interp.get_tensor(lm_out["index"]).reshape(39, 5).astype(np.float64)
        refined = refine(raw, interp.get_tensor(heat_out["index"])[0])
        s, c = math.sin(roi["rotation"]), math.cos(roi["rotation"])

        def to_image(x, y):
            u, v = x / SIDE - 0.5, y / SIDE - 0.5
            return [roi["cx"] + roi["size"] * (c * u - s * v), roi["cy"] + roi["size"] * (s * u + c * v)]

        lms = [to_image(x, y) + [1 / (1 + math.exp(-vis)), 1 / (1 + math.exp(-pres))]
               for x, y, _z, vis, pres in raw]
        flag = float(interp.get_tensor(flag_out["index"]).reshape(-1)[0])
        result.append({"image": case["image"], "landmarks": lms,
                       "refined": [to_image(x, y) for x, y in refined], "pose_flag": flag})
    json.dump(result, open(sys.argv[2], "w"))


if __name__ == "__main__":
    main()

"""What the add-on asks of the sketchbody package, and the messages for what goes wrong.

`Request` holds everything one run needs as plain values (made on Blender's main thread from
the panel's settings); `compute` runs on the worker thread (jobs.Job) and returns the arrays
build.py turns into Blender objects. Nothing here imports bpy.

Joints follow the CLI's `run`: without a joints file the pipeline is called without joints
(`run_pipeline(joints=None)`), so the library detects them itself and treats them as detected
(their own fit settings, gender classifier and calibration) — the same body as `sketchbody run
SKETCH --out DIR` with the same options. Joints from a file or from corrected markers are the
user's (`run_pipeline(joints=...)`), as `sketchbody run --joints`.
"""

import dataclasses
import os
from typing import Optional

import numpy as np


class UserError(Exception):
    """A problem the user can fix; its text goes to the report as it is."""


@dataclasses.dataclass
class Request:
    """One run: `kind` "new" (Sketch to body: a new sketch plane and markers) or "rerun" (from
    the markers; the plane stays); `image` (absolute path) of `width` x `height` px; `joints`
    (skb.Joints2D, the user's) or None (the library detects them, as the CLI); `confidence`
    (15,) of the given joints (None when detected: the detector's); the package's `fit_options`
    and `rig_options`; `scene` (name) and `threshold` (low-confidence level) for the build;
    `views` a turnaround's extra views [(label "side" / "side_left" / "back", absolute path)]
    (their joints detected), empty for one view."""

    kind: str
    image: str
    width: int
    height: int
    joints: Optional[object]
    confidence: Optional[np.ndarray]
    fit_options: object
    rig_options: object
    scene: str
    threshold: float
    views: list = dataclasses.field(default_factory=list)

    @property
    def label(self):
        """What the panel calls this run."""
        return "Sketch to body" if self.kind == "new" else "Re-run"


def check_image(skb, path, what="sketch"):
    """(width, height) of the image at `path` (`what`: "sketch" or a view's name), decoded by the
    library as the pipeline will; UserError with a specific message when it is missing or not a
    PNG/JPEG image."""
    if not path:
        raise UserError("Choose a sketch image first")
    if not os.path.isfile(path):
        raise UserError(f"{what[0].upper() + what[1:]} image not found: {path}")
    try:
        img = skb.load_image(path)
    except skb.SketchbodyError as e:
        if e.status_name == "SKB_ERR_IMAGE_TOO_LARGE":
            raise UserError(f"The {what} {path} is too large for the library: {e.message}")
        raise UserError(f"Not an image the library can read: {path} is not a PNG or JPEG file "
                        f"({e.message}); choose the {what}'s PNG or JPEG file")
    return img.shape[1], img.shape[0]


def read_joints_file(skb, path):
    """(Joints2D, confidence (15,)) from a sketchbody-joints2d file; confidences from the file's
    optional "confidence" ({name: c} or a list), else 1 (0 for joints listed as missing)."""
    import json

    if not os.path.isfile(path):
        raise UserError(f"Joints file not found: {path}")
    try:
        joints = skb.Joints2D.from_json(path)
        with open(path, encoding="utf-8") as f:
            raw = json.load(f).get("confidence")
    except (skb.SketchbodyError, ValueError, KeyError, TypeError, OSError) as e:
        detail = str(e) if path in str(e) else f"{path}: {e}"
        raise UserError(f"Cannot read the joints file {detail}")
    conf = np.where(joints.visible, 1.0, 0.0)
    if isinstance(raw, dict):
        conf = np.array([float(raw.get(n, c)) for n, c in zip(skb.JOINT_NAMES, conf)])
    elif isinstance(raw, list) and len(raw) == len(conf):
        conf = np.array([float(c) for c in raw])
    return joints, conf


def _detected_confidence(skb, image, used, progress, cancel):
    """Per-joint calibrated confidences of the joints the pipeline detected (`used`, Joints2D):
    the standalone detector's (skb.detect, the same models and defaults), which finds the same
    joints; should it not, each joint gets the figure's confidence. Raises Cancelled when
    `cancel` is set."""
    if cancel.is_set():
        raise skb.Cancelled(skb.Status.SKB_ERR_CANCELLED, "cancelled", "detect")
    det = skb.detect(image)
    progress(1.0)
    if np.allclose(det.joints.xy, used.xy, atol=1e-6):
        return np.asarray(det.confidence, dtype=np.float64)
    return np.full(len(used.xy), float(det.score))


_dictionary = {}  # the package's embedded pose dictionary, parsed once per loaded package


def pose_dictionary(skb):
    """The embedded pose dictionary (the one run_pipeline uses by default), parsed on the first
    call for this package module and kept: the live re-pose needs it on every marker move."""
    d = _dictionary.get(id(skb))
    if d is None:
        d = _dictionary[id(skb)] = skb.PoseDictionary()
    return d


def posed_data(result, mesh, rig_options, width, height):
    """What re-posing the fitted body changes (the run's `compute`, and flip_limb / the live
    re-pose, which keep the shape): `camera`, `pixels` (the posed vertices projected, sketch
    pixels), `rig` (posed, with `rig_options`), `seen` (per vertex, how squarely the sketch's
    camera sees it, 0..1) and `sketch_uv` (the projection as UVs of a `width` x `height` sketch).
    `mesh` is `result.mesh()`, made after the last re-pose."""
    camera = result.camera()
    pixels = camera.project(result.vertices(posed=True))
    # How squarely the sketch's camera sees each vertex: the posed normal's component toward the
    # viewer (+Z of the camera frame), full from 0.2 on, none when facing away.
    toward_viewer = (mesh.normals(posed=True) @ camera.r.T)[:, 2]
    return dict(camera=camera, pixels=pixels, rig=mesh.rig(rig_options), seen=np.clip(toward_viewer / 0.2, 0.0, 1.0),
                sketch_uv=np.stack([pixels[:, 0] / width, 1.0 - pixels[:, 1] / height], axis=1))


def compute(skb, req, progress, cancel):
    """Runs the pipeline for `req` (worker thread; no bpy) with `progress(fraction)` and the
    `cancel` event; returns the dict build.py needs: rig, quads, uvs, face_uvs, seen, camera,
    pixels, width, height, sketch_uv, gender, gender_value, low_evidence, edge_support,
    joints (Joints2D used), confidence (15,), detection (skb.FigureInfo or None), body_height
    (the rest mesh's height, metres, as the CLI reports it), `result` (the open skb.Result,
    kept by the add-on to re-pose the body without re-fitting it; the receiver closes it) and
    `dictionary` (pose_dictionary: parsed here, off Blender's main thread)."""
    share = 0.9 if req.joints is None else 1.0  # the rest: the detector's per-joint confidences
    views = [skb.View(label, path) for label, path in req.views]
    result = skb.run_pipeline(req.image, joints=req.joints, fit_options=req.fit_options,
                              progress=lambda f: progress(share * f), cancel=cancel, views=views)
    try:
        data = dict(gender=result.gender, gender_value=result.gender_value()[0], joints=result.joints2d(),
                    detection=result.detection(), width=req.width, height=req.height, views=result.views(),
                    view_warnings=result.view_warnings())
        data["low_evidence"], data["edge_support"] = result.evidence()
        data["body_height"] = float(np.ptp(result.vertices(posed=False)[:, 1]))
        with result.mesh() as mesh:
            data.update(quads=mesh.faces(), uvs=mesh.uvs(), face_uvs=mesh.face_uvs())
            data.update(posed_data(result, mesh, req.rig_options, req.width, req.height))
        if req.joints is None:
            data["confidence"] = _detected_confidence(skb, req.image, data["joints"],
                                                      lambda f: progress(share + (1 - share) * f), cancel)
        else:
            data["confidence"] = np.asarray(req.confidence, dtype=np.float64)
    except BaseException:
        result.close()
        raise
    data["result"], data["dictionary"] = result, pose_dictionary(skb)
    return data


def describe_error(skb, error, req):
    """The message for an exception `compute` raised: a specific sentence for what the user can
    act on (a blank page, no figure found, joints outside the sketch, a sketch too small), the
    library's own message otherwise; never a traceback."""
    name = getattr(error, "status_name", None)
    where = req.image
    if isinstance(error, UserError):
        return str(error)
    if name == "SKB_ERR_BLANK_IMAGE":
        return (f"The sketch is a blank page: {where} has no strokes to fit a body to "
                f"({error.message}); choose the drawing's file")
    if name == "SKB_ERR_NO_FIGURE":
        return (f"No figure found in the sketch {where}: the detector sees no human figure on the page "
                f"({error.message}). If there is one, give its 15 joints in a joints file "
                "(sketchbody-joints2d JSON, e.g. from `sketchbody detect`) and correct them on the sketch")
    if name == "SKB_ERR_VIEWS_DISAGREE":
        return (f"The views do not show one character in one pose: {error.message}. Check each view's image "
                "and, for the side view, which way it faces")
    if name == "SKB_ERR_IMAGE_TOO_SMALL":
        return f"The sketch {where} is too small: {error.message}"
    if name == "SKB_ERR_JOINT_OUTSIDE_IMAGE":
        source = "the joint markers" if req.kind == "rerun" else "the joints file"
        return f"A joint of {source} lies outside the sketch: {error.message}"
    if name in ("SKB_ERR_TOO_FEW_JOINTS", "SKB_ERR_COINCIDENT_JOINTS", "SKB_ERR_DEGENERATE"):
        return f"The 2-D joints give no 3-D pose: {error.message} ({name}); correct the joints"
    if name is not None:
        return f"Sketchbody failed: {error.message} ({name})"
    return f"Sketchbody failed: {type(error).__name__}: {error}"

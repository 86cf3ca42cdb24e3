"""The main job (sketch + 2-D joints -> rigged, posed body) and the shape fit."""

import ctypes
import dataclasses
from typing import Optional

import numpy as np

from . import _arrays as A
from . import _bindings as B
from ._lib import Handle, Progress, call, error, lib, new_handle
from ._options import OptionsBase, options_handle
from .context import AUTO, FEMALE, MALE, default_context, gender_name
from .detect import Facing, FigureInfo
from .images import as_image, load_rgb_image
from .mesh import Mesh
from .pose import REPOSE_OUTCOMES, Camera, Joints2D, PoseEstimate, PoseOptions, _dict_arg, joints2d_arg, limb_index

_WHICH = {"rest": B.SKB_JOINTS_REST, "posed": B.SKB_JOINTS_POSED, "estimated": B.SKB_JOINTS_ESTIMATED}

#: Labels of a turnaround's extra views (`View.label`) and their library codes.
VIEW_LABELS = {"side": B.SKB_VIEW_SIDE, "side_left": B.SKB_VIEW_SIDE_LEFT, "back": B.SKB_VIEW_BACK}
_VIEW_NAMES = {code: name for name, code in VIEW_LABELS.items()}


@dataclasses.dataclass
class View:
    """One extra view of a turnaround for run_pipeline(views=...): `label` "side" (the
    character's right side, facing image right), "side_left" or "back"; `sketch` a numpy uint8
    image or a PNG/JPEG path; `joints` its 2-D joints in that image's pixels (as run_pipeline's
    `joints`; None: detected)."""

    label: str
    sketch: object
    joints: object = None


@dataclasses.dataclass
class ViewInfo:
    """What a turnaround run made of one extra view: its label, the 2-D joints used
    (Joints2D, detected or given; `joints_swapped`: the detector's other left/right labelling,
    which fits the shared pose better), its Camera (projects Result.vertices() onto the view's
    sketch), `residual` (RMS distance of its joints from the shared pose, fraction of the
    figure's height), `scale_ratio` (its drawn size over the front's), `edge_support` (share of
    the fitted outline in the view near a stroke) and, for a side view, how its limbs agree with
    the front's pose as labelled and as the other side (degrees; None for a back view)."""

    label: str
    joints: Joints2D
    joints_detected: bool
    joints_swapped: bool
    camera: Camera
    residual: float
    scale_ratio: float
    edge_support: float
    facing_as_labelled_deg: Optional[float]
    facing_other_side_deg: Optional[float]


def _view_inputs(views):
    """The C view inputs of `views` (View objects) and what must stay alive with them."""
    views = list(views or [])
    arr = (B.skb_view_input * max(len(views), 1))()
    keep = []
    for k, v in enumerate(views):
        if not isinstance(v, View):
            raise TypeError(f"views[{k}] must be a View, not {type(v).__name__}")
        if v.label not in VIEW_LABELS:
            raise ValueError(f"views[{k}].label must be one of {sorted(VIEW_LABELS)}, not {v.label!r}")
        img, img_keep = as_image(v.sketch, f"views[{k}].sketch")
        j = None if v.joints is None else joints2d_arg(v.joints).to_struct()
        keep += [img, img_keep, j]
        arr[k].label = VIEW_LABELS[v.label]
        arr[k].sketch = ctypes.pointer(img)
        arr[k].joints = None if j is None else ctypes.pointer(j)
    return arr, len(views), keep


@dataclasses.dataclass
class FitOptions(OptionsBase):
    """Options of the shape fit (None: the library default; docs/c-api.md "Shape fit").
    gender: "female", "male" or "auto" (default: fitted as a continuous weight); height:
    the character's rest height in metres (0.1..10); score: "paper", "filled_iou",
    "chamfer" (default) or "two_sided_chamfer"; skinning: "linear" or "dual_quaternion"."""

    samples: Optional[int] = None
    iterations: Optional[int] = None
    transition_scale: Optional[float] = None
    score: Optional[str] = None
    temperature: Optional[float] = None
    joint_weight: Optional[float] = None
    height: Optional[float] = None
    sample_camera: Optional[bool] = None
    proportion_sd: Optional[float] = None
    estimate_proportions: Optional[bool] = None
    raster_side: Optional[int] = None
    tolerance: Optional[float] = None
    seed: Optional[int] = None
    skinning: Optional[str] = None
    inside_cap: Optional[float] = None
    dims: Optional[int] = None
    gender: Optional[str] = None

    _c_prefix = "skb_fit_options"
    _enums = {
        "score": {"paper": B.SKB_SCORE_PAPER, "filled_iou": B.SKB_SCORE_FILLED_IOU, "chamfer": B.SKB_SCORE_CHAMFER,
                  "two_sided_chamfer": B.SKB_SCORE_TWO_SIDED_CHAMFER},
        "skinning": {"linear": B.SKB_SKIN_LINEAR, "dual_quaternion": B.SKB_SKIN_DUAL_QUATERNION},
        "gender": {"female": FEMALE, "f": FEMALE, "male": MALE, "m": MALE, "auto": AUTO},
    }


class Result(Handle):
    """The result of run_pipeline: the fitted body posed to the sketch. Owns all its data.
    Several threads may read it at once; only the re-pose methods (pick_alternative, flip_limb,
    repose) change it, in place. Free with close() or `with`."""

    _free_fn = "skb_result_free"

    def _count(self, fn):
        n = ctypes.c_size_t()
        call(fn, self._p, ctypes.byref(n))
        return n.value

    @property
    def vertex_count(self):
        return self._count("skb_result_vertex_count")

    @property
    def face_count(self):
        return self._count("skb_result_face_count")

    @property
    def gender(self):
        """"female" or "male" (given, or the nearer end of the fitted gender value)."""
        g, by = ctypes.c_uint32(), ctypes.c_bool()
        call("skb_result_gender", self._p, ctypes.byref(g), ctypes.byref(by))
        return gender_name(g.value)

    @property
    def gender_fitted(self):
        """True when the gender was fitted, False when given."""
        g, by = ctypes.c_uint32(), ctypes.c_bool()
        call("skb_result_gender", self._p, ctypes.byref(g), ctypes.byref(by))
        return bool(by.value)

    def gender_value(self):
        """(value: 0 female mean .. 1 male mean, confidence 0.5..1)."""
        v, c = ctypes.c_double(), ctypes.c_double()
        call("skb_result_gender_value", self._p, ctypes.byref(v), ctypes.byref(c))
        return v.value, c.value

    @property
    def score(self):
        """The fit's best match score (higher is better)."""
        g, s = ctypes.c_uint32(), ctypes.c_double()
        call("skb_result_gender", self._p, ctypes.byref(g), None)
        call("skb_result_score", self._p, g.value, ctypes.byref(s))
        return s.value

    @property
    def detected(self):
        """True when the embedded detector found the 2-D joints (run_pipeline without `joints`),
        False when they were given."""
        return self.detection() is not None

    def detection(self):
        """The detection behind the joints (FigureInfo: backend, calibrated confidence,
        presence, low_confidence), or None when the joints were given to run_pipeline."""
        info = B.skb_figure_info()
        st = lib.skb_result_detection(self._p, ctypes.byref(info))
        if st == B.SKB_ERR_OUT_OF_RANGE:
            return None
        if st != B.SKB_OK:
            raise error(st, "skb_result_detection")
        return FigureInfo.from_struct(info)

    def facing(self):
        """The facing of the detected figure behind the joints (Facing: facing, probabilities,
        swapped, the swapped labelling and its score), or None when the joints were given."""
        f = B.skb_facing_info()
        st = lib.skb_result_facing(self._p, ctypes.byref(f))
        if st == B.SKB_ERR_OUT_OF_RANGE:
            return None
        if st != B.SKB_OK:
            raise error(st, "skb_result_facing")
        return Facing.from_struct(f)

    def evidence(self):
        """(low_evidence: bool, edge_support: fraction of the fitted outline near a stroke)."""
        low, sup = ctypes.c_bool(), ctypes.c_double()
        call("skb_result_evidence", self._p, ctypes.byref(low), ctypes.byref(sup))
        return bool(low.value), sup.value

    #: Body parts of `part_support`, in the library's order.
    BODY_PARTS = ("head", "torso", "right_arm", "left_arm", "right_leg", "left_leg")

    def part_support(self):
        """Per body part (names in BODY_PARTS), the share (0..1) of the fitted outline near a
        stroke, or None for a part out of view (every part of the mean shape). A part below 0.5
        is not supported by the drawing: the body there is the prior's reading."""
        out = np.full(len(self.BODY_PARTS), np.nan)
        call("skb_result_copy_part_support", self._p, A.ptr(out), out.size)
        return {name: (None if np.isnan(v) else float(v)) for name, v in zip(self.BODY_PARTS, out)}

    def vertices(self, posed=True):
        """(N, 3) float32 vertices, metres, model frame: posed (default) or rest."""
        out = np.empty((self.vertex_count, 3), dtype=np.float32)
        call("skb_result_copy_vertices", self._p, bool(posed), A.ptr(out), out.size)
        return out

    def faces(self):
        """(F, 4) uint32 quads (counter-clockwise from outside)."""
        out = np.empty((self.face_count, 4), dtype=np.uint32)
        call("skb_result_copy_faces", self._p, A.ptr(out), out.size)
        return out

    def joints2d(self):
        """The 2-D joints used (Joints2D)."""
        s = B.skb_joints2d()
        call("skb_result_joints2d", self._p, ctypes.byref(s))
        return Joints2D.from_struct(s)

    def views(self):
        """A turnaround's extra views (list of ViewInfo, in the order given; empty for one view)."""
        n = ctypes.c_size_t()
        call("skb_result_view_count", self._p, ctypes.byref(n))
        out = []
        for k in range(n.value):
            v = B.skb_view_info()
            call("skb_result_view", self._p, k, ctypes.byref(v))
            deg = (lambda x: None if np.isnan(x) else float(x))
            out.append(ViewInfo(_VIEW_NAMES[v.label], Joints2D.from_struct(v.joints), bool(v.joints_detected),
                                bool(v.joints_swapped), Camera.from_struct(v.camera), v.residual, v.scale_ratio, v.edge_support,
                                deg(v.facing_as_labelled_deg), deg(v.facing_other_side_deg)))
        return out

    def view_warnings(self):
        """What the run warns about its views (list of str: views that agree only roughly, a view
        little supported by its strokes); empty for one view."""
        buf = ctypes.create_string_buffer(self._count("skb_result_view_warnings_length") + 1)
        call("skb_result_copy_view_warnings", self._p, buf, len(buf))
        text = buf.value.decode("utf-8")
        return text.split("\n") if text else []

    def joints3d(self, which="posed"):
        """(15, 3) float64 3-D joints, metres: "rest" (the fitted shape's), "posed" (the
        mesh's) or "estimated" (the pose step's, a 1.75 m person)."""
        if which not in _WHICH:
            raise ValueError(f"which must be one of {sorted(_WHICH)}, not {which!r}")
        out = np.empty((15, 3), dtype=np.float64)
        call("skb_result_copy_joints3d", self._p, _WHICH[which], A.ptr(out), out.size)
        return out

    def camera(self):
        """The estimated weak-perspective Camera (model metres -> sketch pixels)."""
        c = B.skb_camera()
        call("skb_result_camera", self._p, ctypes.byref(c))
        return Camera.from_struct(c)

    def skin_weights(self):
        """(bones (N, 4) uint32 in 0..13, weights (N, 4) float32) to the 14 canonical bones.
        The 53-bone rig's weights: result.mesh().rig()."""
        n = self.vertex_count
        bones = np.empty((n, 4), dtype=np.uint32)
        weights = np.empty((n, 4), dtype=np.float32)
        call("skb_result_copy_skin_weights", self._p, A.ptr(bones), A.ptr(weights), bones.size)
        return bones, weights

    def shape_weights(self):
        """The fitted PCA shape weights (metres)."""
        out = np.empty(self._count("skb_result_shape_weight_count"), dtype=np.float64)
        call("skb_result_copy_shape_weights", self._p, A.ptr(out), out.size)
        return out

    def texture(self, sketch, size=1024):
        """The texture `sketchbody run` writes as body_texture.png for this result: `sketch`
        (the colour image the result was computed from, a numpy image or a PNG/JPEG path decoded
        in colour as the CLI does) projected through the result's camera onto its posed mesh, a
        (size, size, 3) uint8 RGB array in the UV layout (row 0 is v = 1; texels the sketch does
        not see grey). images.write_png(texture, path) writes the CLI's bytes."""
        if A.is_path(sketch):
            sketch = load_rgb_image(sketch)
        view, keep = A.image(sketch, "sketch")
        n = A.index(size, "size", 1, 4096)
        out = np.empty((n, n, 3), dtype=np.uint8)
        call("skb_result_project_texture", self._p, ctypes.byref(view), n, A.ptr(out), 3 * n, out.size, None, None)
        del keep
        return out

    def mesh(self):
        """A new Mesh of the result (fitted rest shape, posed as in the result) for UVs,
        normals, triangles, the rig and export (write_glb, write_obj, write_preview)."""
        return Mesh(new_handle("skb_mesh_new_from_result", B.skb_mesh, self._p))

    def pose_estimate(self):
        """A copy of the result's 3-D pose with its ranked depth readings (PoseEstimate;
        `.alternatives`). Flipping the copy does not change the result: use flip_limb()."""
        return PoseEstimate(new_handle("skb_pose_estimate_new_from_result", B.skb_pose_estimate, self._p))

    @property
    def alternatives(self):
        """The ranked depth readings of the result's pose (list of Alternative, best first;
        [0] is the current pose)."""
        with self.pose_estimate() as e:
            return e.alternatives

    def pick_alternative(self, index):
        """Re-poses the fitted body in place to alternative `index` (shape kept). Returns "done"."""
        o = ctypes.c_uint32()
        call("skb_result_pick_alternative", self._p, A.index(index, "index", 0, 2**32 - 1), ctypes.byref(o))
        return REPOSE_OUTCOMES[o.value]

    def flip_limb(self, limb):
        """Flips one limb's depth (LIMB_NAMES name or index) and re-poses the fitted body in place
        (shape kept). Returns "done" or "no_depth" (the limb lies in the picture plane)."""
        o = ctypes.c_uint32()
        call("skb_result_flip_limb", self._p, limb_index(limb), ctypes.byref(o))
        return REPOSE_OUTCOMES[o.value]

    def repose(self, joints, dictionary=None):
        """Re-poses the fitted body in place for moved 2-D joints (Joints2D, path, dict or
        (15, 2) array; the live correction while a joint is dragged): the 3-D pose is
        re-estimated, the shape kept. Returns "done", or with nothing changed
        "joint_outside_image", "joints_coincide" or "implausible". Not while another thread
        reads the result."""
        j = joints2d_arg(joints).to_struct()
        d = _dict_arg(dictionary)
        o = ctypes.c_uint32()
        call("skb_result_repose_joints", self._p, d._p, ctypes.byref(j), ctypes.byref(o))
        return REPOSE_OUTCOMES[o.value]


class _Interim:
    """The skb_interim_fn trampoline for one run: hands `interim(stage, vertices)` each interim
    body's stage name and a copy of its posed vertices; an exception it raises cancels the run
    at the next progress call and is re-raised."""

    STAGES = ("mean_shape", "deciding_fit")

    def __init__(self, interim, prog):
        if interim is not None and not callable(interim):
            raise TypeError(f"interim must be callable, not {type(interim).__name__}")
        self.interim, self.prog = interim, prog
        self.fn = B.skb_interim_fn(self._cb) if interim is not None else B.skb_interim_fn()

    def _cb(self, _user, stage, mesh):
        if self.prog.exc is not None:
            return
        try:
            n = ctypes.c_size_t()
            call("skb_mesh_vertex_count", mesh, ctypes.byref(n))
            v = np.empty((n.value, 3), dtype=np.float32)
            call("skb_mesh_copy_posed_vertices", mesh, A.ptr(v), v.size)
            self.interim(self.STAGES[stage] if stage < len(self.STAGES) else int(stage), v)
        except BaseException as e:  # noqa: BLE001 - re-raised after the C call
            self.prog.exc = e


def run_pipeline(sketch, joints=None, fit_options=None, pose_options=None, dictionary=None, progress=None,
                 cancel=None, context=None, interim=None, views=None):
    """The main job: Canny edges of `sketch` (numpy uint8 image or a PNG/JPEG path), the 2-D
    joints (`joints`: Joints2D, a sketchbody-joints2d JSON path, a dict or a (15, 2) array;
    None: the embedded detector finds them), the 3-D pose and camera, the shape fit and the
    fitted body posed to the estimate. Returns a Result.

    `progress(fraction)` is called on the calling thread after each stage and fit iteration;
    returning False cancels. `cancel` (e.g. a threading.Event, set from any thread) cancels
    too. Cancelling raises Cancelled within one fit iteration; an exception raised by
    `progress` cancels and is re-raised. The GIL is released while the library works.

    `interim(stage, vertices)` (optional) gets the bodies the run has before the final one, on
    the calling thread: "mean_shape" (the mean body posed to the estimated pose, right after the
    pose step), then "deciding_fit" (the chosen gender's first fit, when the gender is decided
    by fitting); `vertices` is an (N, 3) float32 copy of the posed vertices (metres, model
    frame, the Result's vertex order), e.g. to draw a first body at once.

    `views` (optional): a turnaround's extra views of the same character in the same pose
    (View objects: side, side_left, back; `sketch` is then the front view). The views share one
    body and pose (depth from a side view; every view's outline in the shape fit); read them back
    with Result.views() and Result.view_warnings(). Views that do not show one character in one
    pose raise an Error with status_name "SKB_ERR_VIEWS_DISAGREE"."""
    ctx = context or default_context()
    view, keep = as_image(sketch, "sketch")
    j = None if joints is None else joints2d_arg(joints).to_struct()
    d = None if dictionary is None else _dict_arg(dictionary)
    prog = Progress(progress, cancel, always=interim is not None)
    shown = _Interim(interim, prog)
    view_arr, view_count, view_keep = _view_inputs(views)
    out = ctypes.POINTER(B.skb_result)()
    with options_handle(fit_options, FitOptions) as fh, options_handle(pose_options, PoseOptions) as ph:
        try:
            call("skb_pipeline_run_views", ctx._p, ctypes.byref(view), None if j is None else ctypes.byref(j),
                 view_arr, view_count, None if d is None else d._p, ph, fh, prog.fn, shown.fn, None,
                 ctypes.byref(out))
        finally:
            prog.reraise()
    del keep, view_keep
    return Result(out)


def fit_shape(joints3d, camera, edges, options=None, progress=None, cancel=None, context=None):
    """The shape fit alone (SIR, paper §II-C) for a known pose: `joints3d` (15, 3) metres
    (e.g. Pose3D.joints), `camera` (Camera), `edges` an edge map (uint8 image, non-zero =
    edge, e.g. canny(sketch)). Returns (Mesh posed to joints3d, score)."""
    ctx = context or default_context()
    j = A.numeric(joints3d, "joints3d", np.float64, (15, 3))
    if not isinstance(camera, Camera):
        raise TypeError(f"camera must be a Camera, not {type(camera).__name__}")
    cam = camera.to_struct()
    view, keep = as_image(edges, "edges")
    prog = Progress(progress, cancel)
    score = ctypes.c_double()
    out = ctypes.POINTER(B.skb_mesh)()
    with options_handle(options, FitOptions) as fh:
        try:
            call("skb_context_fit_shape", ctx._p, A.ptr(j), j.size, ctypes.byref(cam), ctypes.byref(view), fh, prog.fn,
                 None, ctypes.byref(score), ctypes.byref(out))
        finally:
            prog.reraise()
    del keep
    return Mesh(out), score.value

"""2-D joints, the weak-perspective camera and the 3-D pose solver (paper §II-B)."""

import ctypes
import dataclasses
import threading
from typing import Optional

import numpy as np

from . import _arrays as A
from . import _bindings as B
from ._lib import Handle, call, new_handle
from ._options import OptionsBase, options_handle

JOINT_NAMES = B.JOINT_NAMES


@dataclasses.dataclass
class Joints2D:
    """15 image joints in canonical order (JOINT_NAMES), pixels, origin top-left, y down.
    `xy` is (15, 2) float64; `visible` (15,) bool (False: the position is only a guess)."""

    xy: np.ndarray
    visible: np.ndarray = None

    def __post_init__(self):
        self.xy = A.numeric(self.xy, "Joints2D.xy", np.float64, (15, 2))
        if self.visible is None:
            self.visible = np.ones(15, dtype=bool)
        else:
            v = np.asarray(self.visible)
            if v.shape != (15,) or v.dtype.kind not in "biu":
                raise ValueError(f"Joints2D.visible must be 15 booleans, got {v.dtype} {v.shape}")
            self.visible = v.astype(bool)

    @classmethod
    def from_dict(cls, joints, missing=()):
        """From {name: (x, y)} with every canonical name; `missing` names invisible joints."""
        unknown = set(joints) - set(JOINT_NAMES)
        if unknown:
            raise ValueError(f"unknown joint names {sorted(unknown)}")
        absent = [n for n in JOINT_NAMES if n not in joints]
        if absent:
            raise ValueError(f"joints lack {absent}")
        bad = set(missing) - set(JOINT_NAMES)
        if bad:
            raise ValueError(f"unknown joint names in missing: {sorted(bad)}")
        return cls(np.array([joints[n] for n in JOINT_NAMES], dtype=np.float64),
                   np.array([n not in missing for n in JOINT_NAMES]))

    @classmethod
    def from_json(cls, path):
        """Reads a `sketchbody-joints2d` file (docs/formats.md; what `sketchbody detect` and
        `run` write) with the library's reader, as the CLI and the C API read it: a regular file
        of at most 1 MiB (a FIFO, a device or a folder is refused without blocking), strict JSON
        (no NaN, no key twice; a UTF-8 BOM accepted), every joint named once. Raises
        SketchbodyError (SKB_ERR_IO, SKB_ERR_CORRUPT_DATA)."""
        s = B.skb_joints2d()
        call("skb_joints2d_read_json", A.path_arg(path), ctypes.byref(s))
        return cls.from_struct(s)

    @classmethod
    def from_json_text(cls, text):
        """Parses a `sketchbody-joints2d` document (str, or UTF-8 bytes) with the rules of
        from_json. Raises SketchbodyError (SKB_ERR_CORRUPT_DATA; SKB_ERR_OUT_OF_RANGE over 1 MiB)."""
        data = text.encode("utf-8") if isinstance(text, str) else bytes(text)
        s = B.skb_joints2d()
        call("skb_joints2d_parse_json", data, len(data), ctypes.byref(s))
        return cls.from_struct(s)

    def to_dict(self):
        return {"format": "sketchbody-joints2d", "version": 1,
                "joints": {n: [float(x), float(y)] for n, (x, y) in zip(JOINT_NAMES, self.xy)},
                "missing": [n for n, v in zip(JOINT_NAMES, self.visible) if not v]}

    def to_json(self, path):
        """Writes a `sketchbody-joints2d` file with the library's writer (atomic; only a
        regular file is replaced). Raises SketchbodyError (SKB_ERR_NON_FINITE, SKB_ERR_IO)."""
        s = self.to_struct()
        call("skb_joints2d_write_json", ctypes.byref(s), A.path_arg(path))

    def to_struct(self):
        s = B.skb_joints2d()
        xy = A.numeric(self.xy, "Joints2D.xy", np.float64, (15, 2))
        ctypes.memmove(s.xy, A.ptr(xy), xy.nbytes)
        for i, v in enumerate(self.visible):
            s.visible[i] = 1 if v else 0
        return s

    @classmethod
    def from_struct(cls, s):
        return cls(np.ctypeslib.as_array(s.xy).copy(), np.array(list(s.visible), dtype=bool) != 0)

    def swap_sides(self):
        """These joints with left and right swapped (each joint takes its mirror's position and
        visibility; head, neck and pelvis stay): the other labelling of a figure, e.g. a
        detection's alternative (skb_joints2d_swap_sides)."""
        s = self.to_struct()
        out = B.skb_joints2d()
        call("skb_joints2d_swap_sides", ctypes.byref(s), ctypes.byref(out))
        return Joints2D.from_struct(out)


def joints2d_arg(j, name="joints"):
    """A Joints2D from a Joints2D, a joints JSON path, a {name: (x, y)} dict or a (15, 2) array."""
    if isinstance(j, Joints2D):
        return j
    if A.is_path(j):
        return Joints2D.from_json(j)
    if isinstance(j, dict):
        return Joints2D.from_dict(j)
    if j is None:
        raise TypeError(f"{name} must be Joints2D, a path, a dict or a (15, 2) array, not None")
    return Joints2D(A.numeric(j, name, np.float64, (15, 2)))


@dataclasses.dataclass
class Camera:
    """Weak-perspective camera (paper eq. 1): model point X (metres) -> pixel
    u = sx (R X)_x + t[0], v = -sy (R X)_y + t[1]. `r` is (3, 3), `t` (2,)."""

    sx: float
    sy: float
    r: np.ndarray
    t: np.ndarray

    def __post_init__(self):
        self.sx, self.sy = A.real(self.sx, "Camera.sx"), A.real(self.sy, "Camera.sy")
        self.r = A.numeric(self.r, "Camera.r", np.float64, (3, 3))
        self.t = A.numeric(self.t, "Camera.t", np.float64, (2,))

    def project(self, points):
        """(N, 3) model points -> (N, 2) pixels."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3) @ self.r.T
        return np.stack([self.sx * p[:, 0] + self.t[0], -self.sy * p[:, 1] + self.t[1]], axis=1)

    def to_struct(self):
        c = B.skb_camera()
        c.sx, c.sy = self.sx, self.sy
        for i, v in enumerate(self.r.reshape(-1)):
            c.r[i] = v
        c.t[0], c.t[1] = self.t
        return c

    @classmethod
    def from_struct(cls, c):
        return cls(c.sx, c.sy, np.array(list(c.r)).reshape(3, 3), np.array(list(c.t)))


@dataclasses.dataclass
class PoseOptions(OptionsBase):
    """Options of estimate_pose / refine_pose (None: the library default; docs/c-api.md "3-D
    pose"). alpha_target: "level" or "identity"."""

    kappa: Optional[float] = None
    alpha: Optional[float] = None
    alpha_target: Optional[str] = None
    equal_scales: Optional[bool] = None
    max_bases: Optional[int] = None
    tolerance: Optional[float] = None
    refine: Optional[bool] = None
    prior: Optional[float] = None
    starts: Optional[int] = None
    limb_candidates: Optional[int] = None
    blend: Optional[float] = None
    joint_noise: Optional[float] = None
    proportions: Optional[bool] = None
    standing_prior: Optional[bool] = None
    knee_limits: Optional[bool] = None
    factor_prior: Optional[bool] = None
    depth_prior: Optional[float] = None
    straight_limbs: Optional[bool] = None

    _c_prefix = "skb_pose_options"
    _enums = {"alpha_target": {"level": B.SKB_ALPHA_TARGET_LEVEL, "identity": B.SKB_ALPHA_TARGET_IDENTITY}}


PROPORTION_GROUPS = ("head", "torso", "shoulders", "arms", "hips", "legs")


@dataclasses.dataclass
class Pose3D:
    """A 3-D pose and camera (skb_pose3d + skb_pose_figure): `joints` (15, 3) metres of a
    1.75 m person, model frame (+Y up); `camera`; `rms_px` reprojection RMS; `length_excess`;
    `prior_weight`; `bases` / `weights` the chosen dictionary bases; `proportions`
    {group: factor}; `plausible`."""

    joints: np.ndarray
    camera: Camera
    rms_px: float
    length_excess: float
    prior_weight: float
    bases: np.ndarray
    weights: np.ndarray
    proportions: dict
    plausible: bool
    raw: B.skb_pose3d = dataclasses.field(repr=False, default=None)

    @classmethod
    def from_struct(cls, s, fig=None):
        n = s.num_bases
        cam = Camera(s.sx, s.sy, np.array(list(s.r)).reshape(3, 3), np.array(list(s.t)))
        props = dict(zip(PROPORTION_GROUPS, list(fig.factors))) if fig is not None else {}
        raw = B.skb_pose3d.from_buffer_copy(s)
        return cls(np.ctypeslib.as_array(s.joints).copy(), cam, s.rms_px, s.length_excess, s.prior_weight,
                   np.array(list(s.bases)[:n], dtype=np.uint32), np.array(list(s.weights)[:n]),
                   props, bool(fig.plausible) if fig is not None else True, raw)


class PoseDictionary(Handle):
    """The basis-pose dictionary: the embedded default (`PoseDictionary()`) or a `.skbpd`
    file (`PoseDictionary(path)`). Immutable and thread-safe."""

    _free_fn = "skb_pose_dictionary_free"

    def __init__(self, path=None):
        if path is None:
            super().__init__(new_handle("skb_pose_dictionary_new_default", B.skb_pose_dictionary))
        else:
            super().__init__(new_handle("skb_pose_dictionary_new_from_file", B.skb_pose_dictionary, A.path_arg(path)))

    @property
    def num_bases(self):
        n = ctypes.c_size_t()
        call("skb_pose_dictionary_basis_count", self._p, ctypes.byref(n))
        return n.value

    def mean(self):
        """The mean pose, (15, 3) metres."""
        out = np.empty((15, 3), dtype=np.float64)
        call("skb_pose_dictionary_copy_mean", self._p, A.ptr(out), out.size)
        return out

    def basis(self, index):
        """(basis (15, 3) unit vector, its spread sigma in metres)."""
        out = np.empty((15, 3), dtype=np.float64)
        sigma = ctypes.c_double()
        call("skb_pose_dictionary_copy_basis", self._p, A.index(index, "index", 0, 2**32 - 1), A.ptr(out), out.size,
             ctypes.byref(sigma))
        return out, sigma.value

    def bone_lengths(self):
        """The 14 average bone lengths, metres."""
        out = np.empty(14, dtype=np.float64)
        call("skb_pose_dictionary_copy_bone_lengths", self._p, A.ptr(out), out.size)
        return out


_default_dict = None
_default_dict_lock = threading.Lock()


def _dict_arg(dictionary):
    global _default_dict
    if dictionary is None:
        with _default_dict_lock:
            if _default_dict is None:
                _default_dict = PoseDictionary()
            return _default_dict
    if not isinstance(dictionary, PoseDictionary):
        raise TypeError(f"dictionary must be a PoseDictionary or None, not {type(dictionary).__name__}")
    return dictionary


def estimate_pose(joints, options=None, dictionary=None):
    """The 3-D pose and camera of 15 2-D joints (Joints2D, joints JSON path, dict or (15, 2)
    array) with `options` (PoseOptions or None) and `dictionary` (None: the embedded one).
    Returns a Pose3D (with the drawn proportions and the plausibility flag)."""
    j = joints2d_arg(joints).to_struct()
    d = _dict_arg(dictionary)
    out, fig = B.skb_pose3d(), B.skb_pose_figure()
    with options_handle(options, PoseOptions) as h:
        call("skb_pose3d_estimate_figure", d._p, ctypes.byref(j), h, ctypes.byref(out), ctypes.byref(fig))
    return Pose3D.from_struct(out, fig)


def refine_pose(joints, start, options=None, dictionary=None):
    """The fixed-basis refinement alone (skb_pose3d_refine) from `start` (a Pose3D returned by
    estimate_pose, made with PoseOptions(proportions=False))."""
    if not isinstance(start, Pose3D) or start.raw is None:
        raise TypeError("start must be a Pose3D returned by estimate_pose")
    j = joints2d_arg(joints).to_struct()
    d = _dict_arg(dictionary)
    out = B.skb_pose3d()
    with options_handle(options, PoseOptions) as h:
        call("skb_pose3d_refine", d._p, ctypes.byref(j), h, ctypes.byref(start.raw), ctypes.byref(out))
    return Pose3D.from_struct(out)


LIMB_NAMES = ("r_upper_arm", "r_forearm", "l_upper_arm", "l_forearm", "r_thigh", "r_shin", "l_thigh", "l_shin")
"""The limb bones whose depth can be flipped, in SKB_LIMB_* order."""

REPOSE_OUTCOMES = {
    B.SKB_REPOSE_DONE: "done",
    B.SKB_REPOSE_NO_DEPTH: "no_depth",
    B.SKB_REPOSE_JOINT_OUTSIDE_IMAGE: "joint_outside_image",
    B.SKB_REPOSE_JOINTS_COINCIDE: "joints_coincide",
    B.SKB_REPOSE_IMPLAUSIBLE: "implausible",
}
"""Outcome names of flip_limb and the Result re-pose methods ("done", or what left it unchanged)."""


def limb_index(limb):
    """SKB_LIMB_* of a limb name (LIMB_NAMES) or index."""
    if isinstance(limb, str):
        if limb not in LIMB_NAMES:
            raise ValueError(f"unknown limb {limb!r}; expected one of {LIMB_NAMES}")
        return LIMB_NAMES.index(limb)
    return A.index(limb, "limb", 0, len(LIMB_NAMES) - 1)


@dataclasses.dataclass
class Alternative:
    """One depth reading of a pose: `joints` (15, 3) metres (the frame of Pose3D.joints),
    `score` (px², lower = better; docs/formats.md "3-D pose JSON"), `flipped` the limb names
    flipped relative to the current pose."""

    joints: np.ndarray
    score: float
    flipped: tuple


class PoseEstimate(Handle):
    """A 3-D pose estimate with its ranked depth readings (skb_pose_estimate): `pose` (Pose3D),
    `alternatives` (best first; [0] is the pose itself), flip_limb() and pick() change it in
    place. Made by estimate_pose_alternatives() or Result.pose_estimate()."""

    _free_fn = "skb_pose_estimate_free"

    @property
    def pose(self):
        out = B.skb_pose3d()
        call("skb_pose_estimate_pose", self._p, ctypes.byref(out))
        return Pose3D.from_struct(out)

    @property
    def alternatives(self):
        """The ranked alternatives (list of Alternative, at most 8)."""
        n = ctypes.c_size_t()
        call("skb_pose_estimate_alternative_count", self._p, ctypes.byref(n))
        out = []
        for i in range(n.value):
            j = np.empty((15, 3), dtype=np.float64)
            score = ctypes.c_double()
            call("skb_pose_estimate_copy_alternative_joints", self._p, i, A.ptr(j), j.size, ctypes.byref(score))
            count = ctypes.c_size_t()
            call("skb_pose_estimate_alternative_flipped_count", self._p, i, ctypes.byref(count))
            limbs = (ctypes.c_uint32 * max(count.value, 1))()
            call("skb_pose_estimate_copy_alternative_flipped", self._p, i, limbs, len(limbs))
            out.append(Alternative(j, score.value, tuple(LIMB_NAMES[limbs[k]] for k in range(count.value))))
        return out

    def flip_limb(self, limb):
        """Flips one limb's depth (a LIMB_NAMES name or index) in place; returns "done" or
        "no_depth" (the limb lies in the picture plane; nothing changed)."""
        o = ctypes.c_uint32()
        call("skb_pose_estimate_flip_limb", self._p, limb_index(limb), ctypes.byref(o))
        return REPOSE_OUTCOMES[o.value]

    def pick(self, index):
        """Makes alternative `index` the pose (in place)."""
        call("skb_pose_estimate_pick_alternative", self._p, A.index(index, "index", 0, 2**32 - 1))


def estimate_pose_alternatives(joints, options=None, dictionary=None):
    """estimate_pose as a PoseEstimate handle: the pose with its ranked depth readings
    (`.alternatives`) and flip_limb()."""
    j = joints2d_arg(joints).to_struct()
    d = _dict_arg(dictionary)
    with options_handle(options, PoseOptions) as h:
        return PoseEstimate(new_handle("skb_pose_estimate_new", B.skb_pose_estimate, d._p, ctypes.byref(j), h))

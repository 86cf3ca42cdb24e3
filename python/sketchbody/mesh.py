"""Body meshes (the MakeHuman shape model), posing, the 53-bone rig and export."""

import ctypes
import dataclasses
import threading
from typing import Optional

import numpy as np

from . import _arrays as A
from . import _bindings as B
from ._lib import Handle, call, new_handle
from ._options import OptionsBase, options_handle
from .context import default_context, gender_code, gender_name
from .images import load_rgb_image
from .pose import Camera


@dataclasses.dataclass
class ExportOptions(OptionsBase):
    """The rigged export's conventions (None: the defaults). naming: "project", "mixamo" or
    "unreal"; rest_pose: "a" or "t"; origin: "floor" or "pelvis"; for write_fbx and write_usd
    only (the GLB is always metres, Y up, as glTF specifies): units "m" or "cm", up_axis "y"
    (the body facing +Z) or "z" (the body facing -Y); twist_bones: True adds the 6 twist bones
    of the upper arms, forearms and thighs (default False: the 53 bones); pose_as: "action"
    (default: the rest is the A- or T-pose, the bones posed, a one-frame clip "pose"), "rest"
    (the pose is the rest pose, no clip) or "both" (the pose as rest plus a clip "a_pose" or
    "t_pose"); ik_targets: True adds the 7 non-deforming IK target bones at the hands and
    feet; shape_keys: True adds the mesh's shape dimensions as shape keys at 0 (one per shape
    weight, each one standard deviation of its component)."""

    naming: Optional[str] = None
    rest_pose: Optional[str] = None
    origin: Optional[str] = None
    units: Optional[str] = None
    up_axis: Optional[str] = None
    twist_bones: Optional[bool] = None
    pose_as: Optional[str] = None
    ik_targets: Optional[bool] = None
    shape_keys: Optional[bool] = None

    _c_prefix = "skb_export_options"
    _enums = {
        "naming": {"project": B.SKB_NAMING_PROJECT, "mixamo": B.SKB_NAMING_MIXAMO, "unreal": B.SKB_NAMING_UNREAL},
        "rest_pose": {"a": B.SKB_REST_A_POSE, "t": B.SKB_REST_T_POSE},
        "origin": {"floor": B.SKB_ORIGIN_FLOOR, "pelvis": B.SKB_ORIGIN_PELVIS},
        "units": {"m": B.SKB_UNITS_METRES, "cm": B.SKB_UNITS_CENTIMETRES},
        "up_axis": {"y": B.SKB_UP_Y, "z": B.SKB_UP_Z},
        "pose_as": {"action": B.SKB_POSE_AS_ACTION, "rest": B.SKB_POSE_AS_REST, "both": B.SKB_POSE_AS_BOTH},
    }


@dataclasses.dataclass
class Rig:
    """The rig of a mesh in one pose, as the GLB has it (all numpy copies; no handle): B bones,
    53 (MakeHuman's) then the 6 twist bones and the 7 IK targets when ExportOptions asks for them.

    bone_names: list of B str; parents: (B,) int32, -1 for the root, parents first;
    rest_translations (53, 3) and rest_rotations (53, 4) quaternions x, y, z, w: each bone's
    rest transform relative to its parent (the bind pose); local_rotations (53, 4): the posed
    rotation relative to the parent (what a DCC shows as pose-bone rotations);
    root_translation (3,): the root's translation in the pose; offset (3,): model frame ->
    export frame; posed_heads (53, 3); rest_vertices / posed_vertices (N, 3) float32;
    skin_bones (N, 4) uint32 (indices into the B bones) and skin_weights (N, 4) float32;
    shape_keys: {name: (N, 3) float32}, each key's displacement of the rest vertices at value 1
    (empty unless ExportOptions(shape_keys=True)).
    Rebuilding: G_b = G_parent . T(t_b) . R(q_b) (root: T(t_0 + root_translation) . R(q_0));
    bone b's posed head is G_b's translation."""

    bone_names: list
    parents: np.ndarray
    rest_translations: np.ndarray
    rest_rotations: np.ndarray
    local_rotations: np.ndarray
    root_translation: np.ndarray
    offset: np.ndarray
    posed_heads: np.ndarray
    rest_vertices: np.ndarray
    posed_vertices: np.ndarray
    skin_bones: np.ndarray
    skin_weights: np.ndarray
    shape_keys: dict

    def posed_global_transforms(self):
        """(B, 4, 4) posed bone-to-export-frame matrices rebuilt from the rest translations,
        the local rotations and the root translation (the C API's documented recipe)."""
        out = np.zeros((len(self.parents), 4, 4))
        for b, p in enumerate(self.parents):
            m = np.eye(4)
            m[:3, :3] = quat_to_matrix(self.local_rotations[b])
            m[:3, 3] = self.rest_translations[b] + (self.root_translation if p < 0 else 0)
            out[b] = m if p < 0 else out[p] @ m
        return out


def quat_to_matrix(q):
    """Rotation matrix of a unit quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


class Mesh(Handle):
    """A body mesh: a shape of one gender, rest pose (A-pose), metres, model frame (+Y up, +Z
    toward the viewer). Make one with Mesh.from_shape, Result.mesh() or fit_shape.
    Thread-safe in Python: calls on one Mesh object (pose() changes it, the rest read it, close()
    frees it) are serialised by an internal lock; different meshes run in parallel."""

    _free_fn = "skb_mesh_free"

    def __init__(self, ptr):
        self._lock = threading.RLock()
        super().__init__(ptr)

    def close(self):
        with self._lock:
            super().close()

    @classmethod
    def from_shape(cls, gender, weights=None, context=None):
        """The rest mesh of `gender` ("female"/"male") with PCA `weights` (metres; None or
        fewer than the components: the rest are 0, so None is the mean shape)."""
        ctx = context or default_context()
        w = A.vector(weights, "weights", np.float32)
        return cls(new_handle("skb_mesh_new_from_shape", B.skb_mesh, ctx._p, gender_code(gender, False),
                              A.ptr(w) if w.size else None, w.size))

    def _count(self, fn):
        n = ctypes.c_size_t()
        with self._lock:
            call(fn, self._p, ctypes.byref(n))
        return n.value

    def _copy(self, fn, shape, dtype, *extra):
        out = np.empty(shape, dtype=dtype)
        with self._lock:
            call(fn, self._p, *extra, A.ptr(out), out.size)
        return out

    @property
    def gender(self):
        """"female" or "male"."""
        g = ctypes.c_uint32()
        with self._lock:
            call("skb_mesh_gender", self._p, ctypes.byref(g))
        return gender_name(g.value)

    @property
    def vertex_count(self):
        return self._count("skb_mesh_vertex_count")

    @property
    def face_count(self):
        """Quad faces (the triangle count is twice that)."""
        return self._count("skb_mesh_face_count")

    def vertices(self, posed=False):
        """(N, 3) float32 vertices, metres: the rest pose, or the current pose (`posed`)."""
        fn = "skb_mesh_copy_posed_vertices" if posed else "skb_mesh_copy_vertices"
        return self._copy(fn, (self.vertex_count, 3), np.float32)

    def faces(self):
        """(F, 4) uint32 quads, counter-clockwise from outside (a triangle repeats its third
        index)."""
        return self._copy("skb_mesh_copy_faces", (self.face_count, 4), np.uint32)

    def triangles(self):
        """(2F, 3) uint32 triangles: (a, b, c), (a, c, d) per quad."""
        return self._copy("skb_mesh_copy_triangles", (2 * self.face_count, 3), np.uint32)

    def joints(self, posed=False):
        """(15, 3) float64 canonical joints, metres (rest or current pose)."""
        fn = "skb_mesh_copy_posed_joints" if posed else "skb_mesh_copy_joints"
        return self._copy(fn, (15, 3), np.float64)

    def skin_weights(self):
        """(bones (N, 4) uint32 in 0..13, weights (N, 4) float32 summing to 1) to the 14
        canonical bones."""
        n = self.vertex_count
        bones = np.empty((n, 4), dtype=np.uint32)
        weights = np.empty((n, 4), dtype=np.float32)
        with self._lock:
            call("skb_mesh_copy_skin_weights", self._p, A.ptr(bones), A.ptr(weights), bones.size)
        return bones, weights

    def shape_weights(self):
        """The PCA shape weights (metres) the mesh was made from."""
        return self._copy("skb_mesh_copy_shape_weights", (self._count("skb_mesh_shape_weight_count"),), np.float64)

    def uvs(self):
        """(U, 2) float32 UV coordinates (v up, as OBJ; glTF's v is 1 - v)."""
        return self._copy("skb_mesh_copy_uvs", (self._count("skb_mesh_uv_count"), 2), np.float32)

    def face_uvs(self):
        """(F, 4) uint32: per quad corner its index into uvs()."""
        return self._copy("skb_mesh_copy_face_uvs", (self.face_count, 4), np.uint32)

    def normals(self, posed=False):
        """(N, 3) float32 unit vertex normals of the rest or posed vertices."""
        return self._copy("skb_mesh_copy_normals", (self.vertex_count, 3), np.float32, bool(posed))

    def pose(self, joints, retarget=False, dual_quaternion=False):
        """Poses the mesh to 15 target joints ((15, 3) metres, model frame) by IK and
        skinning, replacing any earlier pose. The mesh is unchanged on error."""
        j = A.numeric(joints, "joints", np.float64, (15, 3))
        flags = (B.SKB_POSE_RETARGET if retarget else 0) | (B.SKB_POSE_DUAL_QUATERNION if dual_quaternion else 0)
        with self._lock:
            call("skb_mesh_pose", self._p, A.ptr(j), j.size, flags)

    def rasterize(self, camera, width, height):
        """The posed silhouette through `camera` as a (height, width) uint8 mask (255 inside)."""
        if not isinstance(camera, Camera):
            raise TypeError(f"camera must be a Camera, not {type(camera).__name__}")
        w, h = A.index(width, "width", 1, 4096), A.index(height, "height", 1, 4096)
        mask = np.empty((h, w), dtype=np.uint8)
        cam = camera.to_struct()
        with self._lock:
            call("skb_mesh_rasterize", self._p, None, ctypes.byref(cam), w, h, A.ptr(mask), w, mask.size)
        return mask

    def write_obj(self, path, posed=True):
        """Wavefront OBJ (normals, UVs, quads) of the posed or rest mesh, written atomically."""
        with self._lock:
            call("skb_mesh_write_obj", self._p, A.path_arg(path), bool(posed))

    def write_glb(self, path, options=None):
        """Binary glTF 2.0: the rest mesh skinned to the 53-bone rig, posed by bone rotations
        (ExportOptions or None for the defaults), written atomically."""
        with options_handle(options, ExportOptions) as h, self._lock:
            call("skb_mesh_write_glb", self._p, A.path_arg(path), h)

    def write_fbx(self, path, options=None):
        """Binary FBX 7.4 of the same rigged, posed body as write_glb, in the options' units and
        up axis (default metres, Y up), a plain skin colour; written atomically."""
        with options_handle(options, ExportOptions) as h, self._lock:
            call("skb_mesh_write_fbx", self._p, A.path_arg(path), h)

    def write_usd(self, path, options=None):
        """UsdSkel text layer (.usda) of the same rigged, posed body as write_glb, in the
        options' units and up axis (metersPerUnit, upAxis); written atomically."""
        with options_handle(options, ExportOptions) as h, self._lock:
            call("skb_mesh_write_usd", self._p, A.path_arg(path), h)

    def texture(self, sketch, camera, size=1024):
        """The sketch projected through `camera` (a Camera: model metres -> sketch pixels) onto
        the mesh in its current pose, as a (size, size, 3) uint8 RGB texture in the UV layout
        (row 0 is v = 1); texels the sketch does not see are grey (190, 190, 190). `sketch`: a
        numpy image or a PNG/JPEG path (decoded in colour). With result.mesh() and
        result.camera() this is Result.texture."""
        if A.is_path(sketch):
            sketch = load_rgb_image(sketch)
        view, keep = A.image(sketch, "sketch")
        n = A.index(size, "size", 1, 4096)
        out = np.empty((n, n, 3), dtype=np.uint8)
        cam = camera.to_struct()
        with self._lock:
            call("skb_mesh_project_texture", self._p, ctypes.byref(view), ctypes.byref(cam), n, A.ptr(out),
                 3 * n, out.size, None, None)
        del keep
        return out

    def write_preview(self, path, size=512):
        """A front + side preview PNG, `size` px square each, written atomically."""
        with self._lock:
            call("skb_mesh_write_preview", self._p, A.path_arg(path), A.index(size, "size", 1, 4096))

    def rig(self, options=None):
        """The Rig of the mesh in its current pose with ExportOptions `options`."""
        with options_handle(options, ExportOptions) as h, self._lock:
            r = new_handle("skb_rig_new_from_mesh", B.skb_rig, self._p, h)
        with _RigHandle(r) as rh:
            return rh.snapshot()


class _RigHandle(Handle):
    _free_fn = "skb_rig_free"

    def _copy(self, fn, shape, dtype):
        out = np.empty(shape, dtype=dtype)
        call(fn, self._p, A.ptr(out), out.size)
        return out

    def snapshot(self):
        nb, nv = ctypes.c_size_t(), ctypes.c_size_t()
        call("skb_rig_bone_count", self._p, ctypes.byref(nb))
        call("skb_rig_vertex_count", self._p, ctypes.byref(nv))
        nb, nv = nb.value, nv.value
        names = []
        buf = ctypes.create_string_buffer(256)
        for b in range(nb):
            call("skb_rig_copy_bone_name", self._p, b, buf, len(buf))
            names.append(buf.value.decode("utf-8"))
        rest = self._copy("skb_rig_copy_rest_transforms", (nb, B.SKB_RIG_TRANSFORM_LEN), np.float64)
        bones = np.empty((nv, 4), dtype=np.uint32)
        weights = np.empty((nv, 4), dtype=np.float32)
        call("skb_rig_copy_skin_weights", self._p, A.ptr(bones), A.ptr(weights), bones.size)
        nk = ctypes.c_size_t()
        call("skb_rig_shape_key_count", self._p, ctypes.byref(nk))
        keys = {}
        for k in range(nk.value):
            d = np.empty((nv, 3), dtype=np.float32)
            call("skb_rig_copy_shape_key", self._p, k, A.ptr(d), d.size)
            keys[f"shape_{k + 1:02d}"] = d
        return Rig(
            bone_names=names,
            parents=self._copy("skb_rig_copy_parents", (nb,), np.int32),
            rest_translations=rest[:, :3].copy(),
            rest_rotations=rest[:, 3:].copy(),
            local_rotations=self._copy("skb_rig_copy_local_rotations", (nb, 4), np.float64),
            root_translation=self._copy("skb_rig_copy_root_translation", (3,), np.float64),
            offset=self._copy("skb_rig_copy_offset", (3,), np.float64),
            posed_heads=self._copy("skb_rig_copy_posed_heads", (nb, 3), np.float64),
            rest_vertices=self._copy("skb_rig_copy_rest_vertices", (nv, 3), np.float32),
            posed_vertices=self._copy("skb_rig_copy_posed_vertices", (nv, 3), np.float32),
            skin_bones=bones,
            skin_weights=weights,
            shape_keys=keys,
        )

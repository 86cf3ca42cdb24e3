"""sketchbody: a concept sketch of a human character -> a rigged 3-D body (Python bindings).

    import sketchbody as skb
    with skb.run_pipeline("sketch.png", joints="sketch_joints.json") as result:
        vertices = result.vertices()            # (13380, 3) float32, metres, posed
        quads = result.faces()                  # (13378, 4) uint32
        with result.mesh() as mesh:
            rig = mesh.rig()                    # 53 bones: names, parents, rest, pose
            mesh.write_glb("body.glb")

Arrays come out as numpy arrays (copies the caller owns). Errors raise SketchbodyError
(`.status`, `.status_name`, `.message`); Cancelled and NoFigure are its subclasses.
Handles (Context, Result, Mesh, PoseDictionary, Detector) free their C object on close(), at
the end of a `with` block or when garbage-collected. See python/README.md.

The raw ctypes declarations of every skb_* function (generated from include/sketchbody.h) are
in sketchbody._bindings; the loaded CDLL is sketchbody.lib.
"""

from . import _bindings
from ._lib import (LIBRARY_PATH, Cancelled, LibraryNotFoundError, NoFigure, SketchbodyError, Status, lib,
                   status_text)
from .context import AUTO, FEMALE, MALE, Context, default_context
from .detect import Detection, DetectOptions, Detector, Facing, FigureInfo, detect
from .images import canny, gaussian_blur, load_image, load_rgb_image, render_sketch, write_png
from .mesh import ExportOptions, Mesh, Rig, quat_to_matrix
from .pipeline import VIEW_LABELS, FitOptions, Result, View, ViewInfo, fit_shape, run_pipeline
from .pose import (JOINT_NAMES, LIMB_NAMES, PROPORTION_GROUPS, Alternative, Camera, Joints2D, Pose3D,
                   PoseDictionary, PoseEstimate, PoseOptions, estimate_pose, estimate_pose_alternatives, refine_pose)

__version__ = _bindings.SKB_VERSION_STRING

NUM_JOINTS = _bindings.SKB_NUM_JOINTS
NUM_RIG_BONES = _bindings.SKB_NUM_RIG_BONES


def version():
    """The loaded library's version, "MAJOR.MINOR.PATCH"."""
    return lib.skb_version().decode()


def library_path():
    """The path (or loader name) of the libsketchbody in use."""
    return LIBRARY_PATH


__all__ = [
    "AUTO", "FEMALE", "MALE", "JOINT_NAMES", "LIMB_NAMES", "NUM_JOINTS", "NUM_RIG_BONES", "PROPORTION_GROUPS",
    "Alternative", "Camera", "Cancelled", "Context", "Detection", "DetectOptions", "Detector", "ExportOptions", "Facing",
    "FigureInfo", "FitOptions",
    "Joints2D", "LibraryNotFoundError", "Mesh", "NoFigure", "Pose3D", "PoseDictionary", "PoseEstimate", "PoseOptions", "Result",
    "Rig", "SketchbodyError", "Status", "canny", "default_context", "detect", "estimate_pose", "estimate_pose_alternatives", "fit_shape",
    "gaussian_blur", "library_path", "load_image", "load_rgb_image", "quat_to_matrix", "refine_pose",
    "render_sketch", "run_pipeline", "status_text", "version", "write_png", "VIEW_LABELS", "View", "ViewInfo",
]

"""Sketchbody for Blender: a concept sketch to a rigged 3-D body, with the paper's one user step
(correcting the 2-D joints) done on the sketch inside Blender.

The add-on is a thin layer over the `sketchbody` Python package (python/ in the sketchbody
checkout): the package runs the pipeline and hands out numpy arrays; build.py turns them into
Blender objects. See integrations/blender/README.md.
"""

bl_info = {
    "name": "Sketchbody",
    "author": "sketchbody authors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Sketchbody",
    "description": "Concept sketch to a rigged, posed 3-D body (53-bone rig); correct the 2-D joints on the sketch",
    "doc_url": "https://github.com/sketchbody/sketchbody/tree/main/integrations/blender",
    "category": "Import-Export",
}

import os  # noqa: E402
import time  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from bpy.props import EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty  # noqa: E402

from . import build, package  # noqa: E402

ADDON = __name__


# ---------------------------------------------------------------------------------------------
# preferences and settings


def _forget_package(self, context):
    package.forget()


class SketchbodyPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON

    python_path: StringProperty(
        name="Python package folder",
        description="Folder holding the sketchbody Python package (the checkout's python/ folder). Empty: "
                    "SKETCHBODY_PYTHON_PATH, the checkout this add-on runs from, or a pip-installed package",
        subtype="DIR_PATH", default="", update=_forget_package)

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "python_path")
        try:
            skb = package.load(self.python_path)
            layout.label(text=f"sketchbody {skb.version()} ({skb.library_path()})", icon="CHECKMARK")
        except package.PackageError as e:
            box = layout.box()
            box.label(text="sketchbody package not loaded:", icon="ERROR")
            for line in _wrap(str(e), 100):
                box.label(text=line)


def _wrap(text, width):
    words, lines, cur = text.split(), [], ""
    for w in words:
        if len(cur) + len(w) + 1 > width and cur:
            lines.append(cur)
            cur = w
        else:
            cur = f"{cur} {w}".strip()
    return lines + ([cur] if cur else [])


def _preference_path(context):
    addon = context.preferences.addons.get(ADDON)
    return addon.preferences.python_path if addon and addon.preferences else ""


def _threshold_changed(self, context):
    plane = build.find_plane()
    if plane is not None:
        for m in build.find_markers(plane):
            build.highlight(m, self.threshold)


class SketchbodySettings(bpy.types.PropertyGroup):
    image: StringProperty(name="Sketch", description="The concept sketch (PNG or JPEG)", subtype="FILE_PATH")
    joints: StringProperty(
        name="Joints", subtype="FILE_PATH",
        description="Optional sketchbody-joints2d JSON file with the 15 2-D joints; empty: the embedded detector")
    gender: EnumProperty(
        name="Gender", default="AUTO",
        items=[("AUTO", "Auto", "Fit gender as a continuous shape weight"),
               ("FEMALE", "Female", "Fit the female body model"), ("MALE", "Male", "Fit the male body model")])
    height: FloatProperty(
        name="Height", description="The character's height (0: unknown, the fit decides)", default=0.0, min=0.0,
        max=10.0, soft_max=2.5, unit="LENGTH", precision=3)
    rest_pose: EnumProperty(
        name="Rest pose", default="A",
        items=[("A", "A-pose", "Bind the armature in MakeHuman's A-pose"),
               ("T", "T-pose", "Bind the armature in a T-pose")])
    naming: EnumProperty(
        name="Bone names", default="PROJECT",
        items=[("PROJECT", "Project", "sketchbody's names (r_elbow, ...)"), ("MIXAMO", "Mixamo", "Mixamo names"),
               ("UNREAL", "Unreal", "Unreal Engine mannequin names")])
    samples: IntProperty(name="Samples", description="Fit samples per iteration (quality vs time)", default=200,
                         min=10, max=2000)
    iterations: IntProperty(name="Iterations", description="Fit iterations at most", default=8, min=1, max=50)
    threshold: FloatProperty(
        name="Low confidence", default=0.75, min=0.0, max=1.0, update=_threshold_changed,
        description="Detected joints whose confidence (the detector's calibrated probability that the joint is "
                    "right) is below this are highlighted (red, larger); 0.75 is the library's low-confidence level")


def _settings(context):
    return context.scene.sketchbody


# ---------------------------------------------------------------------------------------------
# running the package


class UserError(Exception):
    """A problem the user can fix; its text goes to the report as it is."""


def _abspath(path):
    return os.path.normpath(bpy.path.abspath(path)) if path else ""


def _fit_options(skb, st):
    return skb.FitOptions(gender=st.gender.lower(), height=st.height if st.height > 0 else None,
                          samples=st.samples, iterations=st.iterations)


def _read_joints_file(skb, path):
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


def _run(skb, context, image_path, joints, rig_options):
    """Runs the pipeline; returns the arrays build.py needs (nothing in the scene changes here)."""
    st = _settings(context)
    wm = context.window_manager
    wm.progress_begin(0, 100)
    try:
        with skb.run_pipeline(image_path, joints=joints, fit_options=_fit_options(skb, st),
                              progress=lambda f: wm.progress_update(int(100 * f)) or True) as result:
            camera = result.camera()
            pixels = camera.project(result.vertices(posed=True))
            gender, (gender_value, _) = result.gender, result.gender_value()
            low_evidence, support = result.evidence()
            with result.mesh() as mesh:
                rig = mesh.rig(rig_options)
                data = dict(rig=rig, quads=mesh.faces(), uvs=mesh.uvs(), face_uvs=mesh.face_uvs())
                # How squarely the sketch's camera sees each vertex: the posed normal's component
                # toward the viewer (+Z of the camera frame), full from 0.2 on, none when facing away.
                toward_viewer = (mesh.normals(posed=True) @ camera.r.T)[:, 2]
                data["seen"] = np.clip(toward_viewer / 0.2, 0.0, 1.0)
    finally:
        wm.progress_end()
    sketch = skb.load_image(image_path)
    h, w = sketch.shape[:2]
    data.update(
        camera=camera, pixels=pixels, width=w, height=h, gender=gender, gender_value=gender_value,
        low_evidence=low_evidence, edge_support=support,
        sketch_uv=np.stack([pixels[:, 0] / w, 1.0 - pixels[:, 1] / h], axis=1))
    return data


def _rig_options(skb, st):
    return skb.ExportOptions(naming=st.naming.lower(), rest_pose=st.rest_pose.lower(), origin="floor")


def _summary(data, seconds):
    low = " (low evidence: few strokes near the outline)" if data["low_evidence"] else ""
    return (f"Sketchbody: {data['gender']} body (gender value {data['gender_value']:.2f}), "
            f"{len(data['rig'].rest_vertices)} vertices, {len(data['rig'].bone_names)} bones, "
            f"edge support {data['edge_support']:.2f}{low}, {seconds:.1f} s")


def _object_mode(context):
    if context.object is not None and context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")


class _Reporting:
    """execute() wrapper: every failure becomes one error report, never a traceback."""

    def execute(self, context):
        try:
            return self.run(context)
        except package.PackageError as e:
            self.report({"ERROR"}, str(e))
        except UserError as e:
            self.report({"ERROR"}, str(e))
        except Exception as e:  # the package's SketchbodyError and anything unexpected
            name = getattr(e, "status_name", type(e).__name__)
            self.report({"ERROR"}, f"Sketchbody failed: {getattr(e, 'message', str(e))} ({name})")
        return {"CANCELLED"}


class SKETCHBODY_OT_sketch_to_body(_Reporting, bpy.types.Operator):
    """Detect the 15 joints (or read them from the joints file), fit a rigged 3-D body to the
    sketch and show the sketch with draggable joint markers beside it"""

    bl_idname = "sketchbody.sketch_to_body"
    bl_label = "Sketch to body"
    bl_options = {"REGISTER", "UNDO"}

    def run(self, context):
        t0 = time.perf_counter()
        st = _settings(context)
        image_path = _abspath(st.image)
        if not image_path:
            raise UserError("Choose a sketch image first")
        if not os.path.isfile(image_path):
            raise UserError(f"Sketch image not found: {image_path}")
        skb = package.load(_preference_path(context))
        if st.joints:
            joints, confidence = _read_joints_file(skb, _abspath(st.joints))
        else:
            try:
                det = skb.detect(image_path)
            except skb.NoFigure as e:
                raise UserError(
                    f"The detector found no figure in the sketch (score {e.score:.2f}); give a joints file "
                    "(sketchbody-joints2d JSON) and correct the joints on the sketch")
            except skb.SketchbodyError as e:
                raise UserError(f"Joint detection failed: {e.message} ({e.status_name}); give a joints file "
                                "(sketchbody-joints2d JSON) instead")
            joints, confidence = det.joints, np.asarray(det.confidence, dtype=np.float64)
        data = _run(skb, context, image_path, joints, _rig_options(skb, st))
        try:
            image = build.load_image(image_path)
        except RuntimeError as e:
            raise UserError(f"Blender cannot load the sketch {image_path}: {e}")

        # Everything computed: only now change the scene.
        _object_mode(context)
        build.clear(context.scene)
        try:
            px_floor = float(data["pixels"][:, 1].max())
            body_min_x = float(np.min(data["rig"].posed_vertices[:, 0]))
            # The sketch at the body's scale: the projected body's height in pixels = its height in metres.
            px_height = float(np.ptp(data["pixels"][:, 1]))
            body_height = float(np.ptp(data["rig"].posed_vertices[:, 1]))
            scale = body_height / px_height if px_height > 1.0 else 1.0 / data["camera"].sy
            plane = build.make_sketch_plane(context.scene, image, scale, px_floor, body_min_x)
            markers = build.make_markers(context.scene, plane, skb.JOINT_NAMES, joints.xy, confidence,
                                         joints.visible, st.threshold)
            build.build_body(context.scene, data["rig"], data["quads"], data["uvs"], data["face_uvs"],
                             data["sketch_uv"], data["seen"], image)
        except Exception:
            build.clear(context.scene)  # nothing half-built stays in the scene
            raise
        low = [m["skb_joint"] for m in markers if m["skb_low_confidence"]]
        self.report({"INFO"}, _summary(data, time.perf_counter() - t0)
                    + (f"; check the red joints: {', '.join(low)}" if low else ""))
        return {"FINISHED"}


class SKETCHBODY_OT_rerun(_Reporting, bpy.types.Operator):
    """Fit the body again from the joint markers' current positions on the sketch (move them
    with G first: the paper's user-correction step)"""

    bl_idname = "sketchbody.rerun"
    bl_label = "Re-run from corrected joints"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return build.find_plane() is not None

    def run(self, context):
        t0 = time.perf_counter()
        st = _settings(context)
        plane = build.find_plane()
        if plane is None or "skb_image" not in plane:
            raise UserError("No sketch in the scene: run 'Sketch to body' first")
        image_path = _abspath(plane["skb_image"])
        if not os.path.isfile(image_path):
            raise UserError(f"Sketch image not found: {image_path}")
        skb = package.load(_preference_path(context))
        try:
            xy, visible = build.read_markers(plane, skb.JOINT_NAMES)
        except ValueError as e:
            raise UserError(str(e))
        w, h = plane["skb_width"], plane["skb_height"]
        outside = [n for n, (x, y), v in zip(skb.JOINT_NAMES, xy, visible) if v and not (0 <= x <= w and 0 <= y <= h)]
        if outside:
            raise UserError(f"Joint markers outside the sketch: {', '.join(outside)}; move them back onto it")
        joints = skb.Joints2D(xy, visible)
        data = _run(skb, context, image_path, joints, _rig_options(skb, st))
        image = build.load_image(image_path)
        _object_mode(context)
        build.remove_body()
        try:
            build.build_body(context.scene, data["rig"], data["quads"], data["uvs"], data["face_uvs"],
                             data["sketch_uv"], data["seen"], image)
        except Exception:
            build.remove_body()
            raise
        for m in build.find_markers(plane):
            m["skb_visible"] = bool(visible[m["skb_index"]])
            build.highlight(m, st.threshold)
        self.report({"INFO"}, _summary(data, time.perf_counter() - t0))
        return {"FINISHED"}


class SKETCHBODY_OT_clear(_Reporting, bpy.types.Operator):
    """Remove the body, the sketch plane and the joint markers"""

    bl_idname = "sketchbody.clear"
    bl_label = "Clear"
    bl_options = {"REGISTER", "UNDO"}

    def run(self, context):
        _object_mode(context)
        build.clear(context.scene)
        return {"FINISHED"}


class SKETCHBODY_OT_save_joints(_Reporting, bpy.types.Operator):
    """Save the joint markers' positions as a sketchbody-joints2d JSON file (for `sketchbody run --joints`)"""

    bl_idname = "sketchbody.save_joints"
    bl_label = "Save joints"

    filepath: StringProperty(subtype="FILE_PATH", default="joints2d.json")
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    @classmethod
    def poll(cls, context):
        return build.find_plane() is not None

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def run(self, context):
        skb = package.load(_preference_path(context))
        try:
            xy, visible = build.read_markers(build.find_plane(), skb.JOINT_NAMES)
        except ValueError as e:
            raise UserError(str(e))
        skb.Joints2D(xy, visible).to_json(self.filepath)
        self.report({"INFO"}, f"Saved the joints to {self.filepath}")
        return {"FINISHED"}


# ---------------------------------------------------------------------------------------------
# the panel


class SKETCHBODY_PT_panel(bpy.types.Panel):
    bl_label = "Sketchbody"
    bl_idname = "SKETCHBODY_PT_panel"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Sketchbody"

    def draw(self, context):
        st = _settings(context)
        layout = self.layout
        col = layout.column(align=True)
        col.prop(st, "image")
        col.prop(st, "joints")
        col = layout.column()
        col.prop(st, "gender")
        col.prop(st, "height")
        col.prop(st, "rest_pose")
        col.prop(st, "naming")
        row = layout.row(align=True)
        row.prop(st, "samples")
        row.prop(st, "iterations")
        layout.operator(SKETCHBODY_OT_sketch_to_body.bl_idname, icon="OUTLINER_OB_ARMATURE")
        plane = build.find_plane()
        box = layout.box()
        box.label(text="Correct the joints", icon="EMPTY_AXIS")
        if plane is None:
            box.label(text="Run 'Sketch to body' first")
        else:
            low = [m["skb_joint"] for m in build.find_markers(plane) if m.get("skb_low_confidence")]
            box.label(text="Select a marker on the sketch, move it with G")
            if low:
                box.label(text=f"Red: low confidence ({len(low)})", icon="ERROR")
            box.label(text="Orange: moved (used by the last re-run)")
            box.prop(st, "threshold")
        box.operator(SKETCHBODY_OT_rerun.bl_idname, icon="FILE_REFRESH")
        box.operator(SKETCHBODY_OT_save_joints.bl_idname, icon="EXPORT")
        layout.operator(SKETCHBODY_OT_clear.bl_idname, icon="TRASH")


CLASSES = (SketchbodyPreferences, SketchbodySettings, SKETCHBODY_OT_sketch_to_body, SKETCHBODY_OT_rerun,
           SKETCHBODY_OT_clear, SKETCHBODY_OT_save_joints, SKETCHBODY_PT_panel)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.sketchbody = PointerProperty(type=SketchbodySettings)


def unregister():
    del bpy.types.Scene.sketchbody
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

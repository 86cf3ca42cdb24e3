"""Sketchbody for Blender: a concept sketch to a rigged 3-D body, with the paper's one user step
(correcting the 2-D joints) done on the sketch inside Blender.

The add-on is a thin layer over the `sketchbody` Python package (python/ in the sketchbody
checkout): the package runs the pipeline and hands out numpy arrays; build.py turns them into
Blender objects. See integrations/blender/README.md.
"""

bl_info = {
    "name": "Sketchbody",
    "author": "sketchbody authors",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Sketchbody",
    "description": "Concept sketch to a rigged, posed 3-D body (53-bone rig); correct the 2-D joints on the sketch",
    "doc_url": "https://github.com/sketchbody/sketchbody/tree/main/integrations/blender",
    "category": "Import-Export",
}

import contextlib  # noqa: E402
import dataclasses  # noqa: E402
import functools  # noqa: E402
import os  # noqa: E402
import time  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty,  # noqa: E402
                       StringProperty)

from . import build, gltf_compat, jobs, package, work  # noqa: E402

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
    side_image: StringProperty(
        name="Side view", subtype="FILE_PATH",
        description="Optional: the same character in the same pose seen from the side (a turnaround sheet's side "
                    "view, PNG or JPEG); its joints are detected. One body and one pose are fitted to every view")
    side_faces: EnumProperty(
        name="Side faces", default="RIGHT",
        items=[("RIGHT", "Image right", "The character's right side: it faces image right (turned +90°)"),
               ("LEFT", "Image left", "The character's left side: it faces image left (turned -90°)")])
    back_image: StringProperty(
        name="Back view", subtype="FILE_PATH",
        description="Optional: the same character in the same pose seen from behind; its joints are detected")
    gender: EnumProperty(
        name="Gender", default="AUTO",
        items=[("AUTO", "Auto", "The library decides the gender (as the CLI without --gender)"),
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
    progress: FloatProperty(name="Progress", subtype="FACTOR", min=0.0, max=1.0, get=lambda self: running_fraction(),
                            description="The running fit's fraction done (read-only)")
    live_repose: BoolProperty(
        name="Live re-pose", default=True,
        description="While a joint marker is moved, re-pose the body to it at once (3-D pose, IK and skinning; "
                    "the shape is kept: 'Re-run from corrected joints' re-fits it)")
    status: StringProperty(name="Last run", description="What the last run reported")
    status_level: StringProperty(name="Last run's level", default="INFO",
                                 description="INFO, WARNING, ERROR or RUNNING")


def _settings(context):
    """The scene's Sketchbody settings (the panel's)."""
    return context.scene.sketchbody


# ---------------------------------------------------------------------------------------------
# running the package in the background


UserError = work.UserError
POLL_SECONDS = 0.1  # how often the timer looks at a running job


@dataclasses.dataclass
class _Active:
    """The one run in progress: its job, request, package module and start time."""

    job: jobs.Job
    req: work.Request
    skb: object
    t0: float


_active = None


@dataclasses.dataclass
class _Live:
    """The current body's library result, kept open to re-pose the body without re-fitting its
    shape (flip_limb, the live re-pose): the result, the package module, the pose dictionary, the
    armature's and body's names, the rig options and sketch size it was built with, and the
    marker pixels it was last posed to."""

    result: object
    skb: object
    dictionary: object
    armature: str
    body: str
    rig_options: object
    width: int
    height: int
    xy: np.ndarray


_live = None
LIVE_SECONDS = 0.05  # how often the live re-pose looks at the markers
LIMB_LABELS = {"r_upper_arm": "R upper arm", "r_forearm": "R forearm", "l_upper_arm": "L upper arm",
               "l_forearm": "L forearm", "r_thigh": "R thigh", "r_shin": "R shin", "l_thigh": "L thigh",
               "l_shin": "L shin"}


def _set_live(live):
    """Makes `live` (or None) the re-posable body, closing the former one's result."""
    global _live
    old, _live = _live, live
    if old is not None and (live is None or old.result is not live.result):
        old.result.close()


def live_body():
    """(armature, body) of the re-posable body, or None when there is none (no run, Clear, the
    objects removed or replaced)."""
    if _live is None:
        return None
    arm = bpy.data.objects.get(_live.armature)
    if arm is None or not arm.get(build.CURRENT):
        return None
    return arm, bpy.data.objects.get(_live.body)


def _repose_scene(seconds_since):
    """Puts the kept result's current pose onto its body (work.posed_data, build.apply_pose);
    returns the milliseconds since `seconds_since` (perf_counter)."""
    arm, body = live_body()
    with _live.result.mesh() as mesh:
        data = work.posed_data(_live.result, mesh, _live.rig_options, _live.width, _live.height)
    build.apply_pose(arm, body, data["rig"], data["sketch_uv"], data["seen"])
    return 1e3 * (time.perf_counter() - seconds_since)


def live_update():
    """The live re-pose (a bpy.app.timers callback; scripts may call it): when a joint marker of
    the re-posable body has moved since the body was last posed, re-poses the body to the
    markers at once (3-D pose, IK, skinning; the shape kept). A marker outside the sketch, on
    another, or joints no body explains leave the body as it was and say so in the panel.
    Returns the outcome ("done", the library's other outcomes, or None when nothing moved)."""
    ctx = bpy.context
    if _live is None or is_running() or live_body() is None or ctx.scene is None:
        return None
    st = _settings(ctx)
    plane = build.find_plane()
    if not st.live_repose or plane is None:
        return None
    try:
        xy, visible = build.read_markers(plane, _live.skb.JOINT_NAMES)
    except ValueError:
        return None
    if np.allclose(xy, _live.xy, atol=0.01):
        return None
    t = time.perf_counter()
    outcome = _live.result.repose(_live.skb.Joints2D(xy, visible), dictionary=_live.dictionary)
    _live.xy = xy
    if outcome == "done":
        ms = _repose_scene(t)
        _set_status(ctx.scene, "INFO", f"Sketchbody: re-posed to the markers in {ms:.0f} ms (shape kept; "
                                       "'Re-run from corrected joints' re-fits it)")
    else:
        why = {"joint_outside_image": "a joint marker is outside the sketch",
               "joints_coincide": "two joint markers lie on each other",
               "implausible": "no plausible body explains the markers"}[outcome]
        _set_status(ctx.scene, "WARNING", f"Sketchbody: {why}; the body keeps its last pose")
    _redraw()
    return outcome


def _live_tick():
    """The timer around live_update (never raises: a timer that raises is dropped)."""
    try:
        live_update()
    except Exception as e:  # noqa: BLE001 - reported in the panel
        _set_status(bpy.context.scene, "ERROR", f"Sketchbody: live re-pose failed: {e}")
    return LIVE_SECONDS


def is_running():
    """True while a run works in the background (the start buttons are then disabled)."""
    return _active is not None


def running_fraction():
    """The running job's fraction done (0..1), 0 when none runs."""
    return _active.job.fraction if _active is not None else 0.0


def _abspath(path):
    """An absolute, normalised path of a Blender path (// relative to the .blend); "" stays ""."""
    return os.path.normpath(bpy.path.abspath(path)) if path else ""


def _fit_options(skb, st):
    """The package's FitOptions from the panel's settings."""
    return skb.FitOptions(gender=st.gender.lower(), height=st.height if st.height > 0 else None,
                          samples=st.samples, iterations=st.iterations)


def _views(skb, st):
    """The turnaround's extra views from the settings: [(label, absolute path)], each checked."""
    views = []
    for label, path in (("side" if st.side_faces == "RIGHT" else "side_left", st.side_image), ("back", st.back_image)):
        if path:
            full = _abspath(path)
            work.check_image(skb, full, what=f"{label.replace('_', ' ')} view")
            views.append((label, full))
    return views


def _rig_options(skb, st):
    """The package's ExportOptions (names, rest pose; origin on the floor) from the settings."""
    return skb.ExportOptions(naming=st.naming.lower(), rest_pose=st.rest_pose.lower(), origin="floor")


def _summary(req, data, seconds, kept):
    """The report of a finished run."""
    low = " (low evidence: few strokes near the outline)" if data["low_evidence"] else ""
    source = "detected joints" if req.joints is None else "given joints"
    text = (f"Sketchbody: {data['gender']} body, {data['body_height']:.2f} m (gender value "
            f"{data['gender_value']:.2f}), from {source}, {len(data['rig'].rest_vertices)} vertices, "
            f"{len(data['rig'].bone_names)} bones, edge support {data['edge_support']:.2f}{low}, {seconds:.1f} s")
    if data.get("views"):
        parts = [f"{v.label.replace('_', ' ')} ({100 * v.residual:.0f}% off the shared pose)" for v in data["views"]]
        text += "; views: front + " + ", ".join(parts)
        for w in data.get("view_warnings", []):
            text += f"; warning: {w}"
    if kept:
        text += f"; the former body is kept as {kept}"
    return text


def _object_mode(context):
    """Leaves edit or pose mode (the add-on builds and removes objects in object mode)."""
    if context.object is not None and context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")


def _main_context():
    """A context for building the scene: the script's own, or, from a timer (which has no
    window), the first window's, which operators such as mode_set need."""
    wm = bpy.context.window_manager
    if bpy.context.window is None and wm is not None and len(wm.windows) > 0:
        win = wm.windows[0]
        return bpy.context.temp_override(window=win, screen=win.screen)
    return contextlib.nullcontext()


def _redraw():
    """Redraws the 3-D views (their sidebar shows the progress and the last report)."""
    wm = bpy.context.window_manager
    for win in (wm.windows if wm is not None else []):
        for area in win.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


def _cursor_progress(fraction=None):
    """Blender's progress cursor: begun with 0, updated, ended with None (no-op without a window)."""
    wm = bpy.context.window_manager
    try:
        if fraction is None:
            wm.progress_end()
        elif fraction == 0:
            wm.progress_begin(0, 100)
        else:
            wm.progress_update(int(100 * fraction))
    except (RuntimeError, AttributeError):
        pass


def _start(op, context, skb, req):
    """Starts `req` on a worker thread. With the operator's `wait` the call returns when the
    body is built (scripts); otherwise at once, a timer polling the job (Blender stays usable;
    the panel shows the progress and a Cancel button)."""
    global _active
    _active = _Active(jobs.Job(functools.partial(work.compute, skb, req), req.label).start(), req, skb,
                      time.perf_counter())
    _set_status(context.scene, "RUNNING", f"{req.label}: running")
    _cursor_progress(0)
    if op.wait:
        _active.job.wait()
        level, text = _finish()
        op.report({level}, text)
        return {"FINISHED"} if level == "INFO" else {"CANCELLED"}
    if not bpy.app.timers.is_registered(_tick):  # (under blender -b a former one may linger)
        bpy.app.timers.register(_tick, first_interval=POLL_SECONDS)
    op.report({"INFO"}, f"Sketchbody: {req.label} runs in the background (Cancel in the Sketchbody panel)")
    return {"FINISHED"}


def _tick():
    """The bpy.app.timers callback: shows the running job's progress; once it is done builds
    the scene on the main thread (_finish) and stops."""
    if _active is None:
        return None
    if not _active.job.done:
        _cursor_progress(max(_active.job.fraction, 0.01))
        _redraw()
        return POLL_SECONDS
    level, text = _finish()
    print(text, flush=True)
    return None


def wait_for_job(timeout=None):
    """For scripts under `blender -b`, where timers do not run: polls the running job as the
    timer does until it has finished and its result is in the scene. Returns the scene's
    status afterwards as (level, text); (None, "") when nothing ran."""
    deadline = None if timeout is None else time.perf_counter() + timeout
    if _active is None:
        return None, ""
    while _tick() is not None:
        if deadline is not None and time.perf_counter() > deadline:
            raise TimeoutError(f"the Sketchbody run did not finish within {timeout} s")
        time.sleep(0.02)
    st = _settings(bpy.context)
    return st.status_level, st.status


def _set_status(scene, level, text):
    """The panel's report line: `level` INFO, WARNING, ERROR or RUNNING."""
    if scene is not None and hasattr(scene, "sketchbody"):
        scene.sketchbody.status_level, scene.sketchbody.status = level, text


def _finish():
    """Ends the active run on the main thread: builds its result into the scene, or reports
    why not (cancelled: the scene unchanged). Returns (level, text)."""
    global _active
    a, _active = _active, None
    _cursor_progress(None)
    job, req = a.job, a.req
    result = job.result.pop("result", None) if isinstance(job.result, dict) else None
    if isinstance(job.error, a.skb.Cancelled):
        level, text = "WARNING", f"Sketchbody: {req.label} cancelled; the scene is unchanged"
    elif job.error is not None:
        level, text = "ERROR", work.describe_error(a.skb, job.error, req)
    else:
        try:
            with _main_context():
                kept = _build(bpy.context, a.skb, req, job.result)
            arm, body = build.current_body()
            xy, _ = build.read_markers(build.find_plane(), a.skb.JOINT_NAMES)  # where the body is posed to
            _set_live(_Live(result, a.skb, job.result["dictionary"], arm.name, body.name, req.rig_options, req.width, req.height, xy))
            result = None
            level, text = "INFO", _summary(req, job.result, time.perf_counter() - a.t0, kept)
            _undo_push(f"Sketchbody: {req.label}")
        except Exception as e:  # noqa: BLE001 - reported, never a traceback
            level, text = "ERROR", work.describe_error(a.skb, e, req)
    if result is not None:
        result.close()
    _set_status(bpy.context.scene, level, text)
    _redraw()
    return level, text


def _undo_push(message):
    """An undo step for what a background run built (the operator had finished before)."""
    try:
        bpy.ops.ed.undo_push(message=message)
    except RuntimeError:  # no window (blender -b) or undo disabled
        pass


def _build(context, skb, req, data):
    """Puts a finished run into the scene: a new body (beside the former ones, which stay as
    the artist left them, renamed `SKB_Body_runN`), and for "Sketch to body" a new sketch plane
    with its markers; for a re-run the markers' colours. Returns the former current body's new
    name, or ""."""
    try:
        image = build.load_image(req.image)
    except RuntimeError as e:
        raise UserError(f"Blender cannot load the sketch {req.image}: {e}")
    if req.kind == "rerun" and build.find_plane() is None:
        raise UserError("The sketch plane was removed while the body was computed; run 'Sketch to body' again")
    _object_mode(context)
    scene = context.scene
    old_arm, old_body = build.current_body()
    if req.kind == "new":
        build.remove_sketch()
    arm, body = build.build_body(scene, data["rig"], data["quads"], data["uvs"], data["face_uvs"],
                                 data["sketch_uv"], data["seen"], image, build.next_run())
    try:
        if req.kind == "new":
            _make_sketch(scene, skb, req, data, image, arm, body)
        else:
            _update_markers(req, data)
            _place_beside_kept(arm, body)
    except Exception:
        build.remove_body(arm, body)
        raise
    kept = ""
    if old_arm is not None:
        build.retire(old_arm, old_body)
        kept = old_body.name if old_body is not None else old_arm.name
    build.promote(arm, body)
    arm["skb_gender"], arm["skb_height_m"] = data["gender"], data["body_height"]
    arm["skb_detected"] = data["detection"] is not None
    return kept


def _make_sketch(scene, skb, req, data, image, arm, body):
    """The sketch plane beside the new body at the body's scale, its 15 markers, and both moved
    right of the bodies already in the scene."""
    px_floor = float(data["pixels"][:, 1].max())
    body_min_x = float(np.min(data["rig"].posed_vertices[:, 0]))
    # The sketch at the body's scale: the projected body's height in pixels = its height in metres.
    px_height = float(np.ptp(data["pixels"][:, 1]))
    body_height = float(np.ptp(data["rig"].posed_vertices[:, 1]))
    scale = body_height / px_height if px_height > 1.0 else 1.0 / data["camera"].sy
    try:
        plane = build.make_sketch_plane(scene, image, scale, px_floor, body_min_x)
        plane["skb_detected"] = req.joints is None
        build.make_markers(scene, plane, skb.JOINT_NAMES, data["joints"].xy, data["confidence"],
                           data["joints"].visible, req.threshold)
    except Exception:
        build.remove_sketch()
        raise
    right = build.kept_bodies_right_edge(exclude={body})
    if right is not None:
        plane_left = plane.location.x - image.size[0] * scale / 2
        dx = max(0.0, right + build.GAP - plane_left)
        plane.location.x += dx
        arm.location.x += dx


def _update_markers(req, data):
    """After a re-run: the markers' visibility as used, their colours for the threshold."""
    for m in build.find_markers(build.find_plane()):
        m["skb_visible"] = bool(data["joints"].visible[m["skb_index"]])
        build.highlight(m, req.threshold)


def _place_beside_kept(arm, body):
    """Moves the new body right of the bodies already in the scene (GAP between)."""
    right = build.kept_bodies_right_edge(exclude={body})
    new = build.world_x_range([body])
    if right is not None and new is not None:
        arm.location.x += max(0.0, right + build.GAP - new[0])


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


WAIT = BoolProperty(
    name="Wait", default=False, options={"SKIP_SAVE", "HIDDEN"},
    description="Return only when the body is built (for scripts; from the panel the run goes on in the "
                "background while Blender stays usable)")


class SKETCHBODY_OT_sketch_to_body(_Reporting, bpy.types.Operator):
    """Detect the 15 joints (or read them from the joints file), fit a rigged 3-D body to the
    sketch in the background and show the sketch with draggable joint markers beside it"""

    bl_idname = "sketchbody.sketch_to_body"
    bl_label = "Sketch to body"
    bl_options = {"REGISTER"}

    wait: WAIT

    @classmethod
    def poll(cls, context):
        return not is_running()

    def run(self, context):
        st = _settings(context)
        image_path = _abspath(st.image)
        if not image_path:
            raise UserError("Choose a sketch image first")
        if not os.path.isfile(image_path):
            raise UserError(f"Sketch image not found: {image_path}")
        skb = package.load(_preference_path(context))
        w, h = work.check_image(skb, image_path)
        joints, confidence = None, None  # None: the library detects them, as the CLI's run
        if st.joints:
            joints, confidence = work.read_joints_file(skb, _abspath(st.joints))
        req = work.Request("new", image_path, w, h, joints, confidence, _fit_options(skb, st),
                           _rig_options(skb, st), context.scene.name, st.threshold, _views(skb, st))
        return _start(self, context, skb, req)


class SKETCHBODY_OT_rerun(_Reporting, bpy.types.Operator):
    """Fit a new body from the joint markers' current positions on the sketch (move them with
    G first: the paper's user-correction step); the former body stays, renamed, beside it"""

    bl_idname = "sketchbody.rerun"
    bl_label = "Re-run from corrected joints"
    bl_options = {"REGISTER"}

    wait: WAIT

    @classmethod
    def poll(cls, context):
        return build.find_plane() is not None and not is_running()

    def run(self, context):
        st = _settings(context)
        plane = build.find_plane()
        if plane is None or "skb_image" not in plane:
            raise UserError("No sketch in the scene: run 'Sketch to body' first")
        image_path = _abspath(plane["skb_image"])
        skb = package.load(_preference_path(context))
        w, h = work.check_image(skb, image_path)
        try:
            xy, visible = build.read_markers(plane, skb.JOINT_NAMES)
        except ValueError as e:
            raise UserError(str(e))
        outside = [n for n, (x, y), v in zip(skb.JOINT_NAMES, xy, visible) if v and not (0 <= x <= w and 0 <= y <= h)]
        if outside:
            raise UserError(f"Joint markers outside the sketch: {', '.join(outside)}; move them back onto it")
        markers = build.find_markers(plane)
        if plane.get("skb_detected") and not any(m["skb_moved"] for m in markers):
            joints, confidence = None, None  # nothing corrected: detected again, as the CLI
        else:
            joints, confidence = skb.Joints2D(xy, visible), np.array([m["skb_confidence"] for m in markers])
        req = work.Request("rerun", image_path, w, h, joints, confidence, _fit_options(skb, st),
                           _rig_options(skb, st), context.scene.name, st.threshold, _views(skb, st))
        return _start(self, context, skb, req)


class SKETCHBODY_OT_swap_sides(_Reporting, bpy.types.Operator):
    """Swap the joint markers' left and right (the detection's other labelling: a figure read
    as seen from behind that faces the viewer, or the reverse) and fit a new body from them"""

    bl_idname = "sketchbody.swap_sides"
    bl_label = "Swap left/right"
    bl_options = {"REGISTER"}

    wait: WAIT

    @classmethod
    def poll(cls, context):
        return build.find_plane() is not None and not is_running()

    def run(self, context):
        plane = build.find_plane()
        if plane is None or "skb_image" not in plane:
            raise UserError("No sketch in the scene: run 'Sketch to body' first")
        skb = package.load(_preference_path(context))
        try:
            build.swap_markers(plane, skb)
        except ValueError as e:
            raise UserError(str(e))
        context.view_layer.update()
        return SKETCHBODY_OT_rerun.run(self, context)


class SKETCHBODY_OT_cancel(bpy.types.Operator):
    """Stop the running Sketchbody fit (within one fit iteration); the scene stays as it was"""

    bl_idname = "sketchbody.cancel"
    bl_label = "Cancel"

    @classmethod
    def poll(cls, context):
        return is_running()

    def execute(self, context):
        _active.job.cancel()
        self.report({"INFO"}, f"Sketchbody: cancelling {_active.req.label}")
        return {"FINISHED"}


class SKETCHBODY_OT_clear(_Reporting, bpy.types.Operator):
    """Remove every body the add-on made (the current one and those kept by re-runs), the sketch
    plane and the joint markers"""

    bl_idname = "sketchbody.clear"
    bl_label = "Clear"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return not is_running()

    def run(self, context):
        _object_mode(context)
        build.clear(context.scene)
        _set_live(None)
        return {"FINISHED"}


class SKETCHBODY_OT_flip_limb(_Reporting, bpy.types.Operator):
    """Flip this limb's depth (toward / away from the viewer: one view cannot tell them apart)
    and re-pose the body at once; its shape is kept"""

    bl_idname = "sketchbody.flip_limb"
    bl_label = "Flip limb forward/back"
    bl_options = {"REGISTER"}

    limb: EnumProperty(name="Limb", items=[(k, v, f"Flip the {v.lower()}'s depth") for k, v in LIMB_LABELS.items()])

    @classmethod
    def poll(cls, context):
        return live_body() is not None and not is_running()

    def run(self, context):
        if live_body() is None:
            raise UserError("No body to re-pose: run 'Sketch to body' first")
        _object_mode(context)
        t = time.perf_counter()
        outcome = _live.result.flip_limb(self.limb)
        label = LIMB_LABELS[self.limb]
        if outcome == "no_depth":
            text = f"Sketchbody: the {label.lower()} lies in the picture plane: no depth to flip; the body is unchanged"
            level = "WARNING"
        else:
            ms = _repose_scene(t)
            level, text = "INFO", f"Sketchbody: {label.lower()} flipped in depth, body re-posed in {ms:.0f} ms (shape kept)"
        _set_status(context.scene, level, text)
        self.report({level}, text)
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
        col = layout.column(align=True)
        col.prop(st, "side_image")
        if st.side_image:
            col.prop(st, "side_faces")
        col.prop(st, "back_image")
        col = layout.column()
        col.prop(st, "gender")
        col.prop(st, "height")
        col.prop(st, "rest_pose")
        col.prop(st, "naming")
        row = layout.row(align=True)
        row.prop(st, "samples")
        row.prop(st, "iterations")
        layout.operator(SKETCHBODY_OT_sketch_to_body.bl_idname, icon="OUTLINER_OB_ARMATURE")
        _draw_status(layout, st)
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
            box.prop(st, "live_repose")
        box.operator(SKETCHBODY_OT_rerun.bl_idname, icon="FILE_REFRESH")
        box.operator(SKETCHBODY_OT_swap_sides.bl_idname, icon="ARROW_LEFTRIGHT")
        box.operator(SKETCHBODY_OT_save_joints.bl_idname, icon="EXPORT")
        _draw_flips(layout)
        layout.operator(SKETCHBODY_OT_clear.bl_idname, icon="TRASH")


def _draw_flips(layout):
    """The per-limb "flip forward/back" buttons (a limb's depth), two per row."""
    box = layout.box()
    box.label(text="Limb depth: flip forward/back", icon="MOD_MIRROR")
    if live_body() is None:
        box.label(text="Run 'Sketch to body' first")
        return
    names = list(LIMB_LABELS)
    for i in range(0, len(names), 2):
        row = box.row(align=True)
        for limb in names[i:i + 2]:
            row.operator(SKETCHBODY_OT_flip_limb.bl_idname, text=LIMB_LABELS[limb]).limb = limb


def _draw_status(layout, st):
    """The running fit's progress with a Cancel button, or the last run's report."""
    if is_running():
        box = layout.box()
        box.label(text=f"{_active.req.label}: {100 * running_fraction():.0f} %", icon="SORTTIME")
        box.prop(st, "progress", text="", slider=True)
        box.operator(SKETCHBODY_OT_cancel.bl_idname, icon="CANCEL")
    elif st.status:
        icon = {"ERROR": "ERROR", "WARNING": "CANCEL"}.get(st.status_level, "INFO")
        for i, line in enumerate(_wrap(st.status, 60)[:6]):
            layout.label(text=line, icon=icon if i == 0 else "BLANK1")


CLASSES = (SketchbodyPreferences, SketchbodySettings, SKETCHBODY_OT_sketch_to_body, SKETCHBODY_OT_rerun,
           SKETCHBODY_OT_swap_sides, SKETCHBODY_OT_cancel, SKETCHBODY_OT_clear, SKETCHBODY_OT_flip_limb,
           SKETCHBODY_OT_save_joints,
           SKETCHBODY_PT_panel)


def register():
    # Blender 3.4's own glTF importer needs numpy.bool, which Debian 12's numpy 1.24 lacks: with
    # the add-on on, File > Import > glTF 2.0 (e.g. `sketchbody run`'s body.glb) works.
    gltf_compat.patch_numpy_bool()
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.sketchbody = PointerProperty(type=SketchbodySettings)
    if not bpy.app.timers.is_registered(_live_tick):
        bpy.app.timers.register(_live_tick, first_interval=LIVE_SECONDS, persistent=True)


def unregister():
    global _active
    if _active is not None:  # a run in progress: stop it, build nothing
        _active.job.cancel()
        _active = None
    if bpy.app.timers.is_registered(_tick):
        bpy.app.timers.unregister(_tick)
    if bpy.app.timers.is_registered(_live_tick):
        bpy.app.timers.unregister(_live_tick)
    _set_live(None)
    del bpy.types.Scene.sketchbody
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

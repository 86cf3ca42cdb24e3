# The add-on in a windowed Blender (under Xvfb), where Blender's own event loop runs the
# add-on's timer, as for an artist: test_addon.py runs headless (blender -b runs no timers and
# has no window, so it polls the job itself); this checks the path it cannot — the timer
# finishing the run, building the body from a timer's context (edit mode needs the window's),
# Blender's loop running meanwhile, Cancel, and a re-run keeping the former body.
#   xvfb-run -a blender --factory-startup --python integrations/blender/tests/test_addon_ui.py -- \
#       SKETCH.png JOINTS.json RESULT.txt
# The steps are driven by a timer of their own, each as a click would start it; the last writes
# RESULT.txt ("PASS" or "FAIL: ...", one line per check above it) and quits Blender. A run that
# does not finish within DEADLINE seconds writes FAIL.
import os
import sys
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))  # integrations/blender: the add-on package's parent
SKETCH, JOINTS, RESULT = [os.path.abspath(a) for a in sys.argv[sys.argv.index("--") + 1:]][:3]
DEADLINE = 600.0

import addon_utils  # noqa: E402

mod = addon_utils.enable("sketchbody_blender", default_set=True, handle_error=None)
st = bpy.context.scene.sketchbody
lines = []
state = {"step": "start", "t0": time.perf_counter(), "loop_turns": 0, "failed": False}


def check(name, ok, detail=""):
    """Records one check (printed, and written to RESULT at the end)."""
    line = f"{'ok  ' if ok else 'FAIL'} {name}" + (f": {detail}" if detail != "" else "")
    print(line, flush=True)
    lines.append(line)
    state["failed"] |= not ok


def finish():
    """Writes RESULT and quits Blender."""
    with open(RESULT, "w") as f:
        f.write("\n".join(lines) + "\n" + ("FAIL" if state["failed"] else "PASS") + "\n")
    bpy.ops.wm.quit_blender()


def bodies():
    return sorted(o.name for o in bpy.data.objects if o.name.startswith(("SKB_Body", "SKB_Armature")))


def heartbeat():
    """Counts turns of Blender's event loop while a run works (it must keep turning)."""
    if mod.is_running():
        state["loop_turns"] += 1
    return 0.02


def step():
    """The test's steps, one per timer call, each waiting for the add-on's own timer."""
    if time.perf_counter() - state["t0"] > DEADLINE:
        check(f"finished within {DEADLINE:.0f} s", False, f"stuck at step {state['step']}")
        finish()
        return None
    s = state["step"]
    if s == "start":
        st.image, st.joints = SKETCH, JOINTS
        res = bpy.ops.sketchbody.sketch_to_body()
        check("Sketch to body starts in the background", res == {"FINISHED"} and mod.is_running() and not bodies(),
              str(res))
        state["step"] = "built"
    elif s == "built" and not mod.is_running():
        check("the add-on's timer built the body; Blender's loop ran meanwhile",
              st.status_level == "INFO" and bodies() == ["SKB_Armature", "SKB_Body"] and state["loop_turns"] >= 3,
              f"{state['loop_turns']} loop turns while it ran; {st.status}")
        bpy.ops.sketchbody.rerun()
        state["step"] = "cancel"
    elif s == "cancel" and mod.running_fraction() > 0:
        bpy.ops.sketchbody.cancel()
        state["step"] = "cancelled"
    elif s == "cancelled" and not mod.is_running():
        check("Cancel: nothing built", st.status_level == "WARNING" and bodies() == ["SKB_Armature", "SKB_Body"],
              st.status)
        plane = bpy.data.objects["SKB_Sketch"]
        bpy.data.objects["SKB_joint_r_wrist"].location.y += 40 * plane["skb_metres_per_px"]
        bpy.ops.sketchbody.rerun()
        state["step"] = "rerun"
    elif s == "rerun" and not mod.is_running():
        check("re-run from a timer: the former body kept beside the new one",
              st.status_level == "INFO"
              and bodies() == ["SKB_Armature", "SKB_Armature_run1", "SKB_Body", "SKB_Body_run1"],
              f"{bodies()}; {st.status}")
        finish()
        return None
    return 0.05


bpy.app.timers.register(heartbeat, first_interval=0.5)
bpy.app.timers.register(step, first_interval=1.0)

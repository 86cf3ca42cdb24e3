# Imports a sketchbody .glb with Blender's own glTF importer (headless) and reports what an
# animator would check, as JSON: object counts, the bone hierarchy, unweighted vertices, floor
# heights, and what rotating the elbow by 45 degrees does to the forearm and the upper arm.
# Usage: blender -b --factory-startup --python-exit-code 1 -P check_glb.py -- IN.glb EXPECTED.json OUT.json
# EXPECTED.json: {"parents": {bone: parent or null}, "elbow": name, "upper_arm": name}.
import json
import math
import sys

import numpy

# Debian's Blender 3.4 importer uses numpy.bool, removed in numpy 1.24.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

import bpy  # noqa: E402
from mathutils import Quaternion  # noqa: E402

glb, expected_path, out_path = sys.argv[sys.argv.index("--") + 1:][:3]
expected = json.load(open(expected_path))
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)

meshes = [o for o in bpy.data.objects if o.type == "MESH"]
armatures = [o for o in bpy.data.objects if o.type == "ARMATURE"]
report = {"meshes": len(meshes), "armatures": len(armatures), "objects": len(bpy.data.objects)}
mesh, arm = meshes[0], armatures[0]
bones = {b.name: (b.parent.name if b.parent else None) for b in arm.data.bones}
report["bones"] = len(bones)
report["hierarchy_matches"] = bones == expected["parents"]
report["hierarchy_differences"] = sorted(
    k for k in set(bones) | set(expected["parents"]) if bones.get(k, "?") != expected["parents"].get(k, "?")
)
report["vertices"] = len(mesh.data.vertices)
report["unweighted_vertices"] = sum(1 for v in mesh.data.vertices if not any(g.weight > 0 for g in v.groups))
report["actions"] = [a.name for a in bpy.data.actions]


def world_coords():
    bpy.context.view_layer.update()
    ev = mesh.evaluated_get(bpy.context.evaluated_depsgraph_get())
    m = ev.to_mesh()
    co = [mesh.matrix_world @ v.co for v in m.vertices]
    ev.to_mesh_clear()
    return co


posed = world_coords()
rest = [mesh.matrix_world @ v.co for v in mesh.data.vertices]
report["posed_min_z"] = min(c.z for c in posed)
report["rest_min_z"] = min(c.z for c in rest)
report["rest_posed_gap"] = max((a - b).length for a, b in zip(posed, rest))
# The elbow bone: its direction against the forearm (its child's head minus its head).
eb = arm.data.bones[expected["elbow"]]
report["elbow_bone_length"] = eb.length

# Rotate the elbow by 45 degrees about its own X axis, the animation detached so nothing resets it.
if arm.animation_data:
    arm.animation_data.action = None
pb = arm.pose.bones[expected["elbow"]]
pb.rotation_mode = "QUATERNION"
before = world_coords()
pb.rotation_quaternion = pb.rotation_quaternion @ Quaternion((1.0, 0.0, 0.0), math.radians(45.0))
after = world_coords()
index = {g.name: g.index for g in mesh.vertex_groups}
fore, upper = index[expected["elbow"]], index[expected["upper_arm"]]
fore_moves, upper_moves, upper_dominant_moves = [], [], []
for v, a, b in zip(mesh.data.vertices, before, after):
    w = {g.group: g.weight for g in v.groups}
    d = (a - b).length
    if w.get(fore, 0.0) >= 0.5:
        fore_moves.append(d)
    if w.get(upper, 0.0) >= 0.999:
        upper_moves.append(d)
    if w.get(upper, 0.0) >= 0.5:
        upper_dominant_moves.append(d)
report["forearm_vertices"] = len(fore_moves)
report["forearm_mean_move"] = sum(fore_moves) / max(len(fore_moves), 1)
report["forearm_max_move"] = max(fore_moves, default=0.0)
report["upper_arm_vertices"] = len(upper_moves)
report["upper_arm_max_move"] = max(upper_moves, default=0.0)
report["upper_arm_dominant_vertices"] = len(upper_dominant_moves)
report["upper_arm_dominant_max_move"] = max(upper_dominant_moves, default=0.0)
json.dump(report, open(out_path, "w"), indent=1)

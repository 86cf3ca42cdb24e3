# Imports a sketchbody .glb and the .fbx of the same body with Blender's own importers (headless)
# and reports, as JSON, what the FBX import gives against the glTF import: object and bone
# counts, bone names and parents, each bone's rest and posed head in world space, each vertex's
# weights and its posed world position (vertices matched by their rest position), and what the
# FBX importer printed as warnings. Several FBX
# files of the same body (in other units or up axes) may follow, each with its report: Blender's
# own unit and axis conversion brings each into its metres, Z up, where the glTF import is.
# Usage: blender -b --factory-startup --python-exit-code 1 -P check_fbx.py -- IN.glb IN.fbx OUT.json
#        [IN2.fbx OUT2.json ...]
import contextlib
import io
import json
import sys

import numpy

# Debian's Blender 3.4 glTF importer uses numpy.bool, removed in numpy 1.24.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

import bpy  # noqa: E402
from mathutils import kdtree  # noqa: E402

args = sys.argv[sys.argv.index("--") + 1:]
glb = args[0]


def load(importer, path):
    """Imports `path` into an empty scene; returns what the import printed and the objects."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        result = importer(filepath=path)
    meshes = [o for o in bpy.data.objects if o.type == "MESH"]
    armatures = [o for o in bpy.data.objects if o.type == "ARMATURE"]
    return result, text.getvalue(), meshes, armatures


def describe(mesh, arm):
    """Rest and posed world positions, weights by bone name, the bone tree."""
    bpy.context.view_layer.update()
    names = {g.index: g.name for g in mesh.vertex_groups}
    ev = mesh.evaluated_get(bpy.context.evaluated_depsgraph_get())
    m = ev.to_mesh()
    posed = [tuple(mesh.matrix_world @ v.co) for v in m.vertices]
    ev.to_mesh_clear()
    rest = [tuple(mesh.matrix_world @ v.co) for v in mesh.data.vertices]
    weights = [{names[g.group]: g.weight for g in v.groups if g.weight > 0} for v in mesh.data.vertices]
    bones = {b.name: (b.parent.name if b.parent else None) for b in arm.data.bones}
    heads = {b.name: tuple(arm.matrix_world @ b.head_local) for b in arm.data.bones}
    posed_heads = {b.name: tuple(arm.matrix_world @ b.head) for b in arm.pose.bones}
    return {"rest": rest, "posed": posed, "weights": weights, "bones": bones, "heads": heads,
            "posed_heads": posed_heads, "uv_layers": len(mesh.data.uv_layers)}


_, _, meshes, armatures = load(bpy.ops.import_scene.gltf, glb)
ref = describe(meshes[0], armatures[0])
tree = kdtree.KDTree(len(ref["rest"]))
for i, co in enumerate(ref["rest"]):
    tree.insert(co, i)
tree.balance()


def check(fbx, out_path):
    result, printed, meshes, armatures = load(bpy.ops.import_scene.fbx, fbx)
    report = {
        "result": sorted(result),
        "warnings": [line for line in printed.splitlines() if "warn" in line.lower()],
        "meshes": len(meshes),
        "armatures": len(armatures),
    }
    got = describe(meshes[0], armatures[0])
    report["bones"] = len(got["bones"])
    report["bones_match"] = got["bones"] == ref["bones"]
    report["uv_layers"] = got["uv_layers"]
    report["vertices"] = len(got["rest"])
    report["images"] = [(i.name, i.size[0], i.size[1], i.packed_file is not None) for i in bpy.data.images]
    rest_gap = posed_gap = weight_gap = 0.0
    for i, co in enumerate(got["rest"]):
        _, j, d = tree.find(co)
        rest_gap = max(rest_gap, d)
        posed_gap = max(posed_gap, max(abs(a - b) for a, b in zip(got["posed"][i], ref["posed"][j])))
        a, b = got["weights"][i], ref["weights"][j]
        weight_gap = max(weight_gap, max(abs(a.get(k, 0.0) - b.get(k, 0.0)) for k in set(a) | set(b)))
    gap = lambda key: max(  # noqa: E731
        max(abs(a - b) for a, b in zip(got[key][n], ref[key][n])) for n in ref[key] if n in got[key]
    )
    report["bone_head_gap"] = gap("heads")
    report["posed_bone_head_gap"] = gap("posed_heads")
    report["rest_gap"] = rest_gap
    report["posed_gap"] = posed_gap
    report["weight_gap"] = weight_gap
    report["posed_moved"] = max(
        max(abs(a - b) for a, b in zip(p, r)) for p, r in zip(got["posed"], got["rest"])
    )
    json.dump(report, open(out_path, "w"), indent=1)


for fbx, out_path in zip(args[1::2], args[2::2]):
    check(fbx, out_path)

# Imports a sketchbody .glb or .fbx with shape keys with Blender's own importer (headless) and
# reports, as JSON, the shape keys it made (names, values) and how far each key's displacement of
# every vertex is from the expected one (vertices matched by their basis position in world
# space), plus the bones it made and their parents.
# Usage: blender -b --factory-startup --python-exit-code 1 -P check_keys.py -- IN EXPECTED.json OUT.json
# EXPECTED.json: {"rest": [[x, y, z], ...], "keys": {name: [[dx, dy, dz], ...]}} in Blender's
# world space (metres, Z up).
import json
import sys

import numpy

# Debian's Blender 3.4 glTF importer uses numpy.bool, removed in numpy 1.24.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

import bpy  # noqa: E402
from mathutils import Vector, kdtree  # noqa: E402

path, expected_path, out_path = sys.argv[sys.argv.index("--") + 1:][:3]
expected = json.load(open(expected_path))
bpy.ops.wm.read_factory_settings(use_empty=True)
if path.endswith(".fbx"):
    bpy.ops.import_scene.fbx(filepath=path)
else:
    bpy.ops.import_scene.gltf(filepath=path)
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
armatures = [o for o in bpy.data.objects if o.type == "ARMATURE"]
mesh = meshes[0]
report = {"meshes": len(meshes), "armatures": len(armatures)}
arm = armatures[0]
report["bones"] = {b.name: (b.parent.name if b.parent else None) for b in arm.data.bones}
blocks = mesh.data.shape_keys.key_blocks if mesh.data.shape_keys else []
report["keys"] = [(k.name, k.value) for k in blocks]
tree = kdtree.KDTree(len(expected["rest"]))
for i, co in enumerate(expected["rest"]):
    tree.insert(co, i)
tree.balance()
m = mesh.matrix_world
basis = [m @ v.co for v in mesh.data.vertices]
match = []
rest_gap = 0.0
for co in basis:
    _, j, d = tree.find(co)
    match.append(j)
    rest_gap = max(rest_gap, d)
report["rest_gap"] = rest_gap
gaps = {}
for k in blocks[1:]:
    want = expected["keys"].get(k.name)
    if want is None:
        continue
    gap = 0.0
    for i, j in enumerate(match):
        got = m @ k.data[i].co - basis[i]
        gap = max(gap, (got - Vector(want[j])).length)
    gaps[k.name] = gap
report["key_gaps"] = gaps
json.dump(report, open(out_path, "w"), indent=1)

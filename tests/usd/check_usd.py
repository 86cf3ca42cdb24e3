# Checks a sketchbody .usda with Pixar's own libraries (the usd-core wheel): the checks usdchecker
# runs (USD 24 and later: every registered UsdValidation validator; the wheel ships the library,
# not the usdchecker script), then UsdSkel's own skinning of the mesh by the skeleton and its
# animation, compared with the expected posed points (in the layer's own units and axes); the
# stage's up axis and metres per unit as UsdGeom reads them, and the SkelRoot's authored extent
# size; the blend shapes bound to the mesh against the expected displacements. Prints a JSON
# report.
# Usage: python check_usd.py IN.usda EXPECTED.json
#   (EXPECTED.json: {"posed": [[x, y, z], ...], "keys": [[[dx, dy, dz], ...], ...]})
import json
import sys

from pxr import Usd, UsdGeom, UsdSkel, UsdValidation

path, expected_path = sys.argv[1:3]
expected = json.load(open(expected_path))
posed = expected["posed"]
keys = expected.get("keys", [])
report = {}
stage = Usd.Stage.Open(path)
validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
errors = UsdValidation.ValidationContext(validators).Validate(stage)
report["validators"] = len(validators)
report["up_axis"] = str(UsdGeom.GetStageUpAxis(stage))
report["meters_per_unit"] = UsdGeom.GetStageMetersPerUnit(stage)
lo, hi = UsdGeom.Boundable(stage.GetDefaultPrim()).GetExtentAttr().Get()
report["extent_size"] = [hi[k] - lo[k] for k in range(3)]
report["errors"] = [f"{e.GetType()}: {e.GetMessage()}" for e in errors]
root = UsdSkel.Root(stage.GetDefaultPrim())
cache = UsdSkel.Cache()
cache.Populate(root, Usd.TraverseInstanceProxies())
bindings = cache.ComputeSkelBindings(root, Usd.TraverseInstanceProxies())
report["bindings"] = len(bindings)
for binding in bindings:
    query = cache.GetSkelQuery(binding.GetSkeleton())
    report["joints"] = [str(j) for j in query.GetJointOrder()]
    report["has_animation"] = bool(query.GetAnimQuery())
    xforms = query.ComputeSkinningTransforms(Usd.TimeCode.Default())
    targets = binding.GetSkinningTargets()
    report["targets"] = len(targets)
    for target in targets:
        points = UsdGeom.Mesh(target.GetPrim()).GetPointsAttr().Get()
        report["skinned"] = bool(target.ComputeSkinnedPoints(xforms, points, Usd.TimeCode.Default()))
        report["points"] = len(points)
        report["posed_gap"] = max(max(abs(a - b) for a, b in zip(p, q)) for p, q in zip(points, posed))
        # The blend shapes UsdSkel binds to the mesh, against the expected displacements.
        binding_api = UsdSkel.BindingAPI(target.GetPrim())
        shapes = binding_api.GetBlendShapesAttr().Get() or []
        shape_targets = binding_api.GetBlendShapeTargetsRel().GetTargets()
        report["blend_shapes"] = len(shapes)
        gap = 0.0
        for path, want in zip(shape_targets, keys):
            offsets = UsdSkel.BlendShape(stage.GetPrimAtPath(path)).GetOffsetsAttr().Get()
            gap = max(gap, max(max(abs(a - b) for a, b in zip(o, w)) for o, w in zip(offsets, want)))
        report["blend_gap"] = gap
print(json.dumps(report))

"""Building the scene from the sketchbody package's arrays: the sketch plane with its 15 joint
markers, and the body (mesh, 53-bone armature, vertex groups, pose, material).

Frames: the rig's export frame is glTF's (+Y up, +Z toward the viewer, metres, origin on the
floor); the armature object is turned 90 degrees about X, as Blender's glTF importer does, so
the body stands on Blender's floor (+Z up) facing -Y. The sketch plane stands beside it in the
XZ plane, facing -Y too. Everything lives in the collection "Sketchbody".
"""

import math

import bpy
import numpy as np
from mathutils import Matrix, Vector

from . import package

COLLECTION = "Sketchbody"
PLANE = "SKB_Sketch"
ARMATURE = "SKB_Armature"
BODY = "SKB_Body"
MARKER_PREFIX = "SKB_joint_"
BODY_MATERIAL = "SKB_BodyMaterial"
PLANE_MATERIAL = "SKB_SketchMaterial"
MARKER_MATERIALS = {"ok": ("SKB_JointOK", (0.1, 0.55, 1.0, 1.0)), "low": ("SKB_JointLow", (1.0, 0.05, 0.05, 1.0)),
                    "moved": ("SKB_JointMoved", (1.0, 0.6, 0.0, 1.0))}
MARKER_RADIUS_PX = {"ok": 6.0, "low": 11.0, "moved": 7.0}
UNSEEN_GREY = (0.55, 0.55, 0.55, 1.0)  # the body where the sketch does not see it (as the GLB's texture)
SEEN = "sketch_seen"  # colour attribute: how squarely the sketch's camera sees each vertex (0..1)
GAP = 0.4  # metres between the sketch plane's right edge and the body's left side, and between bodies
ROLE = "skb_role"  # custom property: "armature" or "body" on what build_body made
RUN = "skb_run"  # custom property of an armature: its run number (1, 2, ...)
CURRENT = "skb_current"  # custom property of an armature: the latest run's (re-runs keep the others)


# ---------------------------------------------------------------------------------------------
# small helpers


def collection(scene, create=True):
    coll = bpy.data.collections.get(COLLECTION)
    if coll is None and create:
        coll = bpy.data.collections.new(COLLECTION)
    if coll is not None and create and coll.name not in scene.collection.children:
        scene.collection.children.link(coll)
    return coll


def _remove_object(obj):
    data = obj.data
    bpy.data.objects.remove(obj, do_unlink=True)
    if data is not None and data.users == 0:
        if isinstance(data, bpy.types.Mesh):
            bpy.data.meshes.remove(data)
        elif isinstance(data, bpy.types.Armature):
            bpy.data.armatures.remove(data)


def _remove_material(name):
    m = bpy.data.materials.get(name)
    if m is not None and m.users == 0:
        bpy.data.materials.remove(m)


def body_objects():
    """Every body the add-on built and the scene still holds, as (armature, mesh or None) pairs,
    oldest run first: the current one and those kept by re-runs."""
    arms = [o for o in bpy.data.objects if o.get(ROLE) == "armature"]
    arms.sort(key=lambda o: o.get(RUN, 0))
    return [(a, next((c for c in a.children if c.get(ROLE) == "body"), None)) for a in arms]


def current_body():
    """(armature, mesh) of the latest run, or (None, None)."""
    for arm, body in reversed(body_objects()):
        if arm.get(CURRENT):
            return arm, body
    return None, None


def next_run():
    """The run number of the next body (1 + the largest in the scene)."""
    return 1 + max([a.get(RUN, 0) for a, _ in body_objects()], default=0)


def retire(arm, body):
    """Keeps a former run's body as it is (with whatever the artist changed: pose, edits,
    modifiers, materials), renamed `SKB_Armature_runN` / `SKB_Body_runN` so that the next run
    takes the plain names."""
    n = arm.get(RUN, 0)
    arm[CURRENT] = False
    arm.name = f"{ARMATURE}_run{n}"
    arm.data.name = arm.name
    if body is not None:
        body.name = f"{BODY}_run{n}"
        body.data.name = body.name
        material = body.active_material
        if material is not None and material.name == BODY_MATERIAL:
            material.name = f"{BODY_MATERIAL}_run{n}"


def promote(arm, body):
    """Gives a newly built body the plain names (SKB_Armature, SKB_Body, SKB_BodyMaterial)
    once the former current one was retired."""
    arm.name = arm.data.name = ARMATURE
    body.name = body.data.name = BODY
    if body.active_material is not None:
        body.active_material.name = BODY_MATERIAL


def remove_body(arm, body):
    """Removes one body (mesh, armature) and its material when nothing else uses it."""
    material = body.active_material if body is not None else None
    for obj in (body, arm):
        if obj is not None:
            _remove_object(obj)
    if material is not None and material.users == 0:
        bpy.data.materials.remove(material)


def world_x_range(objects):
    """(min, max) world x of the evaluated (deformed, modified) objects' bounding boxes, or
    None for none."""
    bpy.context.view_layer.update()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    xs = []
    for obj in objects:
        ev = obj.evaluated_get(depsgraph)
        xs += [(obj.matrix_world @ Vector(c)).x for c in ev.bound_box]
    return (min(xs), max(xs)) if xs else None


def kept_bodies_right_edge(exclude=()):
    """The largest world x of the bodies already in the scene (not those in `exclude`), or None."""
    r = world_x_range([b for _, b in body_objects() if b is not None and b not in exclude])
    return None if r is None else r[1]


def clear(scene):
    """Removes everything the add-on made: every body (the current one and those kept by
    re-runs), the plane, the markers, their materials and collection."""
    for arm, body in body_objects():
        remove_body(arm, body)
    remove_sketch()
    coll = bpy.data.collections.get(COLLECTION)
    if coll is not None and len(coll.all_objects) == 0:
        bpy.data.collections.remove(coll)


def remove_sketch():
    """Removes the sketch plane, the joint markers and their materials (not the bodies)."""
    for obj in list(bpy.data.objects):
        if obj.name == PLANE or obj.name.startswith(MARKER_PREFIX):
            _remove_object(obj)
    for name in [PLANE_MATERIAL] + [m for m, _ in MARKER_MATERIALS.values()]:
        _remove_material(name)
    mesh = bpy.data.meshes.get("SKB_JointSphere")
    if mesh is not None and mesh.users == 0:
        bpy.data.meshes.remove(mesh)


def load_image(path):
    img = bpy.data.images.load(path, check_existing=True)
    img.reload()  # the file may have changed since it was first loaded
    return img


def _socket(sockets, identifier):
    return next(x for x in sockets if x.identifier == identifier)


def _image_material(name, image, uv_map=None, emission=False, seen_attribute=None, fresh=False):
    """A material showing `image` (through `uv_map`); lit (Principled) or unlit (Emission).
    With `seen_attribute` (a colour attribute: 1 where the sketch sees the surface, 0 where it
    does not) the unseen parts show a neutral grey instead of the projected strokes. `fresh`:
    always a new material (a former body's, which the artist may have changed, stays as it is)."""
    mat = None if fresh else bpy.data.materials.get(name)
    mat = mat or bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.interpolation = "Linear"
    if uv_map:
        uv = nt.nodes.new("ShaderNodeUVMap")
        uv.uv_map = uv_map
        nt.links.new(uv.outputs["UV"], tex.inputs["Vector"])
    if emission:
        sh = nt.nodes.new("ShaderNodeEmission")
        nt.links.new(tex.outputs["Color"], sh.inputs["Color"])
        nt.links.new(sh.outputs["Emission"], out.inputs["Surface"])
    else:
        sh = nt.nodes.new("ShaderNodeBsdfPrincipled")
        sh.inputs["Roughness"].default_value = 0.8
        colour = tex.outputs["Color"]
        if seen_attribute:
            attr = nt.nodes.new("ShaderNodeAttribute")
            attr.attribute_name = seen_attribute
            mix = nt.nodes.new("ShaderNodeMix")
            mix.data_type = "RGBA"
            nt.links.new(attr.outputs["Fac"], _socket(mix.inputs, "Factor_Float"))
            _socket(mix.inputs, "A_Color").default_value = UNSEEN_GREY
            nt.links.new(colour, _socket(mix.inputs, "B_Color"))
            colour = _socket(mix.outputs, "Result_Color")
        nt.links.new(colour, sh.inputs["Base Color"])
        nt.links.new(sh.outputs["BSDF"], out.inputs["Surface"])
    nt.nodes.active = tex  # Workbench's texture colour and the viewport's texture paint use it
    return mat


def _marker_material(kind):
    name, colour = MARKER_MATERIALS[kind]
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.diffuse_color = colour  # Workbench / solid view
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = colour
    nt.links.new(em.outputs["Emission"], out.inputs["Surface"])
    return mat


def _sphere_mesh():
    """A unit UV sphere shared by all markers (scaled per marker)."""
    me = bpy.data.meshes.get("SKB_JointSphere")
    if me is not None:
        return me
    import bmesh

    me = bpy.data.meshes.new("SKB_JointSphere")
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=16, v_segments=8, radius=1.0)
    bm.to_mesh(me)
    bm.free()
    for p in me.polygons:
        p.use_smooth = True
    return me


# ---------------------------------------------------------------------------------------------
# the sketch plane and the joint markers


def make_sketch_plane(scene, image, metres_per_px, floor_row, body_min_x):
    """A plane showing `image` (w x h px) at `metres_per_px`, standing in the XZ plane facing -Y,
    pixel row `floor_row` on the floor (z = 0), its right edge GAP left of `body_min_x`.
    Pixel (u, v) is at plane-local ((u - w/2) s, (h/2 - v) s, 0)."""
    coll = collection(scene)
    w, h = image.size
    s = metres_per_px
    me = bpy.data.meshes.new(PLANE)
    hw, hh = w * s / 2, h * s / 2
    me.from_pydata([(-hw, -hh, 0), (hw, -hh, 0), (hw, hh, 0), (-hw, hh, 0)], [], [(0, 1, 2, 3)])
    uv = me.uv_layers.new(name="UVMap")
    for loop, (u, v) in zip(me.loops, [(0, 0), (1, 0), (1, 1), (0, 1)]):
        uv.data[loop.index].uv = (u, v)
    me.materials.append(_image_material(PLANE_MATERIAL, image, emission=True))
    plane = bpy.data.objects.new(PLANE, me)
    plane.location = (body_min_x - GAP - hw, 0.0, (floor_row - h / 2) * s)
    plane.rotation_euler = (math.radians(90.0), 0.0, 0.0)
    plane["skb_image"] = image.filepath
    plane["skb_width"] = w
    plane["skb_height"] = h
    plane["skb_metres_per_px"] = s
    plane.lock_rotation = (True, True, True)
    coll.objects.link(plane)
    return plane


def pixel_to_plane(plane, xy):
    s, w, h = plane["skb_metres_per_px"], plane["skb_width"], plane["skb_height"]
    return Vector(((xy[0] - w / 2) * s, (h / 2 - xy[1]) * s, 0.0))


def plane_to_pixel(plane, local):
    s, w, h = plane["skb_metres_per_px"], plane["skb_width"], plane["skb_height"]
    return (local.x / s + w / 2, h / 2 - local.y / s)


def make_markers(scene, plane, names, xy, confidence, visible, threshold):
    """The 15 joints as small spheres parented to the plane (drag them with G; their local Z is
    locked, so they stay on the sketch). Joints with confidence below `threshold` or marked
    missing are larger and red; the others blue."""
    coll = collection(scene)
    sphere = _sphere_mesh()
    markers = []
    for i, name in enumerate(names):
        obj = bpy.data.objects.new(MARKER_PREFIX + name, sphere)
        if not obj.data.materials:  # one slot on the shared mesh, its material set per object
            obj.data.materials.append(None)
        obj.material_slots[0].link = "OBJECT"
        obj.parent = plane
        obj.matrix_parent_inverse = Matrix.Identity(4)
        obj.location = pixel_to_plane(plane, xy[i]) + Vector((0.0, 0.0, 0.004))
        obj.lock_location = (False, False, True)
        obj.show_in_front = True
        obj["skb_joint"] = name
        obj["skb_index"] = i
        obj["skb_confidence"] = float(confidence[i])
        obj["skb_visible"] = bool(visible[i])
        obj["skb_start_px"] = [float(xy[i][0]), float(xy[i][1])]
        highlight(obj, threshold)
        coll.objects.link(obj)
        markers.append(obj)
    return markers


def highlight(marker, threshold):
    """Colours a joint marker: orange once the user moved it (a corrected joint, seen by the
    last re-run), else red, larger and named when its confidence is below `threshold` or the
    joint was given as missing, else blue and small."""
    low = marker["skb_confidence"] < threshold or not marker["skb_visible"]
    kind = "moved" if marker.get("skb_moved") else "low" if low else "ok"
    marker.material_slots[0].material = _marker_material(kind)
    r = MARKER_RADIUS_PX[kind] * marker.parent["skb_metres_per_px"]
    marker.scale = (r, r, r)
    marker.show_name = low
    marker["skb_low_confidence"] = low


def find_plane():
    return bpy.data.objects.get(PLANE)


def find_markers(plane):
    return sorted((o for o in plane.children if "skb_joint" in o), key=lambda o: o["skb_index"])


def swap_markers(plane, skb):
    """Swaps the joint markers' left and right (each marker takes its mirror's position,
    confidence and visibility; head, neck and pelvis stay), as the library's
    Joints2D.swap_sides: the detection's other labelling, for a figure read as seen from behind
    that faces the viewer, or the reverse."""
    names = list(skb.JOINT_NAMES)
    xy, visible = read_markers(plane, names)
    swapped = skb.Joints2D(xy, visible).swap_sides()
    markers = {o["skb_joint"]: o for o in find_markers(plane)}
    conf = {n: (markers[n]["skb_confidence"], markers[n]["skb_visible"]) for n in names}
    for i, n in enumerate(names):
        m = markers[n]
        m.location = pixel_to_plane(plane, swapped.xy[i]) + Vector((0.0, 0.0, m.location.z))
        side = {"r_": "l_", "l_": "r_"}.get(n[:2])
        m["skb_confidence"], m["skb_visible"] = conf[side + n[2:] if side else n]


def read_markers(plane, names):
    """(xy (15, 2) pixels, visible (15,) bool) from the markers' current positions. A marker
    moved by more than half a pixel from where detection (or the joints file) put it is marked
    `skb_moved`; a joint given as missing becomes visible once its marker was moved."""
    markers = {o["skb_joint"]: o for o in find_markers(plane)}
    absent = [n for n in names if n not in markers]
    if absent:
        raise ValueError(f"joint markers missing: {', '.join(absent)} (run 'Sketch to body' again)")
    inv = plane.matrix_world.inverted()
    xy = np.zeros((len(names), 2))
    visible = np.zeros(len(names), dtype=bool)
    for i, n in enumerate(names):
        m = markers[n]
        xy[i] = plane_to_pixel(plane, inv @ m.matrix_world.translation)
        moved = math.dist(xy[i], m["skb_start_px"]) > 0.5
        m["skb_moved"] = moved
        visible[i] = bool(m["skb_visible"]) or moved
    return xy, visible


# ---------------------------------------------------------------------------------------------
# the body


def _trs(t, q):
    m = np.eye(4)
    m[:3, :3] = package.load().quat_to_matrix(q)  # the package is loaded: its rig is here
    m[:3, 3] = t
    return m


def rig_matrices(rig):
    """(rest_local, posed_local, rest_global): per bone 4x4 matrices relative to the parent
    (rest and posed) and the rest bone-to-armature matrices, by docs/c-api.md's recipe."""
    n = len(rig.parents)
    rest_local = np.zeros((n, 4, 4))
    posed_local = np.zeros((n, 4, 4))
    rest_global = np.zeros((n, 4, 4))
    for b, p in enumerate(rig.parents):
        t = np.asarray(rig.rest_translations[b], dtype=np.float64)
        rest_local[b] = _trs(t, rig.rest_rotations[b])
        posed_local[b] = _trs(t + (rig.root_translation if p < 0 else 0.0), rig.local_rotations[b])
        rest_global[b] = rest_local[b] if p < 0 else rest_global[p] @ rest_local[b]
    return rest_local, posed_local, rest_global


def _bone_lengths(rig, rest_global):
    n = len(rig.parents)
    lengths = np.zeros(n)
    children = [[] for _ in range(n)]
    for b, p in enumerate(rig.parents):
        if p >= 0:
            children[p].append(b)
    for b in range(n):  # parents come first, so a leaf can use its parent's length
        head, axis = rest_global[b][:3, 3], rest_global[b][:3, 1]
        best = 0.0
        for c in children[b]:
            best = max(best, float(np.dot(rest_global[c][:3, 3] - head, axis)))
        if best < 0.01:
            p = rig.parents[b]
            best = min(max(0.5 * lengths[p], 0.02), 0.12) if p >= 0 else 0.1
        lengths[b] = best
    return lengths


def _mesh_from_arrays(name, vertices, quads, uv_layers):
    """A Blender mesh from (N, 3) vertices and (F, 4) quads (a triangle repeats an index), with
    per-corner UV layers {name: (uvs (U, 2), face_uvs (F, 4))} or {name: per-vertex (N, 2)}."""
    quads = np.asarray(quads, dtype=np.int64)
    keep = np.ones(quads.shape, dtype=bool)
    # A quad whose corners repeat an index is a triangle: drop the repeated corner.
    for k in range(1, 4):
        for j in range(k):
            keep[:, k] &= quads[:, k] != quads[:, j]
    totals = keep.sum(axis=1)
    loops = quads[keep]
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(vertices))
    me.vertices.foreach_set("co", np.asarray(vertices, dtype=np.float32).ravel())
    me.loops.add(len(loops))
    me.loops.foreach_set("vertex_index", loops.astype(np.int32))
    me.polygons.add(len(quads))
    starts = np.concatenate([[0], np.cumsum(totals)[:-1]]).astype(np.int32)
    me.polygons.foreach_set("loop_start", starts)
    me.polygons.foreach_set("loop_total", totals.astype(np.int32))
    me.polygons.foreach_set("use_smooth", np.ones(len(quads), dtype=bool))
    for uv_name, data in uv_layers.items():
        layer = me.uv_layers.new(name=uv_name)
        if isinstance(data, tuple):
            uvs, face_uvs = data
            per_loop = np.asarray(uvs, dtype=np.float32)[np.asarray(face_uvs, dtype=np.int64)[keep]]
        else:
            per_loop = np.asarray(data, dtype=np.float32)[loops]
        layer.data.foreach_set("uv", per_loop.ravel())
    me.update(calc_edges=True)
    return me


def _pose_bones(arm, names, rest_local, posed_local):
    """Poses the armature's bones `names` by the rig's matrices (rig_matrices)."""
    for b, name in enumerate(names):
        pb = arm.pose.bones[name]
        pb.rotation_mode = "QUATERNION"
        pb.matrix_basis = Matrix((np.linalg.inv(rest_local[b]) @ posed_local[b]).tolist())


def _set_seen(me, seen):
    """The colour attribute SEEN of mesh `me` from per-vertex `seen` (0..1)."""
    seen = np.clip(np.asarray(seen, dtype=np.float32), 0.0, 1.0)
    me.color_attributes[SEEN].data.foreach_set("color", np.repeat(seen[:, None], 4, axis=1).ravel())


def apply_pose(arm, body, rig, sketch_uv, seen):
    """Re-poses a built body in place (a flipped limb, a live re-pose: the shape unchanged): the
    armature's bones from `rig` (made with the options the body was built with), the mesh's
    "sketch" UVs and SEEN colours from the re-posed projection. The rest mesh, vertex groups,
    modifiers and material stay; a mesh whose vertex count the artist changed keeps its UVs."""
    rest_local, posed_local, _ = rig_matrices(rig)
    _pose_bones(arm, list(rig.bone_names), rest_local, posed_local)
    me = body.data if body is not None else None
    if me is not None and len(me.vertices) == len(sketch_uv) and "sketch" in me.uv_layers and SEEN in me.color_attributes:
        loops = np.empty(len(me.loops), dtype=np.int32)
        me.loops.foreach_get("vertex_index", loops)
        me.uv_layers["sketch"].data.foreach_set("uv", np.asarray(sketch_uv, dtype=np.float32)[loops].ravel())
        _set_seen(me, seen)
        me.update()


def build_body(scene, rig, quads, uvs, face_uvs, sketch_uv, seen, image, run):
    """The armature (53 bones from the rig's names, parents and rest transforms, posed by its
    local rotations) and the skinned mesh (the rig's bind-pose vertices, vertex groups with the
    rig's weights, an Armature modifier, MakeHuman's UVs and the sketch's
    projection as UV map "sketch" with the sketch as texture where `seen` (per vertex, 0..1,
    the colour attribute "sketch_seen") says the sketch sees the surface), with a material of
    its own; both tagged as run `run` (the current one). Returns (armature, mesh); on an error
    nothing of it stays in the scene. Another run's body is left as it is (the new one may take
    a suffixed name until promote())."""
    made = []
    try:
        return _build_body(scene, rig, quads, uvs, face_uvs, sketch_uv, seen, image, run, made)
    except Exception:
        arm = next((o for o in made if o.type == "ARMATURE"), None)
        if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        remove_body(arm, next((o for o in made if o.type == "MESH"), None))
        raise


def _build_body(scene, rig, quads, uvs, face_uvs, sketch_uv, seen, image, run, made):
    """build_body's work; appends each object it makes to `made` (for the clean-up)."""
    coll = collection(scene)
    names = list(rig.bone_names)
    rest_local, posed_local, rest_global = rig_matrices(rig)
    lengths = _bone_lengths(rig, rest_global)

    arm_data = bpy.data.armatures.new(ARMATURE)
    arm_data.display_type = "STICK"
    arm = bpy.data.objects.new(ARMATURE, arm_data)
    made.append(arm)
    arm.rotation_euler = (math.radians(90.0), 0.0, 0.0)  # glTF +Y up -> Blender +Z up
    arm.show_in_front = True
    coll.objects.link(arm)

    view_layer = bpy.context.view_layer
    view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    try:
        ebones = []
        for b, name in enumerate(names):
            eb = arm_data.edit_bones.new(name)
            eb.head = (0.0, 0.0, 0.0)
            eb.tail = (0.0, float(lengths[b]), 0.0)
            eb.matrix = Matrix(rest_global[b].tolist())
            ebones.append(eb)
        for b, p in enumerate(rig.parents):
            if p >= 0:
                ebones[b].parent = ebones[p]
                ebones[b].use_connect = False
    finally:
        bpy.ops.object.mode_set(mode="OBJECT")

    _pose_bones(arm, names, rest_local, posed_local)

    me = _mesh_from_arrays(BODY, rig.rest_vertices, quads,
                           {"sketch": sketch_uv, "MakeHuman": (uvs, face_uvs)})
    me.uv_layers["sketch"].active = True
    me.uv_layers["sketch"].active_render = True
    me.color_attributes.new(SEEN, "FLOAT_COLOR", "POINT")
    _set_seen(me, seen)
    me.materials.append(_image_material(BODY_MATERIAL, image, uv_map="sketch", seen_attribute=SEEN, fresh=True))
    body = bpy.data.objects.new(BODY, me)
    made.append(body)
    body.parent = arm
    coll.objects.link(body)
    groups = [body.vertex_groups.new(name=n) for n in names]
    bones = np.asarray(rig.skin_bones)
    weights = np.asarray(rig.skin_weights)
    for v in range(bones.shape[0]):
        for k in range(bones.shape[1]):
            w = float(weights[v, k])
            if w > 0.0:
                groups[int(bones[v, k])].add((v,), w, "ADD")
    mod = body.modifiers.new("Armature", "ARMATURE")
    mod.object = arm
    mod.use_vertex_groups = True

    arm["skb_bones"] = len(names)
    arm[ROLE], arm[RUN], arm[CURRENT] = "armature", run, True
    body[ROLE] = "body"
    return arm, body

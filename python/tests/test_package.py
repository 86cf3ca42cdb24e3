"""The Pythonic layer: the pipeline on the bundled example, its arrays against the library's own
results and known facts, pose, detection, mesh and rig, images, and the error paths (bad files,
wrong types and dtypes, None, short and non-contiguous arrays, cancel, closed handles, a missing
library). Run: python3 -m unittest discover -s python/tests (after `pip install ./python`, or with
PYTHONPATH=python from a checkout with target/release/libsketchbody.so)."""

import ctypes
import json
import os
import struct
import subprocess
import sys
import tempfile
import threading
import tomllib
import unittest

import numpy as np

import sketchbody as skb

from _util import CLI, ROOT, SKETCH, SKETCH_JOINTS, read_gray_png, test_card, write_gray_png

NV, NF = 13380, 13378


def rigid_fit(p, q):
    """Rotation r and translation t minimising |p r^T + t - q| (Kabsch)."""
    pc, qc = p.mean(axis=0), q.mean(axis=0)
    u, _, vt = np.linalg.svd((p - pc).T @ (q - qc))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return r, qc - r @ pc


class Example:
    """The example's pipeline result, computed once for all tests."""

    result = None
    progress = []
    seconds = 0.0

    @classmethod
    def get(cls):
        if cls.result is None:
            import time
            t0 = time.perf_counter()
            cls.result = skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, progress=cls.progress.append)
            cls.seconds = time.perf_counter() - t0
            print(f"\n  pipeline on assets/examples/sketch.png: {cls.seconds:.1f} s", end=" ", file=sys.stderr)
        return cls.result


class LibraryTest(unittest.TestCase):
    def test_version_matches_cargo_toml_and_header(self):
        with open(os.path.join(ROOT, "Cargo.toml"), "rb") as f:
            version = tomllib.load(f)["package"]["version"]
        self.assertEqual(skb.version(), version)
        self.assertEqual(skb.__version__, version)
        self.assertTrue(os.path.exists(skb.library_path()) or skb.library_path().startswith("libsketchbody"))

    def test_status_enum_and_text(self):
        self.assertEqual(skb.Status.SKB_OK, 0)
        self.assertEqual(skb.Status.SKB_ERR_IO, 11)
        self.assertEqual(skb.status_text(1), "a required pointer argument was NULL")
        self.assertEqual(skb.status_text(9999), "unknown status")

    def test_missing_library_gives_an_install_hint(self):
        env = dict(os.environ, SKETCHBODY_LIBRARY="/nonexistent/libsketchbody.so")
        r = subprocess.run([sys.executable, "-c", "try:\n import sketchbody\nexcept ImportError as e:\n"
                            " print(type(e).__name__); print(e)\n"], env=env, capture_output=True, text=True,
                           cwd=os.path.dirname(os.path.abspath(__file__)))
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("LibraryNotFoundError", r.stdout)
        self.assertIn("/nonexistent/libsketchbody.so", r.stdout)
        self.assertIn("pip install ./python", r.stdout)


class ImageTest(unittest.TestCase):
    def test_load_image_round_trip(self):
        w, h = 37, 21
        px = test_card(w, h)
        with tempfile.TemporaryDirectory() as tmp:
            p = os.path.join(tmp, "card.png")
            write_gray_png(p, w, h, px)
            img = skb.load_image(p)
        self.assertEqual(img.shape, (h, w))
        self.assertEqual(img.dtype, np.uint8)
        np.testing.assert_array_equal(img, np.array(px, dtype=np.uint8).reshape(h, w))

    def test_canny_matches_rust_cli(self):
        w, h = 97, 64
        px = np.array(test_card(w, h), dtype=np.uint8).reshape(h, w)
        ours = skb.canny(px, 30, 90)
        self.assertEqual(ours.shape, (h, w))
        self.assertTrue(ours.any())
        self.assertTrue(set(np.unique(ours)) <= {0, 255})
        if not os.path.exists(CLI):
            self.skipTest(f"SKIPPED: {CLI} not built")
        with tempfile.TemporaryDirectory() as tmp:
            src, dst = os.path.join(tmp, "in.png"), os.path.join(tmp, "edges.png")
            write_gray_png(src, w, h, px.reshape(-1).tolist())
            subprocess.run([CLI, "edges", src, dst, "--low", "30", "--high", "90"], check=True)
            rw, rh, rust = read_gray_png(dst)
        np.testing.assert_array_equal(ours, np.array(rust, dtype=np.uint8).reshape(rh, rw))

    def test_colour_and_strided_images(self):
        w, h = 64, 48
        gray = np.array(test_card(w, h), dtype=np.uint8).reshape(h, w)
        rgb = np.repeat(gray[:, :, None], 3, axis=2)
        np.testing.assert_array_equal(skb.canny(rgb), skb.canny(gray))
        rgba = np.concatenate([rgb, np.full((h, w, 1), 7, np.uint8)], axis=2)
        np.testing.assert_array_equal(skb.canny(rgba), skb.canny(gray))
        wide = np.repeat(gray, 2, axis=1)           # every other column is the card again
        view = wide[:, ::2]                          # not C-contiguous: copied, not misread
        self.assertFalse(view.flags["C_CONTIGUOUS"])
        np.testing.assert_array_equal(skb.canny(view), skb.canny(gray))
        np.testing.assert_array_equal(skb.canny(np.asfortranarray(gray)), skb.canny(gray))

    def test_gaussian_blur(self):
        img = np.zeros((33, 33), np.uint8)
        img[16, 16] = 255
        out = skb.gaussian_blur(img, 2.0)
        self.assertEqual(out.shape, img.shape)
        self.assertEqual(np.unravel_index(out.argmax(), out.shape), (16, 16))
        np.testing.assert_array_equal(out, out.T)
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.gaussian_blur(img, -1.0)
        self.assertEqual(cm.exception.status_name, "SKB_ERR_OUT_OF_RANGE")

    def test_bad_images(self):
        with self.assertRaises(TypeError):
            skb.canny(None)
        with self.assertRaises(TypeError):
            skb.canny(np.zeros((8, 8), np.float32))
        with self.assertRaises(TypeError):
            skb.canny([[0, 1], [2, 3]])
        with self.assertRaises(ValueError):
            skb.canny(np.zeros((8, 8, 2), np.uint8))
        with self.assertRaises(ValueError):
            skb.canny(np.zeros((0, 8), np.uint8))
        with self.assertRaises(ValueError):
            skb.canny(np.zeros(8, np.uint8))
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.canny(np.zeros((8, 8), np.uint8), aperture=4)
        self.assertEqual(cm.exception.status, skb.Status.SKB_ERR_INVALID_APERTURE)

    def test_bad_files(self):
        with tempfile.TemporaryDirectory() as tmp:
            missing = os.path.join(tmp, "missing.png")
            with self.assertRaises(skb.SketchbodyError) as cm:
                skb.load_image(missing)
            e = cm.exception
            self.assertEqual((e.status, e.status_name), (11, "SKB_ERR_IO"))
            self.assertIn("missing.png", e.message)
            self.assertIn("SKB_ERR_IO", str(e))
            garbage = os.path.join(tmp, "garbage.png")
            with open(garbage, "wb") as f:
                f.write(b"\x89PNG\r\n\x1a\nnot really a png")
            with self.assertRaises(skb.SketchbodyError) as cm:
                skb.run_pipeline(garbage, joints=SKETCH_JOINTS)
            self.assertEqual(cm.exception.status_name, "SKB_ERR_DECODE")
        with self.assertRaises(TypeError):
            skb.load_image(None)
        with self.assertRaises(TypeError):
            skb.load_image(42)
        with self.assertRaises(ValueError):
            skb.load_image("a\0b.png")


class PipelineTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.r = Example.get()
        cls.joints = skb.Joints2D.from_json(SKETCH_JOINTS)

    def test_shapes_and_values(self):
        r = self.r
        self.assertEqual((r.vertex_count, r.face_count), (NV, NF))
        v = r.vertices()
        self.assertEqual((v.shape, v.dtype), ((NV, 3), np.float32))
        self.assertTrue(np.isfinite(v).all())
        rest = r.vertices(posed=False)
        self.assertEqual(rest.shape, (NV, 3))
        height = rest[:, 1].max() - rest[:, 1].min()
        self.assertTrue(1.0 < height < 2.3, height)
        f = r.faces()
        self.assertEqual((f.shape, f.dtype), ((NF, 4), np.uint32))
        self.assertLess(int(f.max()), NV)
        bones, weights = r.skin_weights()
        self.assertEqual((bones.shape, weights.shape), ((NV, 4), (NV, 4)))
        self.assertLess(int(bones.max()), 14)
        np.testing.assert_allclose(weights.sum(axis=1), 1.0, atol=1e-5)
        self.assertIn(r.gender, ("female", "male"))
        value, conf = r.gender_value()
        self.assertTrue(0 <= value <= 1 and 0.5 <= conf <= 1)
        self.assertTrue(np.isfinite(r.score))
        low, support = r.evidence()
        self.assertIsInstance(low, bool)
        parts = r.part_support()
        self.assertEqual(tuple(parts), r.BODY_PARTS)
        seen = [v for v in parts.values() if v is not None]
        self.assertIsNotNone(parts["torso"])
        self.assertTrue(all(0 <= v <= 1 for v in seen))
        self.assertLessEqual(min(seen), support + 1e-9)
        self.assertGreaterEqual(max(seen), support - 1e-9)
        self.assertGreater(len(r.shape_weights()), 0)

    def test_interim_bodies_come_first_and_the_result_is_the_same(self):
        fast = skb.FitOptions(samples=24, iterations=2)
        seen = []
        r = skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, fit_options=fast,
                             interim=lambda stage, v: seen.append((stage, v)))
        plain = skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, fit_options=fast)
        np.testing.assert_array_equal(r.vertices(), plain.vertices())
        self.assertEqual([s for s, _ in seen], ["mean_shape", "deciding_fit"])
        for _, v in seen:
            self.assertEqual((v.shape, v.dtype), ((NV, 3), np.float32))
            self.assertFalse(np.array_equal(v, r.vertices()))

    def test_an_interim_exception_cancels_and_is_raised(self):
        def boom(stage, v):
            raise ValueError(f"stop at {stage}")
        with self.assertRaisesRegex(ValueError, "stop at mean_shape"):
            skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, fit_options=skb.FitOptions(samples=24, iterations=2),
                             interim=boom)

    def test_detection_of_given_and_detected_joints(self):
        # Given joints: no detection behind them.
        self.assertIsNone(self.r.detection())
        self.assertIsNone(self.r.facing())
        self.assertFalse(self.r.detected)
        # No joints: the library detects them as the CLI's `run` does, and says so.
        with skb.run_pipeline(SKETCH, fit_options=skb.FitOptions(samples=8, iterations=1)) as r:
            info = r.detection()
            facing = r.facing()
            self.assertTrue(r.detected)
            used = r.joints2d().xy
        self.assertIsInstance(info, skb.FigureInfo)
        det = skb.detect(SKETCH)
        self.assertEqual(info.backend, det.backend)
        self.assertAlmostEqual(info.confidence, det.score, places=9)
        self.assertEqual(info.low_confidence, info.confidence < 0.75)
        self.assertTrue(0.5 <= info.presence <= 1.0)
        np.testing.assert_allclose(used, det.joints.xy, atol=1e-9)
        # The result's facing is the detection's: the same decision and probabilities.
        self.assertIsInstance(facing, skb.Facing)
        self.assertEqual(facing.facing, det.facing.facing)
        self.assertEqual(facing.probabilities, det.facing.probabilities)
        np.testing.assert_allclose(facing.alternative.xy, det.facing.alternative.xy, atol=1e-9)

    def test_progress_is_monotonic_and_ends_at_one(self):
        p = Example.progress
        self.assertGreater(len(p), 3)
        self.assertEqual(p, sorted(p))
        self.assertAlmostEqual(p[-1], 1.0, places=5)

    def test_joints_and_camera(self):
        r = self.r
        used = r.joints2d()
        np.testing.assert_allclose(used.xy, self.joints.xy)
        np.testing.assert_array_equal(used.visible, self.joints.visible)
        cam = r.camera()
        self.assertEqual(cam.r.shape, (3, 3))
        np.testing.assert_allclose(cam.r @ cam.r.T, np.eye(3), atol=1e-9)
        posed = r.joints3d("posed")
        # The posed joints project near the 2-D joints the pipeline was given.
        err = np.linalg.norm(cam.project(posed) - self.joints.xy, axis=1)
        self.assertLess(np.median(err), 25.0, err)
        for which in ("rest", "estimated"):
            self.assertEqual(r.joints3d(which).shape, (15, 3))
        with self.assertRaises(ValueError):
            r.joints3d("bent")

    def test_result_mesh_matches_result(self):
        r = self.r
        with r.mesh() as m:
            np.testing.assert_array_equal(m.vertices(posed=True), r.vertices())
            np.testing.assert_array_equal(m.vertices(posed=False), r.vertices(posed=False))
            np.testing.assert_array_equal(m.faces(), r.faces())
            np.testing.assert_array_equal(m.joints(posed=True), r.joints3d("posed"))
            for a, b in zip(m.skin_weights(), r.skin_weights()):
                np.testing.assert_array_equal(a, b)
            np.testing.assert_array_equal(m.shape_weights(), r.shape_weights())
            self.assertEqual(m.gender, r.gender)
            q, t = m.faces(), m.triangles()
            self.assertEqual(t.shape, (2 * NF, 3))
            np.testing.assert_array_equal(t[0::2], q[:, [0, 1, 2]])
            np.testing.assert_array_equal(t[1::2], q[:, [0, 2, 3]])
            n = m.normals(posed=True)
            np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-4)
            uv, fuv = m.uvs(), m.face_uvs()
            self.assertGreater(len(uv), NV)
            self.assertTrue(((uv >= -1e-6) & (uv <= 1 + 1e-6)).all())
            self.assertEqual(fuv.shape, (NF, 4))
            self.assertLess(int(fuv.max()), len(uv))

    def test_rig(self):
        with self.r.mesh() as m:
            rig = m.rig()
            posed_joints = m.joints(posed=True)
        self.assertEqual(len(rig.bone_names), skb.NUM_RIG_BONES)
        self.assertEqual(len(set(rig.bone_names)), 53)
        self.assertIn("pelvis", rig.bone_names)
        p = rig.parents
        self.assertEqual((p.shape, p.dtype), ((53,), np.int32))
        self.assertEqual(p[0], -1)
        self.assertTrue(all(0 <= p[b] < b for b in range(1, 53)), "parents come first: a tree rooted at 0")
        np.testing.assert_allclose(np.linalg.norm(rig.rest_rotations, axis=1), 1, atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(rig.local_rotations, axis=1), 1, atol=1e-9)
        # Forward kinematics rebuilt in numpy from the rest translations, local rotations and
        # root translation equals the library's posed heads.
        g = rig.posed_global_transforms()
        np.testing.assert_allclose(g[:, :3, 3], rig.posed_heads, atol=1e-6)
        # Linear blend skinning of the rest vertices with the 53-bone weights, in numpy, equals
        # skb_rig_copy_posed_vertices.
        rest_g = np.zeros((53, 4, 4))
        for b in range(53):
            mat = np.eye(4)
            mat[:3, :3] = skb.quat_to_matrix(rig.rest_rotations[b])
            mat[:3, 3] = rig.rest_translations[b]
            rest_g[b] = mat if p[b] < 0 else rest_g[p[b]] @ mat
        skin = g @ np.linalg.inv(rest_g)
        v = np.concatenate([rig.rest_vertices.astype(np.float64), np.ones((NV, 1))], axis=1)
        posed = np.zeros((NV, 3))
        for k in range(4):
            posed += rig.skin_weights[:, k:k + 1] * np.einsum("nij,nj->ni", skin[rig.skin_bones[:, k]], v)[:, :3]
        np.testing.assert_allclose(posed, rig.posed_vertices, atol=2e-4)
        # The joint-named bones against the mesh's posed joints. For the pipeline's pose they
        # agree only up to a placement (the rig stands on the floor) and within a few cm: after
        # the best rigid alignment 3.4 cm at the pelvis, measured 2026-12-03, because the rig's
        # rotations do not reproduce skb_mesh_pose exactly for large poses (reported in
        # docs/python.md). A mild pose agrees exactly (MeshTest.test_rig_matches_mild_pose).
        b = [rig.bone_names.index(n) for n in skb.JOINT_NAMES[1:]]
        heads = g[b, :3, 3]
        r, t = rigid_fit(posed_joints[1:], heads)
        residual = np.linalg.norm(posed_joints[1:] @ r.T + t - heads, axis=1)
        self.assertLess(residual.max(), 0.05, dict(zip(skb.JOINT_NAMES[1:], residual.round(4))))

    def test_rig_options(self):
        with self.r.mesh() as m:
            mix = m.rig(skb.ExportOptions(naming="mixamo", rest_pose="t", origin="pelvis"))
            with self.assertRaises(ValueError):
                m.rig(skb.ExportOptions(naming="blender"))
            with self.assertRaises(TypeError):
                m.rig({"naming": "mixamo"})
        self.assertTrue(all(n.startswith("mixamorig:") for n in mix.bone_names[1:]), mix.bone_names[:3])
        np.testing.assert_allclose(mix.root_translation, 0, atol=1e-12)

    def test_rig_an_animator_keeps(self):
        """Twist bones, IK targets, the pose as the rest and shape keys (issue 49)."""
        opts = skb.ExportOptions(naming="unreal", twist_bones=True, ik_targets=True, pose_as="rest", shape_keys=True)
        with self.r.mesh() as m:
            rig = m.rig(opts)
            action = m.rig(skb.ExportOptions(naming="unreal"))
            n = len(m.shape_weights())
            with self.assertRaises(ValueError):
                m.rig(skb.ExportOptions(pose_as="keyed"))
        b = skb._bindings
        nb = b.SKB_NUM_RIG_BONES + b.SKB_NUM_TWIST_BONES + b.SKB_NUM_IK_BONES
        self.assertEqual((len(rig.bone_names), len(rig.parents)), (nb, nb))
        self.assertEqual(rig.bone_names[rig.parents[rig.bone_names.index("upperarm_twist_01_l")]], "upperarm_l")
        self.assertEqual(rig.bone_names[rig.parents[rig.bone_names.index("ik_hand_r")]], "ik_hand_gun")
        # The pose as the rest: the rest vertices are the action's posed body.
        np.testing.assert_allclose(rig.rest_vertices, action.posed_vertices, atol=1e-4)
        np.testing.assert_allclose(rig.posed_vertices, action.posed_vertices, atol=1e-4)
        # One key per fitted shape weight.
        self.assertGreater(n, 0)
        self.assertEqual(sorted(rig.shape_keys), [f"shape_{k:02d}" for k in range(1, n + 1)])
        self.assertTrue(all(d.shape == (NV, 3) and np.abs(d).max() > 1e-3 for d in rig.shape_keys.values()))
        self.assertEqual(action.shape_keys, {})

    def test_export(self):
        with self.r.mesh() as m, tempfile.TemporaryDirectory() as tmp:
            glb, obj, png = (os.path.join(tmp, n) for n in ("b.glb", "b.obj", "p.png"))
            m.write_glb(glb, skb.ExportOptions(naming="unreal"))
            m.write_obj(obj)
            m.write_preview(png, 64)
            with open(glb, "rb") as f:
                magic, version, length = struct.unpack("<4sII", f.read(12))
            self.assertEqual((magic, version, length), (b"glTF", 2, os.path.getsize(glb)))
            with open(obj) as f:
                lines = f.read().splitlines()
            self.assertEqual(sum(line.startswith("v ") for line in lines), NV)
            with open(png, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
            with self.assertRaises(skb.SketchbodyError) as cm:
                m.write_obj(os.path.join(tmp, "no", "such", "dir", "x.obj"))
            self.assertEqual(cm.exception.status_name, "SKB_ERR_IO")

    def test_estimated_pose_matches_pose_solver(self):
        pose = skb.estimate_pose(self.joints)
        self.assertEqual(pose.joints.shape, (15, 3))
        self.assertTrue(np.isfinite(pose.joints).all())
        self.assertLess(pose.rms_px, 20)
        self.assertEqual(set(pose.proportions), set(skb.PROPORTION_GROUPS))
        est = self.r.joints3d("estimated")
        # The pipeline's pose step is skb_pose3d_estimate with the same defaults.
        np.testing.assert_allclose(pose.joints - pose.joints[8], est - est[8], atol=0.05)


class PoseTest(unittest.TestCase):
    def test_dictionary(self):
        with skb.PoseDictionary() as d:
            self.assertGreater(d.num_bases, 0)
            self.assertEqual(d.mean().shape, (15, 3))
            b, sigma = d.basis(0)
            self.assertAlmostEqual(float(np.linalg.norm(b)), 1.0, places=6)
            self.assertGreater(sigma, 0)
            self.assertEqual(d.bone_lengths().shape, (14,))
            with self.assertRaises(skb.SketchbodyError):
                d.basis(d.num_bases)
        with self.assertRaises(ValueError):
            d.mean()                                  # closed
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.PoseDictionary("/nonexistent.skbpd")
        self.assertEqual(cm.exception.status_name, "SKB_ERR_IO")

    def test_options_and_refine(self):
        j = skb.Joints2D.from_json(SKETCH_JOINTS)
        opts = skb.PoseOptions(proportions=False, alpha_target="identity", starts=2, max_bases=3)
        pose = skb.estimate_pose(j.xy, opts)
        again = skb.refine_pose(j, pose, opts)
        self.assertLessEqual(again.rms_px, pose.rms_px + 1e-6)
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.estimate_pose(j, skb.PoseOptions(alpha=2.0))
        self.assertEqual(cm.exception.status_name, "SKB_ERR_OUT_OF_RANGE")
        self.assertIn("alpha", cm.exception.message.lower())
        with self.assertRaises(TypeError):
            skb.PoseOptions(alpha="high").handle()
        with self.assertRaises(ValueError):
            skb.estimate_pose(j, skb.PoseOptions(alpha_target="up"))

    def test_straight_limbs_straighten_the_example(self):
        j = skb.Joints2D.from_json(SKETCH_JOINTS)

        def bends(x):
            out = []
            for a, b, c in ((2, 3, 4), (5, 6, 7), (9, 10, 11), (12, 13, 14)):
                u, v = x[b] - x[a], x[c] - x[b]
                cos = np.dot(u, v) / (np.linalg.norm(u) * np.linalg.norm(v))
                out.append(float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))))
            return out

        # By default the knees come out near straight (issue 46's uncertain bone lengths: 10.5° /
        # 10.9°, not the 37.6° of a solve that keeps the lengths); straight_limbs makes every limb
        # straight to within 10°.
        default = bends(skb.estimate_pose(j).joints)
        self.assertLess(max(default[2:]), 15.0, default)
        straight = bends(skb.estimate_pose(j, skb.PoseOptions(straight_limbs=True)).joints)
        self.assertLessEqual(max(straight), 10.0, straight)

    def test_bad_joints(self):
        with self.assertRaises(TypeError):
            skb.estimate_pose(None)
        with self.assertRaises(ValueError):
            skb.estimate_pose(np.zeros((14, 2)))
        with self.assertRaises(TypeError):
            skb.estimate_pose(np.array([["a", "b"]] * 15))
        with self.assertRaises(ValueError):
            skb.Joints2D.from_dict({"head": (1, 2)})
        xy = skb.Joints2D.from_json(SKETCH_JOINTS).xy.copy()
        xy[3] = np.nan
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.estimate_pose(xy)
        self.assertEqual(cm.exception.status_name, "SKB_ERR_TOO_FEW_JOINTS")
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.estimate_pose(np.zeros((15, 2)))
        self.assertIn(cm.exception.status_name, ("SKB_ERR_COINCIDENT_JOINTS", "SKB_ERR_DEGENERATE"))

    def test_joints_json_round_trip(self):
        j = skb.Joints2D.from_json(SKETCH_JOINTS)
        j.visible[4] = False
        with tempfile.TemporaryDirectory() as tmp:
            p = os.path.join(tmp, "j.json")
            j.to_json(p)
            k = skb.Joints2D.from_json(p)
            with open(p) as f:
                self.assertEqual(json.load(f)["missing"], ["r_wrist"])
        np.testing.assert_array_equal(k.xy, j.xy)
        np.testing.assert_array_equal(k.visible, j.visible)


class JointsFileTest(unittest.TestCase):
    """Issue 52 finding 4: the package reads joints files through the library's reader, with the
    CLI's guards (it used to hang on a FIFO, read /dev/zero until MemoryError, accept 100 MB files,
    NaN literals and a key given twice)."""

    def read_in_thread(self, path):
        """Joints2D.from_json(path) on a worker thread: its exception, or None; fails if the call
        has not returned after a minute (it blocked)."""
        box = []

        def work():
            try:
                skb.Joints2D.from_json(path)
                box.append(None)
            except Exception as e:  # the test inspects it
                box.append(e)

        t = threading.Thread(target=work, daemon=True)
        t.start()
        t.join(60)
        self.assertFalse(t.is_alive(), f"Joints2D.from_json({path!r}) blocked")
        return box[0]

    def test_special_and_oversized_files_are_refused(self):
        with tempfile.TemporaryDirectory() as tmp:
            fifo = os.path.join(tmp, "fifo")
            os.mkfifo(fifo)
            big = os.path.join(tmp, "big.json")
            with open(big, "wb") as f:
                f.write(b" " * (2 << 20))
            for path in (fifo, "/dev/zero", big, tmp):
                e = self.read_in_thread(path)
                self.assertIsInstance(e, skb.SketchbodyError, path)
                self.assertEqual(e.status_name, "SKB_ERR_IO", path)
            with self.assertRaises(skb.SketchbodyError) as cm:
                skb.run_pipeline(SKETCH, joints=fifo)
            self.assertEqual(cm.exception.status_name, "SKB_ERR_IO")

    def test_strict_json(self):
        with open(SKETCH_JOINTS, encoding="utf-8") as f:
            text = f.read()
        good = skb.Joints2D.from_json(SKETCH_JOINTS)
        np.testing.assert_array_equal(skb.Joints2D.from_json_text("\ufeff" + text).xy, good.xy)
        x = float(good.xy[0][0])
        cases = {
            "NaN literal": text.replace(json.dumps(x), "NaN", 1),
            "key twice": text.replace('"head":', '"head": [1, 2], "head":', 1),
            "unknown joint": text.replace('"head":', '"tail": [1, 2], "head":', 1),
        }
        self.assertNotEqual(cases["NaN literal"], text)
        with tempfile.TemporaryDirectory() as tmp:
            for what, doc in cases.items():
                p = os.path.join(tmp, "j.json")
                with open(p, "w", encoding="utf-8") as f:
                    f.write(doc)
                for read in (lambda: skb.Joints2D.from_json(p), lambda: skb.Joints2D.from_json_text(doc)):
                    with self.assertRaises(skb.SketchbodyError, msg=what) as cm:
                        read()
                    self.assertEqual(cm.exception.status_name, "SKB_ERR_CORRUPT_DATA", what)
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.Joints2D.from_json_text(b" " * ((1 << 20) + 1))
        self.assertEqual(cm.exception.status_name, "SKB_ERR_OUT_OF_RANGE")
        bad = skb.Joints2D(good.xy.copy())
        bad.xy[2, 1] = np.inf
        with tempfile.TemporaryDirectory() as tmp:
            with self.assertRaises(skb.SketchbodyError) as cm:
                bad.to_json(os.path.join(tmp, "j.json"))
            self.assertEqual(cm.exception.status_name, "SKB_ERR_NON_FINITE")
            self.assertEqual(os.listdir(tmp), [])


class DetectTest(unittest.TestCase):
    def test_detect_example(self):
        d = skb.detect(SKETCH)
        self.assertEqual(d.joints.xy.shape, (15, 2))
        self.assertTrue(((d.confidence > 0) & (d.confidence < 1)).all())
        self.assertAlmostEqual(d.score, float(d.confidence.mean()), places=12)
        self.assertIn(d.backend, ("fmp", "blazepose"))
        self.assertEqual(d.low_confidence, d.score < 0.75)
        self.assertGreaterEqual(d.presence, 0.5)
        truth = skb.Joints2D.from_json(SKETCH_JOINTS).xy
        self.assertLess(np.median(np.linalg.norm(d.joints.xy - truth, axis=1)), 20)
        for backend in ("fmp", "blazepose"):
            b = skb.detect(SKETCH, skb.DetectOptions(backend=backend))
            self.assertEqual(b.backend, backend)
            self.assertLess(np.median(np.linalg.norm(b.joints.xy - truth, axis=1)), 20)
        with self.assertRaises(ValueError):
            skb.DetectOptions(backend="openpose").handle()

    def test_facing_and_the_swapped_labelling(self):
        # The example faces the viewer (a faceless outline): the front's labelling, the
        # character's right shoulder on the image's left; the alternative is the same joints with
        # left and right swapped, less likely than the reported ones.
        d = skb.detect(SKETCH)
        f = d.facing
        self.assertIn(f.facing, ("front", "back", "left", "right", "unknown"))
        self.assertEqual(set(f.probabilities), {"front", "back", "left", "right"})
        self.assertAlmostEqual(sum(f.probabilities.values()), 1.0, places=9)
        self.assertNotEqual(f.facing, "back")
        names = list(skb.JOINT_NAMES)
        xy = d.joints.xy
        self.assertLess(xy[names.index("r_shoulder")][0], xy[names.index("l_shoulder")][0])
        alt = f.alternative.xy
        np.testing.assert_array_equal(alt[names.index("r_wrist")], xy[names.index("l_wrist")])
        np.testing.assert_array_equal(alt[names.index("head")], xy[names.index("head")])
        self.assertLess(f.alternative_score, 0.5)
        # Joints2D.swap_sides is the same swap, and twice is the identity.
        np.testing.assert_array_equal(d.joints.swap_sides().xy, alt)
        np.testing.assert_array_equal(d.joints.swap_sides().swap_sides().xy, xy)

    def test_detect_errors(self):
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.detect(np.full((16, 16), 255, np.uint8))
        self.assertEqual(cm.exception.status_name, "SKB_ERR_IMAGE_TOO_SMALL")
        with self.assertRaises(skb.NoFigure):
            skb.detect(np.full((64, 64), 255, np.uint8), skb.DetectOptions(levels_per_octave=3))
        with self.assertRaises(skb.NoFigure):
            skb.detect(np.full((64, 64), 255, np.uint8), skb.DetectOptions(backend="fmp", strict=True, threshold=1e6))
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.DetectOptions(figure_range=(0.9, 0.1)).handle()
        self.assertEqual(cm.exception.status_name, "SKB_ERR_OUT_OF_RANGE")
        with self.assertRaises(TypeError):
            skb.DetectOptions(scales=4.0).handle()
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.Detector("/nonexistent.skbd")
        self.assertEqual(cm.exception.status_name, "SKB_ERR_IO")


class MeshTest(unittest.TestCase):
    def test_shape_pose_and_errors(self):
        ctx = skb.default_context()
        n = ctx.num_components("female")
        self.assertGreater(n, 0)
        self.assertLessEqual(ctx.default_dim("male"), ctx.num_components("male"))
        with skb.Mesh.from_shape("female") as m, skb.Mesh.from_shape("f", np.zeros(3)) as same:
            self.assertEqual(m.gender, "female")
            self.assertEqual((m.vertex_count, m.face_count), (NV, NF))
            np.testing.assert_array_equal(m.vertices(), same.vertices())
            rest = m.joints()
            target = rest.copy()
            target[4] += [0.0, 0.3, 0.1]             # raise the right wrist
            m.pose(target)
            self.assertFalse(np.allclose(m.vertices(posed=True), m.vertices()))
            before = m.vertices(posed=True)
            bad = target.copy()
            bad[0, 0] = np.inf
            with self.assertRaises(skb.SketchbodyError) as cm:
                m.pose(bad)
            self.assertEqual(cm.exception.status_name, "SKB_ERR_NON_FINITE")
            np.testing.assert_array_equal(m.vertices(posed=True), before)   # unchanged on error
            with self.assertRaises(ValueError):
                m.pose(target[:14])
            with self.assertRaises(TypeError):
                m.pose(None)
            cam = skb.Camera(200.0, 200.0, np.eye(3), [64.0, 200.0])
            mask = m.rasterize(cam, 128, 400)
            self.assertEqual(mask.shape, (400, 128))
            self.assertTrue(mask.any())
            with self.assertRaises(TypeError):
                m.rasterize("camera", 10, 10)
        with self.assertRaises(ValueError):
            m.vertices()                              # closed
        m.close()                                     # idempotent
        with self.assertRaises(ValueError):
            skb.Mesh.from_shape("other")
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.Mesh.from_shape("male", np.zeros(n + 1000))
        self.assertEqual(cm.exception.status_name, "SKB_ERR_OUT_OF_RANGE")
        with self.assertRaises(TypeError):
            skb.Mesh.from_shape("male", "0,1")

    def test_rig_matches_mild_pose(self):
        # As cpp_tests/capi_rig_test.c: a mild pose, the joint-named bones (all but the head)
        # start on skb_mesh_pose's joints moved to the export frame.
        with skb.Mesh.from_shape("female") as m:
            target = m.joints()
            target[4] += [0.0, 0.3, 0.1]
            m.pose(target)
            posed, rig = m.joints(posed=True), m.rig()
        g = rig.posed_global_transforms()
        for j, name in enumerate(skb.JOINT_NAMES[1:], start=1):
            b = rig.bone_names.index(name)
            np.testing.assert_allclose(g[b, :3, 3], posed[j] + rig.offset + rig.root_translation, atol=1e-9,
                                       err_msg=name)

    def test_threads_share_one_mesh(self):
        with skb.Mesh.from_shape("male") as m:
            out, errors = [], []

            def work():
                try:
                    for _ in range(5):
                        out.append(float(m.vertices(posed=True).sum()))
                except Exception as e:  # noqa: BLE001
                    errors.append(e)

            ts = [threading.Thread(target=work) for _ in range(4)]
            for t in ts:
                t.start()
            for t in ts:
                t.join()
        self.assertEqual(errors, [])
        self.assertEqual(len(set(out)), 1)


class CancelAndOptionsTest(unittest.TestCase):
    def test_cancel_by_progress(self):
        calls = []

        def stop(f):
            calls.append(f)
            return False

        with self.assertRaises(skb.Cancelled) as cm:
            skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, progress=stop)
        self.assertEqual(cm.exception.status, skb.Status.SKB_ERR_CANCELLED)
        self.assertEqual(len(calls), 1)

    def test_cancel_event_and_callback_exception(self):
        ev = threading.Event()
        ev.set()
        with self.assertRaises(skb.Cancelled):
            skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, cancel=ev)

        def boom(f):
            raise KeyError("from the callback")

        with self.assertRaises(KeyError):
            skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, progress=boom)
        with self.assertRaises(TypeError):
            skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, progress=3)
        with self.assertRaises(TypeError):
            skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, cancel=True)

    def test_fit_options_are_checked(self):
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, fit_options=skb.FitOptions(samples=1))
        self.assertEqual(cm.exception.status_name, "SKB_ERR_OUT_OF_RANGE")
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.FitOptions(height=float("nan")).handle()
        self.assertEqual(cm.exception.status_name, "SKB_ERR_NON_FINITE")
        with self.assertRaises(TypeError):
            skb.FitOptions(samples="many").handle()
        with self.assertRaises(ValueError):
            skb.FitOptions(gender="x").handle()
        with self.assertRaises(TypeError):
            skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, fit_options={"samples": 3})
        h = skb.FitOptions(gender="m", height=1.8, skinning="dual_quaternion", score="paper").handle()
        skb.FitOptions().free_handle(h)

    def test_bad_pipeline_inputs(self):
        with self.assertRaises(TypeError):
            skb.run_pipeline(None)
        with self.assertRaises(TypeError):
            skb.run_pipeline(np.zeros((64, 64), np.float64), joints=SKETCH_JOINTS)
        with self.assertRaises(ValueError):
            skb.run_pipeline(SKETCH, joints=np.zeros(29))
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.run_pipeline(np.full((16, 16), 255, np.uint8), joints=np.zeros((15, 2)))
        self.assertEqual(cm.exception.status_name, "SKB_ERR_IMAGE_TOO_SMALL")
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.run_pipeline(np.full((64, 64), 255, np.uint8), joints=np.full((15, 2), 10.0))
        self.assertEqual(cm.exception.status_name, "SKB_ERR_BLANK_IMAGE")

    def test_small_fit_runs(self):
        # A quick fit from the pose step through fit_shape (the pipeline's pieces by hand).
        j = skb.Joints2D.from_json(SKETCH_JOINTS)
        pose = skb.estimate_pose(j)
        edges = skb.canny(SKETCH)
        mesh, score = skb.fit_shape(pose.joints, pose.camera, edges,
                                    skb.FitOptions(samples=8, iterations=1, gender="female"))
        with mesh:
            self.assertEqual(mesh.gender, "female")
            self.assertTrue(np.isfinite(score))
            self.assertEqual(mesh.vertices(posed=True).shape, (NV, 3))


class TextureTest(unittest.TestCase):
    """The CLI's textured result and its cm / Z-up FBX and USD, reproduced through the package:
    `sketchbody run` with a small fit, then the same job here (colour sketch, the same fit
    settings): Result.texture written by write_png is the CLI's body_texture.png byte for byte,
    Mesh.texture with the result's mesh and camera the same pixels, Mesh.write_usd with
    ExportOptions(units="cm", up_axis="z", twist_bones=True, shape_keys=True) (the CLI's
    defaults) the CLI's points, metadata, bind transforms and shape keys."""

    SIZE = 128

    @classmethod
    def setUpClass(cls):
        if not os.path.exists(CLI):
            raise unittest.SkipTest(f"SKIPPED: {CLI} not built")
        cls.tmp = tempfile.TemporaryDirectory()
        cls.out = os.path.join(cls.tmp.name, "cli")
        fast = ["--samples", "24", "--iterations", "2", "--quiet", "--preview-size=128"]
        subprocess.run([CLI, "run", SKETCH, "--joints", SKETCH_JOINTS, "--gender", "m", "--out", cls.out, *fast,
                        "--texture-size", str(cls.SIZE), "--format", "usd", "--units", "cm", "--up", "z"], check=True)
        cls.sketch = skb.load_rgb_image(SKETCH)
        cls.r = skb.run_pipeline(cls.sketch, joints=SKETCH_JOINTS,
                                 fit_options=skb.FitOptions(samples=24, iterations=2, gender="male"))

    @classmethod
    def tearDownClass(cls):
        cls.r.close()
        cls.tmp.cleanup()

    def test_texture_is_the_cli_texture(self):
        self.assertEqual(self.sketch.ndim, 3)
        tex = self.r.texture(SKETCH, self.SIZE)
        self.assertEqual((tex.shape, tex.dtype), ((self.SIZE, self.SIZE, 3), np.uint8))
        np.testing.assert_array_equal(tex, self.r.texture(self.sketch, self.SIZE))
        png = os.path.join(self.tmp.name, "t.png")
        skb.write_png(tex, png)
        with open(png, "rb") as a, open(os.path.join(self.out, "body_texture.png"), "rb") as b:
            self.assertEqual(a.read(), b.read(), "body_texture.png differs from the CLI's")
        grey = np.all(tex == 190, axis=2).mean()
        self.assertTrue(0.05 < grey < 0.95, grey)
        np.testing.assert_array_equal(skb.load_rgb_image(png), tex)
        with self.r.mesh() as m:
            np.testing.assert_array_equal(m.texture(self.sketch, self.r.camera(), self.SIZE), tex)

    def test_units_and_up_axis(self):
        usd = os.path.join(self.tmp.name, "c.usda")
        with self.r.mesh() as m:
            # The CLI's defaults: twist bones and shape keys on (the C API's are off).
            m.write_usd(usd, skb.ExportOptions(units="cm", up_axis="z", twist_bones=True, shape_keys=True))
            fbx = os.path.join(self.tmp.name, "c.fbx")
            m.write_fbx(fbx, skb.ExportOptions(units="cm", up_axis="z"))
            with open(fbx, "rb") as f:
                self.assertEqual(f.read(18), b"Kaydara FBX Binary")
            with self.assertRaises(ValueError) as cm:
                m.write_usd(usd, skb.ExportOptions(units="km"))
            self.assertIn("units", str(cm.exception))
            with self.assertRaises(ValueError):
                m.write_fbx(fbx, skb.ExportOptions(up_axis="x"))
            with self.assertRaises(skb.SketchbodyError) as cm:
                m.write_usd(os.path.join(self.tmp.name, "no", "such", "x.usda"))
            self.assertEqual(cm.exception.status_name, "SKB_ERR_IO")
        with open(usd) as f:
            ours = f.read().splitlines()
        with open(os.path.join(self.out, "body.usda")) as f:
            cli = f.read().splitlines()
        self.assertIn("    metersPerUnit = 0.01", ours)
        self.assertIn('    upAxis = "Z"', ours)
        line = lambda lines, key: next(x for x in lines if key in x)  # noqa: E731
        self.assertEqual(line(ours, "point3f[] points"), line(cli, "point3f[] points"))
        self.assertEqual(line(ours, "bindTransforms"), line(cli, "bindTransforms"))
        self.assertEqual(line(ours, "skel:blendShapes"), line(cli, "skel:blendShapes"))
        self.assertEqual(line(ours, "vector3f[] offsets"), line(cli, "vector3f[] offsets"))

    def test_bad_texture_arguments(self):
        with self.assertRaises(ValueError):
            self.r.texture(self.sketch, 0)
        with self.assertRaises(ValueError):
            self.r.texture(self.sketch, 5000)
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.load_rgb_image(SKETCH_JOINTS)
        self.assertEqual(cm.exception.status_name, "SKB_ERR_DECODE")
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.write_png(self.sketch, os.path.join(self.tmp.name, "no", "such", "x.png"))
        self.assertEqual(cm.exception.status_name, "SKB_ERR_IO")


class RawBindingsTest(unittest.TestCase):
    def test_raw_call_through_lib(self):
        st = skb.lib.skb_image_canny(None, 1.0, 2.0, 3, False, None, 0, 0)
        self.assertEqual(st, skb.Status.SKB_ERR_NULL_POINTER)
        self.assertIn(b"NULL", skb.lib.skb_last_error_message())
        n = ctypes.c_size_t()
        self.assertEqual(skb.lib.skb_context_component_count(None, 0, ctypes.byref(n)), 1)


if __name__ == "__main__":
    unittest.main(verbosity=2)

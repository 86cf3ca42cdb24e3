"""The ranked depth readings of a 3-D pose (issue 46 item 3) and the re-pose of a fitted result
without re-fitting its shape (issue 50 item 2): PoseEstimate.alternatives, flip_limb, pick,
Result.alternatives / flip_limb / pick_alternative / repose."""

import unittest

import numpy as np

import sketchbody as skb

from _util import SKETCH, SKETCH_JOINTS


class PoseAlternativesTest(unittest.TestCase):
    def test_alternatives_are_ranked_and_flip_twice_restores(self):
        with skb.estimate_pose_alternatives(SKETCH_JOINTS) as e:
            pose = e.pose
            alts = e.alternatives
            self.assertTrue(1 <= len(alts) <= 8)
            np.testing.assert_array_equal(alts[0].joints, pose.joints)
            self.assertEqual(alts[0].flipped, ())
            scores = [a.score for a in alts[1:]]
            self.assertEqual(scores, sorted(scores))
            for a in alts:
                self.assertTrue(np.isfinite(a.joints).all() and np.isfinite(a.score))
                self.assertTrue(set(a.flipped) <= set(skb.LIMB_NAMES))
                # A flip keeps the image: every reading projects onto the same 2-D joints.
                np.testing.assert_allclose(pose.camera.project(a.joints), pose.camera.project(pose.joints), atol=1e-6)
            flippable = [n for n in skb.LIMB_NAMES if e.flip_limb(n) == "done" and e.flip_limb(n) == "done"]
            self.assertTrue(flippable)
            np.testing.assert_allclose(e.pose.joints, pose.joints, atol=1e-12)
            if len(alts) > 1:
                e.pick(1)
                np.testing.assert_allclose(e.pose.joints, alts[1].joints, atol=1e-12)
            with self.assertRaises(ValueError):
                e.flip_limb("tail")
            with self.assertRaises(skb.SketchbodyError):
                e.pick(8)


class ResultReposeTest(unittest.TestCase):
    result = None

    @classmethod
    def setUpClass(cls):
        cls.result = skb.run_pipeline(SKETCH, joints=SKETCH_JOINTS, fit_options=skb.FitOptions(gender="female"))

    @classmethod
    def tearDownClass(cls):
        cls.result.close()

    def test_flip_and_repose_keep_the_shape(self):
        r = self.result
        shape = r.shape_weights()
        rest = r.vertices(posed=False)
        posed = r.vertices()
        alts = r.alternatives
        self.assertTrue(alts and alts[0].flipped == ())
        limb = next(n for n in skb.LIMB_NAMES if r.flip_limb(n) == "done")
        self.assertFalse(np.allclose(r.vertices(), posed, atol=1e-4))
        np.testing.assert_array_equal(r.shape_weights(), shape)
        np.testing.assert_array_equal(r.vertices(posed=False), rest)
        self.assertEqual(r.flip_limb(limb), "done")
        np.testing.assert_allclose(r.vertices(), posed, atol=1e-5)
        # The unchanged joints re-estimate the run's own pose: the same mesh.
        self.assertEqual(r.repose(r.joints2d()), "done")
        np.testing.assert_allclose(r.vertices(), posed, atol=1e-5)
        np.testing.assert_array_equal(r.shape_weights(), shape)
        # A joint dragged outside the sketch, or onto another: a status, nothing changed.
        j = r.joints2d()
        j.xy[4] = (-50.0, 10.0)
        self.assertEqual(r.repose(j), "joint_outside_image")
        j = r.joints2d()
        j.xy[4] = j.xy[3]
        self.assertEqual(r.repose(j), "joints_coincide")
        np.testing.assert_allclose(r.vertices(), posed, atol=1e-5)
        if len(alts) > 1:
            self.assertEqual(r.pick_alternative(1), "done")
            np.testing.assert_allclose(r.joints3d("estimated"), alts[1].joints, atol=1e-12)
            self.assertEqual(r.pick_alternative(0), "done")
        with self.assertRaises(skb.SketchbodyError):
            r.pick_alternative(99)


if __name__ == "__main__":
    unittest.main()

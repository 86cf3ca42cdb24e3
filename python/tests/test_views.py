"""Turnarounds (issue 48): run_pipeline(views=[View(...)]) fits one body to the front view and a
side view of the same character in the same pose; Result.views() and view_warnings() read them
back; views of another figure or a side drawn facing the other way raise SKB_ERR_VIEWS_DISAGREE."""

import unittest

import numpy as np

import sketchbody as skb

FIT = skb.FitOptions(samples=24, iterations=2, gender="female")


def turnaround():
    """The same female body and pose drawn from the front and from the side (yaw +90°)."""
    front, fj, _ = skb.render_sketch("female", 256, 256, seed=11, camera=(0, 0, 0))
    side, sj, _ = skb.render_sketch("female", 256, 256, seed=11, camera=(90, 0, 0))
    return front, fj, side, sj


class TurnaroundTest(unittest.TestCase):
    def test_front_and_side_fit_one_body_and_read_back(self):
        front, fj, side, sj = turnaround()
        with skb.run_pipeline(front, joints=fj, fit_options=FIT, views=[skb.View("side", side, sj)]) as r:
            views = r.views()
            self.assertEqual(len(views), 1)
            v = views[0]
            self.assertEqual((v.label, v.joints_detected, v.joints_swapped), ("side", False, False))
            np.testing.assert_allclose(v.joints.xy, sj)
            self.assertLess(v.residual, 0.05)
            self.assertAlmostEqual(v.scale_ratio, 1.0, delta=0.05)
            self.assertGreater(v.edge_support, 0.3)
            self.assertLess(v.facing_as_labelled_deg, v.facing_other_side_deg)
            # The side camera is the front camera turned by +90° about the body's (tilted) vertical.
            rel = r.camera().r.T @ v.camera.r
            self.assertAlmostEqual(np.degrees(np.arccos(np.clip((np.trace(rel) - 1) / 2, -1, 1))), 90.0, places=6)
            axis = np.array([rel[2, 1] - rel[1, 2], rel[0, 2] - rel[2, 0], rel[1, 0] - rel[0, 1]])
            self.assertGreater(axis[1] / np.linalg.norm(axis), 0.9)
            self.assertIsInstance(r.view_warnings(), list)
            posed = r.vertices()
        with skb.run_pipeline(front, joints=fj, fit_options=FIT) as one:
            self.assertEqual(one.views(), [])
            self.assertEqual(one.view_warnings(), [])
            self.assertFalse(np.array_equal(one.vertices(), posed), "the side view changes the body")

    def test_views_that_disagree_or_are_mislabelled_are_refused(self):
        front, fj, side, sj = turnaround()
        upside_down = sj.copy()
        upside_down[:, 1] = 256 - upside_down[:, 1]
        for what, view, status in [
            ("another figure", skb.View("side", side, upside_down), "SKB_ERR_VIEWS_DISAGREE"),
            ("facing the other way", skb.View("side_left", side, sj), "SKB_ERR_VIEWS_DISAGREE"),
        ]:
            with self.subTest(what):
                with self.assertRaises(skb.SketchbodyError) as cm:
                    skb.run_pipeline(front, joints=fj, fit_options=FIT, views=[view])
                self.assertEqual(cm.exception.status_name, status)
        with self.assertRaises(ValueError):
            skb.run_pipeline(front, joints=fj, views=[skb.View("top", side, sj)])
        with self.assertRaises(TypeError):
            skb.run_pipeline(front, joints=fj, views=[("side", side, sj)])
        with self.assertRaises(skb.SketchbodyError) as cm:
            skb.run_pipeline(front, joints=fj, fit_options=FIT,
                             views=[skb.View("side", side, sj), skb.View("side", side, sj)])
        self.assertEqual(cm.exception.status_name, "SKB_ERR_OUT_OF_RANGE")


if __name__ == "__main__":
    unittest.main()

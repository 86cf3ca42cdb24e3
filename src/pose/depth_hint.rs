//! Relative joint depths from an image cue, used to choose among the pose step's hypotheses.
//!
//! A near-frontal view hardly constrains whether a limb points toward or away from the viewer:
//! a stride seen from the front projects almost the same either way, and small 2-D joint errors
//! (a detector's, not the ground truth's) tip the solver from one reading to the other. A
//! landmark network (BlazePose) also predicts each landmark's depth relative to the hips; that
//! guess is coarse but usually has the sign right. [`DepthHint`] carries it into
//! [`super::estimate_pose_hinted`] as a weak third image coordinate: a squared depth residual,
//! weighted, is added to the 2-D reprojection cost where the solver *chooses* — the exemplar
//! starts ([`super::exemplar::nearest`]), each limb of a recomposed start
//! ([`super::exemplar::compose`]) and the blend of the hypotheses ([`super::blend`]) — and
//! nowhere else: the refinements keep fitting the 2-D joints alone.
//!
//! Units: depths are pixels at the image's scale, measured toward the camera (the camera
//! frame's +z; a joint nearer the viewer has the larger depth), relative to any common origin
//! (only differences are used).

use nalgebra::Vector3;

use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::skeleton::{joint, NUM_JOINTS};

/// True depth per unit of BlazePose's depth: the least-squares slope of the true camera-frame
/// depth difference of a limb's two joints on the landmark network's (both px), over the limbs
/// (upper arms, forearms, thighs, shins) pointing more than 5 cm toward or away from the viewer
/// in `make-dataset 60 --seed 78` with detected joints: 0.29 (345 limbs, correlation 0.79; the
/// network's depths are about twice as deep as the figure, their sign is right on 84 %).
pub const LANDMARK_DEPTH_SCALE: f64 = 0.3;

/// Per-joint relative depths and their weight (see the module doc). Plain data; `Copy`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthHint {
    /// Depth of each joint toward the camera, px at the image's scale (only differences count).
    pub depth: [f64; NUM_JOINTS],
    /// Which joints carry a depth; a joint without one adds no cost.
    pub known: [bool; NUM_JOINTS],
    /// Weight of a squared depth residual against a squared 2-D reprojection residual (both
    /// px²), ≥ 0; 0 makes the hint inert.
    pub weight: f64,
}

impl DepthHint {
    /// A hint from BlazePose's depths `z` (px, *smaller is nearer* the camera, as MediaPipe's
    /// landmarks), for the joints in `known`, with `weight`: depth = −[`LANDMARK_DEPTH_SCALE`] z.
    pub fn from_landmark_depth(z: &[f64; NUM_JOINTS], known: [bool; NUM_JOINTS], weight: f64) -> Self {
        Self { depth: std::array::from_fn(|j| -LANDMARK_DEPTH_SCALE * z[j]), known, weight }
    }

    /// Checks the weight (finite, ≥ 0) and the known depths (finite). Errors: `OutOfRange`,
    /// `NonFinite`.
    pub fn validate(&self) -> Result<()> {
        if !(self.weight.is_finite() && self.weight >= 0.0) {
            return Err(Error::OutOfRange {
                name: "depth_hint.weight", detail: format!("{} is not ≥ 0", self.weight)
            });
        }
        for (d, k) in self.depth.iter().zip(&self.known) {
            if *k {
                crate::error::ensure_finite("depth_hint.depth", *d)?;
            }
        }
        Ok(())
    }

    /// Weighted squared disagreement, px², of the depths of `x` (model frame, metres) seen by
    /// `cam` with the hint, relative to `root`: Σ over known joints `j` in `joints` of
    /// weight · ((d(j) − d(root)) − (hint(j) − hint(root)))², d = mean scale × camera-frame z.
    /// 0 when `root` has no depth.
    pub fn cost_about(
        &self,
        cam: &WeakPerspective,
        root: usize,
        x_root: &Vector3<f64>,
        joints: &[(usize, Vector3<f64>)],
    ) -> f64 {
        if self.weight == 0.0 || !self.known[root] {
            return 0.0;
        }
        let s = 0.5 * (cam.sx + cam.sy);
        let d_root = s * (cam.r * x_root).z;
        joints
            .iter()
            .filter(|(j, _)| self.known[*j])
            .map(|(j, x)| {
                let d = s * (cam.r * x).z - d_root;
                (d - (self.depth[*j] - self.depth[root])).powi(2)
            })
            .sum::<f64>()
            * self.weight
    }

    /// [`Self::cost_about`] for the whole pose `x`, relative to the pelvis.
    pub fn cost(&self, cam: &WeakPerspective, x: &[Vector3<f64>; NUM_JOINTS]) -> f64 {
        let all: Vec<(usize, Vector3<f64>)> =
            (0..NUM_JOINTS).filter(|&j| j != joint::PELVIS).map(|j| (j, x[j])).collect();
        self.cost_about(cam, joint::PELVIS, &x[joint::PELVIS], &all)
    }
}

/// `hint`'s [`DepthHint::cost`], or 0 without a hint.
pub(crate) fn hint_cost(hint: Option<&DepthHint>, cam: &WeakPerspective, x: &[Vector3<f64>; NUM_JOINTS]) -> f64 {
    hint.map_or(0.0, |h| h.cost(cam, x))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    fn frontal(s: f64) -> WeakPerspective {
        WeakPerspective { r: Matrix3::identity(), sx: s, sy: s, t: [0.0, 0.0] }
    }

    fn pose_with_knee_depth(z: f64) -> [Vector3<f64>; NUM_JOINTS] {
        let mut x = [Vector3::zeros(); NUM_JOINTS];
        x[joint::R_KNEE] = Vector3::new(-0.1, -0.4, z);
        x
    }

    #[test]
    fn a_limb_toward_the_camera_agrees_with_a_landmark_depth_that_is_smaller() {
        let mut z = [0.0; NUM_JOINTS];
        z[joint::R_KNEE] = -40.0 / LANDMARK_DEPTH_SCALE; // the network: nearer than the hips
        let mut known = [false; NUM_JOINTS];
        known[joint::PELVIS] = true;
        known[joint::R_KNEE] = true;
        let h = DepthHint::from_landmark_depth(&z, known, 0.5);
        let cam = frontal(200.0);
        let toward = pose_with_knee_depth(0.2); // +z = toward the camera: 40 px at scale 200
        let away = pose_with_knee_depth(-0.2);
        assert!(h.cost(&cam, &toward) < 1e-9, "{}", h.cost(&cam, &toward));
        assert!((h.cost(&cam, &away) - 0.5 * 80.0f64.powi(2)).abs() < 1e-6);
        // Unknown joints and a zero weight add nothing.
        let mut only_pelvis = known;
        only_pelvis[joint::R_KNEE] = false;
        assert_eq!(DepthHint { known: only_pelvis, ..h }.cost(&cam, &away), 0.0);
        assert_eq!(DepthHint { weight: 0.0, ..h }.cost(&cam, &away), 0.0);
        // A rotated camera sees the depth along its own z.
        let half_turn = WeakPerspective { r: Matrix3::new(-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0), ..cam };
        assert!(h.cost(&half_turn, &away) < 1e-9);
    }

    #[test]
    fn bad_hints_are_refused() {
        let known = [true; NUM_JOINTS];
        assert!(DepthHint::from_landmark_depth(&[0.0; NUM_JOINTS], known, 0.1).validate().is_ok());
        let mut z = [0.0; NUM_JOINTS];
        z[3] = f64::NAN;
        assert!(matches!(DepthHint::from_landmark_depth(&z, known, 0.1).validate(), Err(Error::NonFinite { .. })));
        let mut unknown = known;
        unknown[3] = false;
        assert!(DepthHint::from_landmark_depth(&z, unknown, 0.1).validate().is_ok());
        for w in [-1.0, f64::INFINITY, f64::NAN] {
            assert!(matches!(
                DepthHint::from_landmark_depth(&[0.0; NUM_JOINTS], known, w).validate(),
                Err(Error::OutOfRange { .. })
            ));
        }
    }
}

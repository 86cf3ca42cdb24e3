//! The learned prior on the bends of the knees and elbows: a cost per bend angle, learned from
//! the training motion (`sketchbody-lab train-factor-prior` stores it in
//! `assets/factor_prior.json`, [`super::factor_prior::FactorPrior::bend`]) and used by the
//! free-joint step ([`super::joint_fit`], [`super::PoseOptions::bend_prior`]).
//!
//! **Learning** ([`BendPrior::learn`]). The bend of a hinge is the angle θ between its two bones
//! (0 = straight). Over every training frame, the bends of both knees and of both elbows are
//! counted in [`STEP_DEG`] bins over 0–180°; each count is divided by the sine of its bin's
//! centre, which makes the histogram a density per unit solid angle of the child bone's
//! direction — the density of the joint positions the free-joint step solves for (a density per
//! degree of θ would favour bent limbs by the sin θ of the sphere's measure: real motion's knees
//! are rarely bent under 5°, but there is little solid angle that close to straight). The
//! histogram is smoothed twice with [1 2 1] / 4 and the cost of bin `i` is `−2 ln(p_i / p_mode)`
//! (the units of the free-joint step's squared residuals), `p` floored at [`FLOOR`] of a uniform
//! bin's share; bins at or below the mode cost 0. On the library's training motion the knees'
//! mode is at 7.5–10° and a knee bent 20° costs 2.2 more, 30° 4.0; the elbows' mode is at
//! 12.5–15°, and an elbow bent 30° costs 1.3 more, 45° 2.0.
//!
//! **Use** ([`BendPrior::cost`]): linear between bin centres, flat beyond the first and last.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::skeleton::{joint, Joints3};

/// Bin width, degrees.
pub const STEP_DEG: f64 = 2.5;
/// Number of bins (0–180°).
pub const BINS: usize = 72;
/// Floor of a bin's probability, as a share of a uniform bin's (1 / [`BINS`]).
pub const FLOOR: f64 = 1e-3;

/// The hinges (parent, hinge, child): right knee, left knee, right elbow, left elbow.
pub const HINGES: [(usize, usize, usize); 4] = [
    (joint::R_HIP, joint::R_KNEE, joint::R_ANKLE),
    (joint::L_HIP, joint::L_KNEE, joint::L_ANKLE),
    (joint::R_SHOULDER, joint::R_ELBOW, joint::R_WRIST),
    (joint::L_SHOULDER, joint::L_ELBOW, joint::L_WRIST),
];

/// Costs per bend bin of the knees and of the elbows ([`BINS`] each, ≥ 0, [`STEP_DEG`] wide).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BendPrior {
    /// The knees' costs, bin `i` covering [`STEP_DEG`]·[i, i + 1) degrees.
    pub knee: Vec<f64>,
    /// The elbows' costs.
    pub elbow: Vec<f64>,
}

/// Bend, radians, of the hinge (`p`, `h`, `c`) of `x`: the angle between its two bones; `None`
/// when a bone has no length.
pub fn bend_of(x: &Joints3, (p, h, c): (usize, usize, usize)) -> Option<f64> {
    let d = |a: usize, b: usize| nalgebra::Vector3::from(x[b]) - nalgebra::Vector3::from(x[a]);
    let (u, v) = (d(p, h).try_normalize(1e-12)?, d(h, c).try_normalize(1e-12)?);
    Some(u.dot(&v).clamp(-1.0, 1.0).acos())
}

fn costs(hist: &[f64; BINS]) -> Vec<f64> {
    // Per unit solid angle of the child bone's direction: each count over the sine of its
    // bin's centre.
    let mut s: [f64; BINS] = std::array::from_fn(|i| hist[i] / ((i as f64 + 0.5) * STEP_DEG).to_radians().sin());
    for _ in 0..2 {
        let t = s;
        for i in 0..BINS {
            s[i] = 0.25 * t[i.saturating_sub(1)] + 0.5 * t[i] + 0.25 * t[(i + 1).min(BINS - 1)];
        }
    }
    let total: f64 = s.iter().sum();
    let (mode, max) = s.iter().enumerate().fold((0, 0.0), |(m, v), (i, &x)| if x > v { (i, x) } else { (m, v) });
    if !(max > 0.0) {
        return vec![0.0; BINS];
    }
    let floor = FLOOR * total / BINS as f64;
    (0..BINS).map(|i| if i <= mode { 0.0 } else { -2.0 * (s[i].max(floor) / max).ln() }).collect()
}

impl BendPrior {
    /// Learns the costs from `poses` (module doc). Poses with a zero-length limb bone skip that
    /// hinge; with no poses every cost is 0.
    pub fn learn<'a>(poses: impl IntoIterator<Item = &'a Joints3>) -> BendPrior {
        let mut hist = [[0.0; BINS]; 2];
        for x in poses {
            for (i, &hinge) in HINGES.iter().enumerate() {
                if let Some(t) = bend_of(x, hinge) {
                    hist[i / 2][((t.to_degrees() / STEP_DEG) as usize).min(BINS - 1)] += 1.0;
                }
            }
        }
        BendPrior { knee: costs(&hist[0]), elbow: costs(&hist[1]) }
    }

    /// Checks the tables: [`BINS`] finite, non-negative costs each. Errors: [`Error::CorruptData`].
    pub fn validate(&self) -> Result<()> {
        for (name, t) in [("knee", &self.knee), ("elbow", &self.elbow)] {
            if t.len() != BINS || t.iter().any(|c| !(c.is_finite() && *c >= 0.0)) {
                return Err(Error::CorruptData(format!(
                    "bend prior: the {name} table needs {BINS} finite costs ≥ 0 (has {})",
                    t.len()
                )));
            }
        }
        Ok(())
    }

    /// The cost of a bend of `theta` radians of hinge `i` of [`HINGES`] (0, 1 knees; 2, 3
    /// elbows) and its slope per radian: linear between the bins' centres, flat outside them.
    pub fn cost(&self, i: usize, theta: f64) -> (f64, f64) {
        let t = if i < 2 { &self.knee } else { &self.elbow };
        let step = STEP_DEG.to_radians();
        let x = theta / step - 0.5;
        if !(x > 0.0) {
            return (t[0], 0.0);
        }
        if x >= (BINS - 1) as f64 {
            return (t[BINS - 1], 0.0);
        }
        let i0 = x.floor() as usize;
        let f = x - i0 as f64;
        (t[i0] * (1.0 - f) + t[i0 + 1] * f, (t[i0 + 1] - t[i0]) / step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::NUM_JOINTS;

    /// A pose whose knees bend `k` degrees and elbows `e` degrees.
    fn pose(k: f64, e: f64) -> Joints3 {
        let mut x = [[0.0; 3]; NUM_JOINTS];
        for (i, &(p, h, c)) in HINGES.iter().enumerate() {
            let t = if i < 2 { k } else { e }.to_radians();
            x[p] = [i as f64, 0.0, 0.0];
            x[h] = [i as f64, -0.4, 0.0];
            x[c] = [i as f64, -0.4 - 0.4 * t.cos(), 0.4 * t.sin()];
        }
        x
    }

    #[test]
    fn learns_zero_at_the_mode_and_more_beyond_it() {
        // Knees mostly at 11°, some at 30° and 60°; elbows mostly at 40°.
        let mut poses = Vec::new();
        for (k, e, n) in [(11.0, 40.0, 60), (30.0, 20.0, 20), (60.0, 90.0, 10)] {
            poses.extend(std::iter::repeat_n(pose(k, e), n));
        }
        let b = BendPrior::learn(&poses);
        b.validate().unwrap();
        let knee = |d: f64| b.cost(0, d.to_radians()).0;
        assert_eq!(knee(0.0), 0.0);
        assert_eq!(knee(11.25), 0.0);
        assert!(knee(30.0) > 1.0 && knee(60.0) > knee(30.0), "{} {}", knee(30.0), knee(60.0));
        // Bends between the peaks and far from any training bend cost most (up to the floor).
        assert!(knee(45.0) > knee(30.0) && knee(120.0) > knee(60.0));
        let elbow = |d: f64| b.cost(2, d.to_radians()).0;
        assert_eq!(elbow(20.0), 0.0);
        assert!(elbow(90.0) > 1.0);
        // The slope is that of the linear interpolation.
        let (c0, s) = b.cost(0, 0.5);
        let c1 = b.cost(0, 0.5 + 1e-6).0;
        assert!(((c1 - c0) / 1e-6 - s).abs() < 1e-3 * s.abs().max(1.0));
        // No poses: no cost; a wrong table does not validate.
        assert!(BendPrior::learn(&[]).knee.iter().all(|c| *c == 0.0));
        assert!(BendPrior { knee: vec![0.0; 3], elbow: vec![0.0; BINS] }.validate().is_err());
        assert!(BendPrior { knee: vec![f64::NAN; BINS], elbow: vec![0.0; BINS] }.validate().is_err());
    }
}

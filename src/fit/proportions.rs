//! Bone-length factors in the shape fit: non-standard proportions (long legs, broad shoulders,
//! small heads, ...) that no PCA shape represents. With [`FitOptions::proportion_sd`] > 0 every
//! SIR sample carries five log factors `z` after its PCA weights — legs, arms, shoulders, head,
//! torso, the order of [`Proportions`] — with the prior `z ~ N(m, sd²)` each, `m` = 0 or, with
//! [`FitOptions::estimate_proportions`], the closed-form estimate of
//! [`super::bone_estimate`] from the 2-D joints, pose and camera. The first
//! iteration draws them from the prior; later iterations draw from `N(z; z_prev, (s·sd)²) ·
//! N(z; m, sd²)` (the same form as eq. 9, a Gaussian product sampled exactly), `s` being the
//! transition scale. A sample's rest body gets factor `exp(z)` on its bones, applied as the
//! renderer applies proportions ([`apply_proportions`]: bones stretched about the pelvis root
//! by skinning, the head scaled about the neck).
//!
//! [`FitOptions::proportion_sd`]: super::FitOptions::proportion_sd
//! [`FitOptions::estimate_proportions`]: super::FitOptions::estimate_proportions

use rand::Rng;
use rand_distr::StandardNormal;

use crate::body::proportions::{apply_proportions, Proportions};
use crate::body::VertexWeights;
use crate::error::Result;
use crate::skeleton::Joints3;

/// Number of factors (legs, arms, shoulders, head, torso).
pub const NUM_FACTORS: usize = 5;

/// Log factors are kept within ±this (factors 0.61..1.65, inside [`Proportions::validate`]'s
/// 0.5..=2.0).
const MAX_LOG: f64 = 0.5;

/// The factors' prior and transition.
#[derive(Clone, Copy, Debug)]
pub(super) struct FactorPrior {
    /// Prior standard deviation of each log factor.
    sd: f64,
    /// Transition standard deviation of each log factor.
    step: f64,
    /// Prior mean of each log factor.
    centre: [f64; NUM_FACTORS],
}

impl FactorPrior {
    /// `sd` is the prior's standard deviation, `scale` the transition scale in prior
    /// standard deviations (both > 0, checked by the options); the prior mean is 0.
    pub(super) fn new(sd: f64, scale: f64) -> FactorPrior {
        FactorPrior { sd, step: scale * sd, centre: [0.0; NUM_FACTORS] }
    }

    /// The same prior centred on the log factors `centre` (each clamped to ±0.5).
    pub(super) fn centred(self, centre: [f64; NUM_FACTORS]) -> FactorPrior {
        FactorPrior { centre: centre.map(|c| c.clamp(-MAX_LOG, MAX_LOG)), ..self }
    }

    /// Prior standard deviation of each log factor (for the convergence test).
    pub(super) fn sd(&self) -> f64 {
        self.sd
    }

    /// Appends a draw from the prior to `y`.
    pub(super) fn extend_initial<R: Rng + ?Sized>(&self, y: &mut Vec<f64>, rng: &mut R) {
        for m in self.centre {
            let n: f64 = rng.sample(StandardNormal);
            y.push((m + self.sd * n).clamp(-MAX_LOG, MAX_LOG));
        }
    }

    /// Appends a successor of the log factors `prev` to `y`: the exact draw from
    /// `N(z; prev, step²) · N(z; centre, sd²)`.
    pub(super) fn extend_successor<R: Rng + ?Sized>(&self, prev: &[f64], y: &mut Vec<f64>, rng: &mut R) {
        let (a, b) = (1.0 / (self.step * self.step), 1.0 / (self.sd * self.sd));
        let sd_post = (1.0 / (a + b)).sqrt();
        for (&z, m) in prev.iter().zip(self.centre) {
            let n: f64 = rng.sample(StandardNormal);
            y.push(((z * a + m * b) / (a + b) + sd_post * n).clamp(-MAX_LOG, MAX_LOG));
        }
    }
}

/// The proportions of log factors `z` (legs, arms, shoulders, head, torso).
pub fn proportions_of(z: &[f64]) -> Proportions {
    let f = |k: usize| z.get(k).map_or(1.0, |v| v.exp());
    Proportions { legs: f(0), arms: f(1), shoulders: f(2), head: f(3), torso: f(4) }
}

/// Applies proportions to rest vertices (in place) and joints, as the renderer does.
pub fn apply_in_place(
    vertices: &mut Vec<[f32; 3]>,
    joints: &mut Joints3,
    weights: &[VertexWeights],
    props: &Proportions,
) -> Result<()> {
    let (v, j) = apply_proportions(vertices, joints, weights, props)?;
    *vertices = v;
    *joints = j;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn transition_is_the_gaussian_product_and_factors_map_back() {
        // sd 0.1, step 0.1: posterior mean prev / 2, sd 0.1 / sqrt 2.
        let p = FactorPrior::new(0.1, 1.0);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let n = 20000;
        let (mut sum, mut sq) = (0.0, 0.0);
        for _ in 0..n {
            let mut y = Vec::new();
            p.extend_successor(&[0.2; NUM_FACTORS], &mut y, &mut rng);
            assert_eq!(y.len(), NUM_FACTORS);
            sum += y[0];
            sq += y[0] * y[0];
        }
        let mean = sum / n as f64;
        let var = sq / n as f64 - mean * mean;
        assert!((mean - 0.1).abs() < 0.003, "{mean}");
        assert!((var.sqrt() - 0.1 / 2f64.sqrt()).abs() < 0.003, "{}", var.sqrt());
        let mut y = vec![7.0];
        FactorPrior::new(5.0, 1.0).extend_initial(&mut y, &mut rng);
        assert_eq!(y.len(), 1 + NUM_FACTORS);
        assert!(y[1..].iter().all(|z| z.abs() <= MAX_LOG));
        // Centred at 0.3 (prev 0.2, equal precisions): mean 0.25.
        let c = FactorPrior::new(0.1, 1.0).centred([0.3; NUM_FACTORS]);
        let mut sum = 0.0;
        for _ in 0..n {
            let mut y = Vec::new();
            c.extend_successor(&[0.2; NUM_FACTORS], &mut y, &mut rng);
            sum += y[4];
        }
        assert!((sum / n as f64 - 0.25).abs() < 0.003, "{}", sum / n as f64);
        let mut y = Vec::new();
        FactorPrior::new(1e-9, 1.0).centred([0.2, -0.1, 0.0, 0.9, 0.0]).extend_initial(&mut y, &mut rng);
        assert!((y[0] - 0.2).abs() < 1e-6 && (y[1] + 0.1).abs() < 1e-6 && (y[3] - MAX_LOG).abs() < 1e-6, "{y:?}");
        let pr = proportions_of(&[0.0, 2f64.ln(), 0.0, -(2f64.ln()), 0.0]);
        assert!((pr.arms - 2.0).abs() < 1e-12 && (pr.head - 0.5).abs() < 1e-12 && pr.legs == 1.0);
        assert_eq!(proportions_of(&[]), Proportions::default());
    }
}

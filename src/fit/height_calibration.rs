//! Calibration of the fitted body's rest height (issues 16 and 21). A single drawing fixes the
//! body's size only through its proportions (the per-sample camera is refitted to each sample's
//! skeleton), and the SIR's posterior mean is drawn toward the prior's mean body: on training
//! sketches the fitted heights vary less than the true ones once the gender's mean is taken
//! out. A linear model in log height, fitted by least squares on held-apart training sketches,
//! corrects that:
//!
//! `ln h = intercept + slope · ln h_fit + male · g + Σ_k w_k (x_k − m_k)`, with `h_fit` the fitted
//! rest mesh's height (metres, [`crate::body::rig::y_extent`]), `g` the fit's gender value
//! (0 female … 1 male) and `x` the drawing's [`HeightEvidence`]: the fitted bone-length factors
//! and the drawn widths over the torso length ([`crate::fit::GenderFeatures`]). `m_k` is the
//! training mean of `x_k`, so a missing value adds nothing (docs/benchmarks.md, "Height
//! evidence").
//!
//! The pipeline scales the fitted rest body about its pelvis to `h` when the character's height
//! is unknown and the 2-D joints are given ([`crate::pipeline::PipelineOptions::calibrate_fit`]),
//! after the shape map of [`crate::fit::ShapeCalibration`] ([`crate::fit::FitCalibration`]);
//! the shape at a given height is untouched. Fits of the detector's joints keep their fitted
//! height (docs/benchmarks.md, "Height calibration"). The change is bounded by
//! [`MAX_LOG_CHANGE`], so a figure far outside the training bodies (a chibi, a giant) keeps its
//! fitted height within that bound.

use crate::body::proportions::Proportions;
use crate::error::{ensure_finite, Error, Result};
use crate::fit::gender_evidence::{GenderFeatures, GENDER_FEATURE_NAMES, NUM_GENDER_FEATURES};
use crate::fit::proportions::NUM_FACTORS;

/// Largest |ln(h / h_fit)| the calibration applies (natural log; about ±16 % of the height).
pub const MAX_LOG_CHANGE: f64 = 0.15;

/// Number of [`HeightEvidence`] values: the five bone-length factors, then the drawn widths.
pub const NUM_HEIGHT_EVIDENCE: usize = NUM_FACTORS + NUM_GENDER_FEATURES;

/// Names of the [`HeightEvidence`] values, in order: the natural logs of the fitted
/// [`Proportions`] factors, then [`GENDER_FEATURE_NAMES`].
pub const HEIGHT_EVIDENCE_NAMES: [&str; NUM_HEIGHT_EVIDENCE] = {
    let factors: [&str; NUM_FACTORS] =
        ["log_legs_factor", "log_arms_factor", "log_shoulders_factor", "log_head_factor", "log_torso_factor"];
    let mut names = [""; NUM_HEIGHT_EVIDENCE];
    let mut k = 0;
    while k < NUM_HEIGHT_EVIDENCE {
        names[k] = if k < factors.len() { factors[k] } else { GENDER_FEATURE_NAMES[k - factors.len()] };
        k += 1;
    }
    names
};

/// What a drawing says about the body's size beyond its fitted height (module documentation),
/// in the order of [`HEIGHT_EVIDENCE_NAMES`]; `None` = missing. Plain data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightEvidence {
    /// The values (natural logs of ratios, dimensionless).
    pub values: [Option<f64>; NUM_HEIGHT_EVIDENCE],
}

impl HeightEvidence {
    /// No evidence: every value missing.
    pub const NONE: HeightEvidence = HeightEvidence { values: [None; NUM_HEIGHT_EVIDENCE] };

    /// The evidence of a fit: its bone-length factors (`None` = the standard proportions, every
    /// factor 1) and the drawing's measured widths (`None` = all missing).
    pub fn new(proportions: Option<&Proportions>, widths: Option<&GenderFeatures>) -> HeightEvidence {
        let p = proportions.copied().unwrap_or_default();
        let mut values = [None; NUM_HEIGHT_EVIDENCE];
        for (v, f) in values.iter_mut().zip([p.legs, p.arms, p.shoulders, p.head, p.torso]) {
            *v = (f > 0.0).then(|| f.ln());
        }
        if let Some(w) = widths {
            values[NUM_FACTORS..].copy_from_slice(&w.values);
        }
        HeightEvidence { values }
    }
}

/// A height calibration (module documentation). Plain data; `Send + Sync`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightCalibration {
    /// ln metres at `ln h_fit = 0` for a female fit at the mean evidence.
    pub intercept: f64,
    /// Weight of `ln h_fit`.
    pub slope: f64,
    /// Added per unit gender value (male − female), ln metres.
    pub male: f64,
    /// Training mean of each [`HeightEvidence`] value.
    pub evidence_means: [f64; NUM_HEIGHT_EVIDENCE],
    /// ln metres per unit of each evidence value's deviation from its mean; 0 = not used.
    pub evidence_weights: [f64; NUM_HEIGHT_EVIDENCE],
}

impl HeightCalibration {
    /// [`crate::fit::FitCalibration::SHIPPED`]'s height calibration, trained on the heights of
    /// the bodies its shape map gives (`sketchbody-lab calibrate-fit`; that constant's
    /// documentation says on what).
    pub const SHIPPED: HeightCalibration = HeightCalibration {
        intercept: -0.139366,
        slope: 1.262180,
        male: -0.001347,
        evidence_means: [
            0.038452, -0.020611, 0.047618, -0.031282, -0.014027, -0.336410, -0.945750, -0.435126, -0.841815, -0.712646,
            -2.234667, -2.085904, -2.239109, -1.351525, -1.863323,
        ],
        evidence_weights: [
            -0.232208, 0.006393, -0.024176, -0.325399, -0.647989, 0.000253, -0.280454, 0.006021, 0.014180, -0.022996,
            0.005327, -0.009669, 0.013063, -0.012863, -0.015014,
        ],
    };

    /// The calibrated height (metres) for a fit `fit_height` metres tall with gender value
    /// `gender_value` (clamped to 0..=1) and the drawing's `evidence`, within
    /// [`MAX_LOG_CHANGE`] of `fit_height`.
    /// Errors: a non-finite input or `fit_height` ≤ 0 ([`Error::OutOfRange`], [`Error::NonFinite`]).
    pub fn calibrated(&self, fit_height: f64, gender_value: f64, evidence: &HeightEvidence) -> Result<f64> {
        ensure_finite("fit height", fit_height)?;
        ensure_finite("gender value", gender_value)?;
        if fit_height <= 0.0 {
            return Err(Error::OutOfRange { name: "fit height", detail: format!("{fit_height} m is not > 0") });
        }
        let ln_fit = fit_height.ln();
        let mut ln_h = self.intercept + self.slope * ln_fit + self.male * gender_value.clamp(0.0, 1.0);
        for ((v, m), w) in evidence.values.iter().zip(&self.evidence_means).zip(&self.evidence_weights) {
            if let Some(x) = v {
                ensure_finite("height evidence", *x)?;
                ln_h += w * (x - m);
            }
        }
        Ok((ln_h - ln_fit).clamp(-MAX_LOG_CHANGE, MAX_LOG_CHANGE).exp() * fit_height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NO_WEIGHTS: [f64; NUM_HEIGHT_EVIDENCE] = [0.0; NUM_HEIGHT_EVIDENCE];

    fn plain(intercept: f64, slope: f64, male: f64) -> HeightCalibration {
        HeightCalibration { intercept, slope, male, evidence_means: NO_WEIGHTS, evidence_weights: NO_WEIGHTS }
    }

    #[test]
    fn the_evidence_names_follow_the_factors_then_the_widths() {
        assert_eq!(HEIGHT_EVIDENCE_NAMES[..2], ["log_legs_factor", "log_arms_factor"]);
        assert_eq!(HEIGHT_EVIDENCE_NAMES[4..7], ["log_torso_factor", "log_shoulder_width", "log_hip_width"]);
        let p = Proportions { legs: 1.2, arms: 0.9, shoulders: 1.0, head: 1.5, torso: 1.1 };
        let mut w = GenderFeatures { values: [Some(-0.5); NUM_GENDER_FEATURES] };
        w.values[3] = None;
        let e = HeightEvidence::new(Some(&p), Some(&w));
        assert!((e.values[0].unwrap() - 1.2f64.ln()).abs() < 1e-15);
        assert!((e.values[3].unwrap() - 1.5f64.ln()).abs() < 1e-15);
        assert_eq!(e.values[5], Some(-0.5));
        assert_eq!(e.values[8], None, "a missing width stays missing");
        let standard = HeightEvidence::new(None, None);
        assert!(standard.values[..5].iter().all(|v| *v == Some(0.0)), "standard proportions: ln 1");
        assert!(standard.values[5..].iter().all(Option::is_none));
    }

    #[test]
    fn the_change_is_bounded_and_follows_the_model_inside_the_bound() {
        let c = plain(-0.18, 1.37, -0.035);
        let none = HeightEvidence::NONE;
        let h = c.calibrated(1.7, 0.0, &none).unwrap();
        assert!((h.ln() - (-0.18 + 1.37 * 1.7f64.ln())).abs() < 1e-12);
        assert!(c.calibrated(1.7, 1.0, &none).unwrap() < h, "the male offset applies");
        assert_eq!(c.calibrated(1.7, 7.0, &none).unwrap(), c.calibrated(1.7, 1.0, &none).unwrap(), "gender clamped");
        for fit in [0.3, 1.0, 3.0, 10.0] {
            let r = (c.calibrated(fit, 0.5, &none).unwrap() / fit).ln();
            assert!(r.abs() <= MAX_LOG_CHANGE + 1e-12, "{fit}: {r}");
        }
        let stretch = plain(0.0, 2.0, 0.0);
        assert!((stretch.calibrated(3.0, 0.0, &none).unwrap() / 3.0 - MAX_LOG_CHANGE.exp()).abs() < 1e-12);
        let mut heavy = c;
        heavy.evidence_weights[0] = 10.0;
        let mut e = none;
        e.values[0] = Some(5.0);
        let r = (heavy.calibrated(1.7, 0.0, &e).unwrap() / 1.7).ln();
        assert!((r - MAX_LOG_CHANGE).abs() < 1e-12, "the evidence is bounded too: {r}");
    }

    #[test]
    fn bad_inputs_are_errors() {
        let c = HeightCalibration::SHIPPED;
        let none = HeightEvidence::NONE;
        assert!(matches!(c.calibrated(0.0, 0.0, &none), Err(Error::OutOfRange { .. })));
        assert!(matches!(c.calibrated(f64::NAN, 0.0, &none), Err(Error::NonFinite { .. })));
        assert!(matches!(c.calibrated(1.7, f64::INFINITY, &none), Err(Error::NonFinite { .. })));
        let mut nan = none;
        nan.values[4] = Some(f64::NAN);
        assert!(matches!(c.calibrated(1.7, 0.0, &nan), Err(Error::NonFinite { .. })));
    }
}

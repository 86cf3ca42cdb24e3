//! Calibration of the fitted body's rest height (issues 16 and 21). A single drawing fixes the
//! body's size only through its proportions (the per-sample camera is refitted to each sample's
//! skeleton), and the SIR's posterior mean is drawn toward the prior's mean body: on training
//! sketches the fitted heights vary less than the true ones once the gender's mean is taken
//! out. A linear model in log height, fitted by least squares on held-apart training sketches,
//! corrects that:
//!
//! `ln h = intercept + slope · ln h_fit + male · g`, with `h_fit` the fitted rest mesh's height
//! (metres, [`crate::body::rig::y_extent`]) and `g` the fit's gender value (0 female … 1 male).
//!
//! The pipeline scales the fitted rest body about its pelvis to `h` when the character's height
//! is unknown and the 2-D joints are given ([`crate::pipeline::PipelineOptions::calibrate_fit`]),
//! after the shape map of [`crate::fit::ShapeCalibration`] ([`crate::fit::FitCalibration`]);
//! the shape at a given height is untouched. With the detector's joints the fitted height says
//! less (its error is near the spread of heights) and a calibration fitted the same way on
//! detected-joint fits measured worse on the tuning set (docs/benchmarks.md, "Height
//! calibration"), so those fits keep their height. The change is bounded by [`MAX_LOG_CHANGE`], so a figure far outside
//! the training bodies (a chibi, a giant) keeps its fitted height within that bound.

use crate::error::{ensure_finite, Error, Result};

/// Largest |ln(h / h_fit)| the calibration applies (about ±16 %); with the shipped calibration
/// the change stays within about ±5 % on a tuning set (`make-dataset 60 --seed 78`).
pub const MAX_LOG_CHANGE: f64 = 0.15;

/// A height calibration (module documentation). Plain data; `Send + Sync`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightCalibration {
    /// ln metres at `ln h_fit = 0` for a female fit.
    pub intercept: f64,
    /// Weight of `ln h_fit`.
    pub slope: f64,
    /// Added per unit gender value (male − female), ln metres.
    pub male: f64,
}

impl HeightCalibration {
    /// [`crate::fit::FitCalibration::SHIPPED`]'s height calibration, trained on the heights of
    /// the bodies its shape map gives (`sketchbody calibrate-fit`; that constant's
    /// documentation says on what).
    pub const SHIPPED: HeightCalibration = HeightCalibration { intercept: -0.251905, slope: 1.505194, male: -0.042254 };

    /// The calibrated height (metres) for a fit `fit_height` metres tall with gender value
    /// `gender_value` (clamped to 0..=1), within [`MAX_LOG_CHANGE`] of `fit_height`.
    /// Errors: a non-finite input or `fit_height` ≤ 0 ([`Error::OutOfRange`], [`Error::NonFinite`]).
    pub fn calibrated(&self, fit_height: f64, gender_value: f64) -> Result<f64> {
        ensure_finite("fit height", fit_height)?;
        ensure_finite("gender value", gender_value)?;
        if fit_height <= 0.0 {
            return Err(Error::OutOfRange { name: "fit height", detail: format!("{fit_height} m is not > 0") });
        }
        let ln_fit = fit_height.ln();
        let ln_h = self.intercept + self.slope * ln_fit + self.male * gender_value.clamp(0.0, 1.0);
        Ok((ln_h - ln_fit).clamp(-MAX_LOG_CHANGE, MAX_LOG_CHANGE).exp() * fit_height)
    }

    /// Least-squares fit to `(fitted height m, gender value, true height m)` triples.
    /// Errors: fewer than 3 samples, a non-finite or non-positive height, or inputs that do not
    /// determine the three coefficients (one gender only, all fitted heights equal) —
    /// [`Error::OutOfRange`], [`Error::NonFinite`], [`Error::Degenerate`].
    pub fn train(samples: &[(f64, f64, f64)]) -> Result<HeightCalibration> {
        if samples.len() < 3 {
            return Err(Error::OutOfRange {
                name: "height calibration set",
                detail: format!("{} samples; need at least 3", samples.len()),
            });
        }
        let mut ata = nalgebra::Matrix3::<f64>::zeros();
        let mut atb = nalgebra::Vector3::<f64>::zeros();
        for &(fit, g, truth) in samples {
            for (name, v) in [("fit height", fit), ("gender value", g), ("true height", truth)] {
                ensure_finite(name, v)?;
            }
            if fit <= 0.0 || truth <= 0.0 {
                return Err(Error::OutOfRange {
                    name: "height calibration set",
                    detail: format!("heights must be > 0 (fitted {fit} m, true {truth} m)"),
                });
            }
            let row = nalgebra::Vector3::new(1.0, fit.ln(), g);
            ata += row * row.transpose();
            atb += row * truth.ln();
        }
        let x = ata
            .cholesky()
            .filter(|c| c.l().diagonal().iter().all(|d| *d > 1e-9))
            .ok_or_else(|| {
                Error::Degenerate("height calibration: the inputs do not determine the coefficients".into())
            })?
            .solve(&atb);
        Ok(HeightCalibration { intercept: x[0], slope: x[1], male: x[2] })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn training_recovers_a_known_calibration() {
        let truth = HeightCalibration { intercept: -0.2, slope: 1.3, male: -0.03 };
        let samples: Vec<(f64, f64, f64)> = (0..40)
            .map(|i| {
                let fit = 1.5 + 0.01 * i as f64;
                let g = (i % 2) as f64;
                (fit, g, (truth.intercept + truth.slope * fit.ln() + truth.male * g).exp())
            })
            .collect();
        let got = HeightCalibration::train(&samples).unwrap();
        for (a, b) in [(got.intercept, truth.intercept), (got.slope, truth.slope), (got.male, truth.male)] {
            assert!((a - b).abs() < 1e-9, "{got:?}");
        }
    }

    #[test]
    fn the_change_is_bounded_and_follows_the_model_inside_the_bound() {
        let c = HeightCalibration { intercept: -0.18, slope: 1.37, male: -0.035 };
        let h = c.calibrated(1.7, 0.0).unwrap();
        assert!((h.ln() - (-0.18 + 1.37 * 1.7f64.ln())).abs() < 1e-12);
        assert!(c.calibrated(1.7, 1.0).unwrap() < h, "the male offset applies");
        assert_eq!(c.calibrated(1.7, 7.0).unwrap(), c.calibrated(1.7, 1.0).unwrap(), "gender value clamped");
        for fit in [0.3, 1.0, 3.0, 10.0] {
            let r = (c.calibrated(fit, 0.5).unwrap() / fit).ln();
            assert!(r.abs() <= MAX_LOG_CHANGE + 1e-12, "{fit}: {r}");
        }
        let stretch = HeightCalibration { intercept: 0.0, slope: 2.0, male: 0.0 };
        assert!((stretch.calibrated(3.0, 0.0).unwrap() / 3.0 - MAX_LOG_CHANGE.exp()).abs() < 1e-12);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let c = HeightCalibration::SHIPPED;
        assert!(matches!(c.calibrated(0.0, 0.0), Err(Error::OutOfRange { .. })));
        assert!(matches!(c.calibrated(f64::NAN, 0.0), Err(Error::NonFinite { .. })));
        assert!(matches!(c.calibrated(1.7, f64::INFINITY), Err(Error::NonFinite { .. })));
        assert!(matches!(HeightCalibration::train(&[(1.7, 0.0, 1.7)]), Err(Error::OutOfRange { .. })));
        let one_gender = [(1.6, 0.0, 1.6), (1.7, 0.0, 1.72), (1.8, 0.0, 1.79)];
        assert!(matches!(HeightCalibration::train(&one_gender), Err(Error::Degenerate(_))));
        let bad = [(1.6, 0.0, 1.6), (-1.7, 1.0, 1.72), (1.8, 0.0, 1.79)];
        assert!(matches!(HeightCalibration::train(&bad), Err(Error::OutOfRange { .. })));
    }
}

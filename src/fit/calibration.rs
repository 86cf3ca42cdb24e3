//! Calibration of the fitted body (issues 16 and 21): the SIR's posterior mean Y* is drawn
//! toward the prior's mean body. On training sketches the fitted shape weights spread far less
//! than the true ones (per dimension 0.1–0.5 against 0.5–3 of the true standard deviation) and
//! the true weights grow faster than the fitted ones (least-squares slopes 1–3), so a per-gender,
//! per-dimension linear map fitted on held-apart training sketches moves Y* toward the bodies
//! that drew such sketches:
//!
//! `w'_k = intercept_k + slope_k · w_k` for dimensions `k ≥ first_dim` of a 10-dimension fit,
//! the lower dimensions untouched.
//!
//! The lower dimensions carry most of the body's size, which [`HeightCalibration`] corrects
//! after this map (it is trained on the mapped bodies' heights); `first_dim` (3 in the shipped
//! map) is chosen by 5-fold cross-validation on the training sketches (docs/benchmarks.md,
//! "Shape calibration"). [`FitCalibration`] holds both maps, applied in
//! that order by [`crate::pipeline::fit_body`] when the 2-D joints are given and the height is
//! unknown.

use crate::body::Gender;
use crate::error::{ensure_finite, Error, Result};

use super::HeightCalibration;

/// Number of shape dimensions a [`ShapeCalibration`] maps: the gendered fits' default
/// (`FitOptions::dims` = all 10 dimensions of a gendered prior). Fits of other dimensions are
/// left as they are.
pub const CALIBRATED_DIMS: usize = 10;

/// A per-gender, per-dimension linear map of fitted shape weights (module documentation).
/// Plain data; `Send + Sync`. Index 0 of the arrays is female, 1 male ([`Gender::index`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeCalibration {
    /// First mapped dimension; lower ones keep their fitted weight.
    pub first_dim: usize,
    /// Added to each mapped weight, metres (0 below `first_dim`).
    pub intercept: [[f64; CALIBRATED_DIMS]; 2],
    /// Factor on each mapped weight (1 below `first_dim`).
    pub slope: [[f64; CALIBRATED_DIMS]; 2],
}

impl ShapeCalibration {
    /// The identity map.
    pub const IDENTITY: ShapeCalibration = ShapeCalibration {
        first_dim: CALIBRATED_DIMS,
        intercept: [[0.0; CALIBRATED_DIMS]; 2],
        slope: [[1.0; CALIBRATED_DIMS]; 2],
    };

    /// [`FitCalibration::SHIPPED`]'s shape map (its documentation says how it was trained).
    pub const SHIPPED: ShapeCalibration = ShapeCalibration {
        first_dim: 3,
        intercept: [
            [0.0, 0.0, 0.0, -0.144443, -0.056520, -0.052164, 0.072359, 0.067591, -0.061619, 0.254755],
            [0.0, 0.0, 0.0, -0.124522, -0.022723, 0.126347, -0.194232, 0.038970, -0.004553, 0.036635],
        ],
        slope: [
            [1.0, 1.0, 1.0, 2.259102, 1.270454, 2.253368, 1.773746, 1.931948, 2.147624, 3.194369],
            [1.0, 1.0, 1.0, 1.400180, 1.403525, 1.935107, 2.614819, 1.257286, 1.656558, 2.294618],
        ],
    };

    /// The fitted weights mapped (module documentation), or `None` when `weights` is not a
    /// [`CALIBRATED_DIMS`]-dimension fit (left as it is). The caller clamps the result to the
    /// prior's range. Errors: a non-finite weight ([`Error::NonFinite`]).
    pub fn apply(&self, gender: Gender, weights: &[f64]) -> Result<Option<Vec<f64>>> {
        if weights.len() != CALIBRATED_DIMS {
            return Ok(None);
        }
        let g = gender.index();
        let mut out = Vec::with_capacity(CALIBRATED_DIMS);
        for (k, &w) in weights.iter().enumerate() {
            ensure_finite("shape weight", w)?;
            out.push(if k < self.first_dim { w } else { self.intercept[g][k] + self.slope[g][k] * w });
        }
        Ok(Some(out))
    }

    /// Least-squares fit, per gender and dimension `k ≥ first_dim`, of the true weight on the
    /// fitted one with an intercept, from `(gender, fitted weights, true weights)` samples (the
    /// first [`CALIBRATED_DIMS`] of each; `true` may hold more). Errors: `first_dim` above
    /// [`CALIBRATED_DIMS`], a sample with fewer weights, a non-finite weight, or a gender with
    /// fewer than 2 samples or a constant fitted weight ([`Error::OutOfRange`],
    /// [`Error::NonFinite`], [`Error::Degenerate`]).
    pub fn train(samples: &[(Gender, &[f64], &[f64])], first_dim: usize) -> Result<ShapeCalibration> {
        if first_dim > CALIBRATED_DIMS {
            return Err(Error::OutOfRange {
                name: "first calibrated dimension",
                detail: format!("{first_dim} is above {CALIBRATED_DIMS}"),
            });
        }
        for (_, fit, truth) in samples {
            if fit.len() < CALIBRATED_DIMS || truth.len() < CALIBRATED_DIMS {
                return Err(Error::OutOfRange {
                    name: "shape calibration set",
                    detail: format!(
                        "a sample has {} fitted and {} true weights; need {CALIBRATED_DIMS} of each",
                        fit.len(),
                        truth.len()
                    ),
                });
            }
            for &w in fit[..CALIBRATED_DIMS].iter().chain(&truth[..CALIBRATED_DIMS]) {
                ensure_finite("shape weight", w)?;
            }
        }
        let mut c = ShapeCalibration { first_dim, ..ShapeCalibration::IDENTITY };
        for gender in [Gender::Female, Gender::Male] {
            let set: Vec<_> = samples.iter().filter(|s| s.0 == gender).collect();
            if set.len() < 2 {
                return Err(Error::OutOfRange {
                    name: "shape calibration set",
                    detail: format!("{} {} samples; need at least 2 of each gender", set.len(), gender.name()),
                });
            }
            let n = set.len() as f64;
            for k in first_dim..CALIBRATED_DIMS {
                let mx = set.iter().map(|s| s.1[k]).sum::<f64>() / n;
                let my = set.iter().map(|s| s.2[k]).sum::<f64>() / n;
                let sxx: f64 = set.iter().map(|s| (s.1[k] - mx).powi(2)).sum();
                let sxy: f64 = set.iter().map(|s| (s.1[k] - mx) * (s.2[k] - my)).sum();
                if sxx <= 1e-12 * n {
                    return Err(Error::Degenerate(format!(
                        "shape calibration: the fitted {} weights of dimension {k} do not vary",
                        gender.name()
                    )));
                }
                let slope = sxy / sxx;
                c.slope[gender.index()][k] = slope;
                c.intercept[gender.index()][k] = my - slope * mx;
            }
        }
        Ok(c)
    }
}

/// The fitted body's calibration: the shape map, then the height calibration trained on the
/// mapped bodies' heights (module documentation). Plain data; `Send + Sync`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitCalibration {
    /// Maps the fitted shape weights (gendered fits only).
    pub shape: ShapeCalibration,
    /// Calibrates the mapped body's height.
    pub height: HeightCalibration,
}

impl FitCalibration {
    /// For fits with the user's (or the ground truth's) 2-D joints, fitted on 3600 training
    /// sketches (`make-dataset 1200 --seed 79|80|81 --mocap DIR`, DIR: the DeepMimic clips other
    /// than the shape-fit benchmark's six) fitted with the true gender by a pose step that has
    /// not seen their motion: the clips in two folds, each fold's sketches posed with a
    /// dictionary learned without it (`run-dataset --dictionary`), as a user's drawing is posed
    /// by the shipped dictionary. `scripts/train-fit-calibration.sh` rebuilds it
    /// (docs/benchmarks.md, "Shape calibration").
    pub const SHIPPED: FitCalibration =
        FitCalibration { shape: ShapeCalibration::SHIPPED, height: HeightCalibration::SHIPPED };
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(i: usize, gender: Gender, c: &ShapeCalibration) -> (Gender, Vec<f64>, Vec<f64>) {
        let fit: Vec<f64> = (0..CALIBRATED_DIMS).map(|k| ((i * 7 + k * 3) % 11) as f64 * 0.1 - 0.5).collect();
        let g = gender.index();
        let truth: Vec<f64> = fit
            .iter()
            .enumerate()
            .map(|(k, w)| if k < c.first_dim { 0.3 * w } else { c.intercept[g][k] + c.slope[g][k] * w })
            .collect();
        (gender, fit, truth)
    }

    #[test]
    fn training_recovers_a_known_map_and_leaves_the_lower_dimensions() {
        let mut want = ShapeCalibration { first_dim: 3, ..ShapeCalibration::IDENTITY };
        for g in 0..2 {
            for k in 3..CALIBRATED_DIMS {
                want.slope[g][k] = 1.5 + 0.1 * k as f64 + g as f64;
                want.intercept[g][k] = 0.05 * k as f64 - 0.2 * g as f64;
            }
        }
        let data: Vec<_> =
            (0..30).map(|i| sample(i, if i % 2 == 0 { Gender::Female } else { Gender::Male }, &want)).collect();
        let samples: Vec<(Gender, &[f64], &[f64])> = data.iter().map(|(g, f, t)| (*g, &f[..], &t[..])).collect();
        let got = ShapeCalibration::train(&samples, 3).unwrap();
        assert_eq!(got.first_dim, 3);
        for g in 0..2 {
            for k in 0..CALIBRATED_DIMS {
                assert!((got.slope[g][k] - want.slope[g][k]).abs() < 1e-9, "{got:?}");
                assert!((got.intercept[g][k] - want.intercept[g][k]).abs() < 1e-9, "{got:?}");
            }
        }
        let (g, fit, truth) = &data[1];
        let mapped = got.apply(*g, fit).unwrap().unwrap();
        assert_eq!(mapped[..3], fit[..3], "the lower dimensions keep the fitted weights");
        for k in 3..CALIBRATED_DIMS {
            assert!((mapped[k] - truth[k]).abs() < 1e-9);
        }
    }

    #[test]
    fn other_dimensions_and_bad_input_are_handled() {
        let c = ShapeCalibration { first_dim: 0, ..ShapeCalibration::IDENTITY };
        assert_eq!(c.apply(Gender::Male, &[0.1; 4]).unwrap(), None, "a 4-D fit is left as it is");
        assert!(c.apply(Gender::Male, &[f64::NAN; CALIBRATED_DIMS]).is_err());
        let one = [0.0; CALIBRATED_DIMS];
        let few: Vec<(Gender, &[f64], &[f64])> = vec![
            (Gender::Female, &one[..], &one[..]),
            (Gender::Female, &one[..], &one[..]),
            (Gender::Male, &one[..], &one[..]),
        ];
        assert!(ShapeCalibration::train(&few, 3).is_err(), "one male sample");
        let both: Vec<(Gender, &[f64], &[f64])> =
            (0..6).map(|i| (if i % 2 == 0 { Gender::Female } else { Gender::Male }, &one[..], &one[..])).collect();
        assert!(matches!(ShapeCalibration::train(&both, 3), Err(Error::Degenerate(_))), "constant weights");
        assert!(ShapeCalibration::train(&both, CALIBRATED_DIMS + 1).is_err());
        let short = [0.0; 4];
        let bad: Vec<(Gender, &[f64], &[f64])> = vec![(Gender::Male, &short[..], &one[..])];
        assert!(ShapeCalibration::train(&bad, 3).is_err());
    }
}

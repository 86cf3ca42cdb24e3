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
use crate::error::{ensure_finite, Result};

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

    #[test]
    fn other_dimensions_and_bad_input_are_handled() {
        let c = ShapeCalibration { first_dim: 0, ..ShapeCalibration::IDENTITY };
        assert_eq!(c.apply(Gender::Male, &[0.1; 4]).unwrap(), None, "a 4-D fit is left as it is");
        assert!(c.apply(Gender::Male, &[f64::NAN; CALIBRATED_DIMS]).is_err());
        let mut m = ShapeCalibration { first_dim: 3, ..ShapeCalibration::IDENTITY };
        m.slope[1][4] = 2.0;
        m.intercept[1][4] = 0.5;
        let w = [0.25; CALIBRATED_DIMS];
        let mapped = m.apply(Gender::Male, &w).unwrap().unwrap();
        assert_eq!(mapped[4], 1.0);
        assert_eq!(mapped[..4], w[..4]);
        assert_eq!(m.apply(Gender::Female, &w).unwrap().unwrap(), w.to_vec(), "per gender");
    }
}

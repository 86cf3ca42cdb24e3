//! Training the fitted body's shape map ([`ShapeCalibration`], module documentation of
//! [`sketchbody::fit::calibration`]) from fits of training sketches with known shapes.

use sketchbody::body::Gender;
use sketchbody::error::{ensure_finite, Error, Result};
use sketchbody::fit::{ShapeCalibration, CALIBRATED_DIMS};

/// Least-squares fit, per gender and dimension `k ≥ first_dim`, of the true weight on the
/// fitted one with an intercept, from `(gender, fitted weights, true weights)` samples (the
/// first [`CALIBRATED_DIMS`] of each; `true` may hold more). Errors: `first_dim` above
/// [`CALIBRATED_DIMS`], a sample with fewer weights, a non-finite weight, or a gender with
/// fewer than 2 samples or a constant fitted weight ([`Error::OutOfRange`],
/// [`Error::NonFinite`], [`Error::Degenerate`]).
pub fn train_shape_calibration(samples: &[(Gender, &[f64], &[f64])], first_dim: usize) -> Result<ShapeCalibration> {
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
        let got = train_shape_calibration(&samples, 3).unwrap();
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
    fn bad_training_sets_are_errors() {
        let one = [0.0; CALIBRATED_DIMS];
        let few: Vec<(Gender, &[f64], &[f64])> = vec![
            (Gender::Female, &one[..], &one[..]),
            (Gender::Female, &one[..], &one[..]),
            (Gender::Male, &one[..], &one[..]),
        ];
        assert!(train_shape_calibration(&few, 3).is_err(), "one male sample");
        let both: Vec<(Gender, &[f64], &[f64])> =
            (0..6).map(|i| (if i % 2 == 0 { Gender::Female } else { Gender::Male }, &one[..], &one[..])).collect();
        assert!(matches!(train_shape_calibration(&both, 3), Err(Error::Degenerate(_))), "constant weights");
        assert!(train_shape_calibration(&both, CALIBRATED_DIMS + 1).is_err());
        let short = [0.0; 4];
        let bad: Vec<(Gender, &[f64], &[f64])> = vec![(Gender::Male, &short[..], &one[..])];
        assert!(train_shape_calibration(&bad, 3).is_err());
    }
}

//! Training the fitted body's height calibration ([`HeightCalibration`], module documentation
//! of [`sketchbody::fit::height_calibration`]) by least squares in log height.

use sketchbody::error::{ensure_finite, Error, Result};
use sketchbody::fit::{HeightCalibration, HeightEvidence, NUM_HEIGHT_EVIDENCE};

/// One training sample of [`train_height_calibration`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightSample {
    /// The fitted rest body's height, metres.
    pub fit_height: f64,
    /// The fit's gender value (0 female … 1 male).
    pub gender_value: f64,
    /// The drawing's evidence.
    pub evidence: HeightEvidence,
    /// The true rest height, metres.
    pub true_height: f64,
}

/// Least-squares fit to `samples`, the evidence values marked in `used` as regressors (the
/// others get weight 0; every mean is the training mean of the present values, 0 when none).
/// Errors: fewer samples than coefficients + 1, a non-finite value or non-positive height,
/// or inputs that do not determine the coefficients (one gender only, a constant regressor)
/// — [`Error::OutOfRange`], [`Error::NonFinite`], [`Error::Degenerate`].
pub fn train_height_calibration(
    samples: &[HeightSample],
    used: &[bool; NUM_HEIGHT_EVIDENCE],
) -> Result<HeightCalibration> {
    let cols: Vec<usize> = (0..NUM_HEIGHT_EVIDENCE).filter(|&k| used[k]).collect();
    let n = 3 + cols.len();
    if samples.len() <= n {
        return Err(Error::OutOfRange {
            name: "height calibration set",
            detail: format!("{} samples; need more than {n}", samples.len()),
        });
    }
    let mut sums = [(0.0, 0usize); NUM_HEIGHT_EVIDENCE];
    for s in samples {
        for (name, v) in
            [("fit height", s.fit_height), ("gender value", s.gender_value), ("true height", s.true_height)]
        {
            ensure_finite(name, v)?;
        }
        if s.fit_height <= 0.0 || s.true_height <= 0.0 {
            return Err(Error::OutOfRange {
                name: "height calibration set",
                detail: format!("heights must be > 0 (fitted {} m, true {} m)", s.fit_height, s.true_height),
            });
        }
        for (sum, v) in sums.iter_mut().zip(&s.evidence.values) {
            if let Some(x) = v {
                ensure_finite("height evidence", *x)?;
                sum.0 += x;
                sum.1 += 1;
            }
        }
    }
    let means = sums.map(|(sum, count)| if count > 0 { sum / count as f64 } else { 0.0 });
    let mut ata = nalgebra::DMatrix::<f64>::zeros(n, n);
    let mut atb = nalgebra::DVector::<f64>::zeros(n);
    for s in samples {
        let mut row = nalgebra::DVector::<f64>::zeros(n);
        row[0] = 1.0;
        row[1] = s.fit_height.ln();
        row[2] = s.gender_value;
        for (i, &k) in cols.iter().enumerate() {
            row[3 + i] = s.evidence.values[k].map_or(0.0, |x| x - means[k]);
        }
        ata += &row * row.transpose();
        atb += &row * s.true_height.ln();
    }
    let x = ata
        .cholesky()
        .filter(|c| c.l().diagonal().iter().all(|d| *d > 1e-9))
        .ok_or_else(|| Error::Degenerate("height calibration: the inputs do not determine the coefficients".into()))?
        .solve(&atb);
    let mut evidence_weights = [0.0; NUM_HEIGHT_EVIDENCE];
    for (i, &k) in cols.iter().enumerate() {
        evidence_weights[k] = x[3 + i];
    }
    Ok(HeightCalibration { intercept: x[0], slope: x[1], male: x[2], evidence_means: means, evidence_weights })
}

#[cfg(test)]
mod tests {
    use super::*;

    const NO_WEIGHTS: [f64; NUM_HEIGHT_EVIDENCE] = [0.0; NUM_HEIGHT_EVIDENCE];

    fn plain(intercept: f64, slope: f64, male: f64) -> HeightCalibration {
        HeightCalibration { intercept, slope, male, evidence_means: NO_WEIGHTS, evidence_weights: NO_WEIGHTS }
    }

    fn sample(fit: f64, g: f64, evidence: HeightEvidence, c: &HeightCalibration) -> HeightSample {
        let mut ln_h = c.intercept + c.slope * fit.ln() + c.male * g;
        for k in 0..NUM_HEIGHT_EVIDENCE {
            ln_h += evidence.values[k].map_or(0.0, |x| c.evidence_weights[k] * (x - c.evidence_means[k]));
        }
        HeightSample { fit_height: fit, gender_value: g, evidence, true_height: ln_h.exp() }
    }

    #[test]
    fn training_recovers_a_known_calibration() {
        let truth = plain(-0.2, 1.3, -0.03);
        let samples: Vec<HeightSample> =
            (0..40).map(|i| sample(1.5 + 0.01 * i as f64, (i % 2) as f64, HeightEvidence::NONE, &truth)).collect();
        let got = train_height_calibration(&samples, &[false; NUM_HEIGHT_EVIDENCE]).unwrap();
        for (a, b) in [(got.intercept, truth.intercept), (got.slope, truth.slope), (got.male, truth.male)] {
            assert!((a - b).abs() < 1e-9, "{got:?}");
        }
        assert_eq!(got.evidence_weights, NO_WEIGHTS);
    }

    #[test]
    fn training_recovers_evidence_weights_and_a_missing_value_adds_nothing() {
        let mut truth = plain(-0.25, 1.4, -0.04);
        truth.evidence_weights[1] = 0.08;
        truth.evidence_weights[7] = -0.05;
        let mut used = [false; NUM_HEIGHT_EVIDENCE];
        used[1] = true;
        used[7] = true;
        let evidence = |i: usize| {
            let mut e = HeightEvidence::NONE;
            e.values[1] = Some(((i * 7) % 13) as f64 * 0.02 - 0.1);
            e.values[7] = (!i.is_multiple_of(9)).then(|| ((i * 5) % 11) as f64 * 0.05 - 0.4);
            e.values[2] = Some(i as f64);
            e
        };
        // The training means are the present values' means: put them into the truth first.
        let raw: Vec<HeightEvidence> = (0..60).map(evidence).collect();
        for k in [1, 7] {
            let v: Vec<f64> = raw.iter().filter_map(|e| e.values[k]).collect();
            truth.evidence_means[k] = v.iter().sum::<f64>() / v.len() as f64;
        }
        let samples: Vec<HeightSample> =
            raw.iter().enumerate().map(|(i, e)| sample(1.5 + 0.007 * i as f64, (i % 2) as f64, *e, &truth)).collect();
        let got = train_height_calibration(&samples, &used).unwrap();
        for k in 0..NUM_HEIGHT_EVIDENCE {
            assert!((got.evidence_weights[k] - truth.evidence_weights[k]).abs() < 1e-9, "{k}: {got:?}");
        }
        assert!((got.slope - truth.slope).abs() < 1e-9 && (got.male - truth.male).abs() < 1e-9);
        assert_eq!(got.evidence_weights[2], 0.0, "an unused value gets no weight");
        let mut at_mean = HeightEvidence::NONE;
        at_mean.values[1] = Some(got.evidence_means[1]);
        at_mean.values[7] = Some(got.evidence_means[7]);
        let missing = HeightEvidence::NONE;
        let (a, b) = (got.calibrated(1.7, 1.0, &at_mean).unwrap(), got.calibrated(1.7, 1.0, &missing).unwrap());
        assert!((a - b).abs() < 1e-12, "a missing value is read as the training mean");
        let mut taller = at_mean;
        taller.values[1] = Some(got.evidence_means[1] + 0.1);
        let want = (0.08f64 * 0.1).exp() * a;
        assert!((got.calibrated(1.7, 1.0, &taller).unwrap() - want).abs() < 1e-9);
    }

    #[test]
    fn bad_training_sets_are_errors() {
        let none = HeightEvidence::NONE;
        let s = |fit: f64, g: f64, truth: f64| HeightSample {
            fit_height: fit,
            gender_value: g,
            evidence: none,
            true_height: truth,
        };
        let unused = [false; NUM_HEIGHT_EVIDENCE];
        assert!(matches!(train_height_calibration(&[s(1.7, 0.0, 1.7)], &unused), Err(Error::OutOfRange { .. })));
        let one_gender = [s(1.6, 0.0, 1.6), s(1.7, 0.0, 1.72), s(1.8, 0.0, 1.79), s(1.75, 0.0, 1.7)];
        assert!(matches!(train_height_calibration(&one_gender, &unused), Err(Error::Degenerate(_))));
        let bad = [s(1.6, 0.0, 1.6), s(-1.7, 1.0, 1.72), s(1.8, 0.0, 1.79), s(1.75, 1.0, 1.7)];
        assert!(matches!(train_height_calibration(&bad, &unused), Err(Error::OutOfRange { .. })));
        let mut used = unused;
        used[0] = true;
        let both = [s(1.6, 0.0, 1.6), s(1.7, 1.0, 1.72), s(1.8, 0.0, 1.79), s(1.75, 1.0, 1.7), s(1.65, 0.0, 1.7)];
        assert!(
            matches!(train_height_calibration(&both, &used), Err(Error::Degenerate(_))),
            "an evidence value missing everywhere determines nothing"
        );
    }
}

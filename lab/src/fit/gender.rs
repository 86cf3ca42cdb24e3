//! Training the gender classifier and the final gender decision ([`GenderClassifier`],
//! [`MarginCombination`]) by penalised logistic regression, and recalibrating the decision's
//! intercept on sketches it was not trained on.

use sketchbody::error::{ensure_finite, Error, Result};
use sketchbody::fit::gender_evidence::{sigmoid, NUM_GENDER_FEATURES};
use sketchbody::fit::{GenderClassifier, GenderFeatures, MarginCombination};

/// Fits the classifier to `(features, is_male)` by Newton's method on the L2-penalised
/// log-likelihood (penalty `ridge` × Σ coefficient², the intercept not penalised). Means and
/// scales are the samples' (over the samples where each feature is present).
/// Deterministic. Errors: fewer than 2 samples or a single class, a non-finite or negative
/// ridge ([`Error::OutOfRange`]), a non-finite feature ([`Error::NonFinite`]).
pub fn train_gender_classifier(samples: &[(GenderFeatures, bool)], ridge: f64) -> Result<GenderClassifier> {
    let rows: Vec<(Vec<Option<f64>>, bool)> = samples.iter().map(|(f, m)| (f.values.to_vec(), *m)).collect();
    let fit = fit_logistic(&rows, NUM_GENDER_FEATURES, ridge)?;
    Ok(GenderClassifier {
        means: std::array::from_fn(|k| fit.means[k]),
        scales: std::array::from_fn(|k| fit.scales[k]),
        coefficients: std::array::from_fn(|k| fit.coefficients[k]),
        intercept: fit.intercept,
    })
}

/// Fits the combination to `(classifier log-odds, score margin, is_male)` as
/// [`train_gender_classifier`] does (same errors).
pub fn train_margin_combination(samples: &[(f64, f64, bool)], ridge: f64) -> Result<MarginCombination> {
    let rows: Vec<(Vec<Option<f64>>, bool)> =
        samples.iter().map(|&(z, m, male)| (vec![Some(z), m.is_finite().then_some(m)], male)).collect();
    let fit = fit_logistic(&rows, 2, ridge)?;
    Ok(MarginCombination {
        means: [fit.means[0], fit.means[1]],
        scales: [fit.scales[0], fit.scales[1]],
        coefficients: [fit.coefficients[0], fit.coefficients[1]],
        intercept: fit.intercept,
    })
}

/// The decision by the score margin alone (male fit's best score − female fit's): `P(male) =
/// σ(slope × margin)`, the classifier's log-odds weighted 0 and no intercept (equal scores are
/// an even chance), the slope fitted by maximum likelihood to `(classifier log-odds, score
/// margin, is_male)` (the log-odds ignored). Deterministic (Newton's method on one unknown).
/// Errors: `OutOfRange` without both sexes among the samples with a finite, non-zero margin, or
/// when the margins separate the sexes perfectly (no finite maximum).
pub fn train_margin_only(samples: &[(f64, f64, bool)]) -> Result<MarginCombination> {
    let rows: Vec<(f64, f64, bool)> =
        samples.iter().filter(|s| s.1.is_finite() && s.1 != 0.0).map(|&(_, m, male)| (0.0, m, male)).collect();
    let slope = fit_one_coefficient(&rows, 50.0, "gender margin training set")?;
    Ok(MarginCombination { means: [0.0, 0.0], scales: [1.0, 1.0], coefficients: [0.0, slope], intercept: 0.0 })
}

/// `c` with its intercept refitted (maximum likelihood, the other parameters
/// kept) to `(classifier log-odds, score margin, is_male)` of sketches it was not trained
/// on: a recalibration for sketches whose gender evidence reads one sex more often than the
/// training set's did. Deterministic (Newton's method on one unknown). Errors:
/// `OutOfRange` without both sexes among the samples (the likelihood has no maximum) or
/// when every sample's inputs are non-finite.
pub fn recalibrated(c: &MarginCombination, samples: &[(f64, f64, bool)]) -> Result<MarginCombination> {
    let rows: Vec<(f64, f64, bool)> = samples
        .iter()
        .filter(|(l, m, _)| l.is_finite() || m.is_finite())
        .map(|&(l, m, male)| (c.combined_log_odds(l, m), 1.0, male))
        .collect();
    let shift = fit_one_coefficient(&rows, 2.0, "gender recalibration set")?;
    Ok(MarginCombination { intercept: c.intercept + shift, ..*c })
}

/// The maximum-likelihood `t` of `P(male) = σ(offset + t × x)` over `rows` of `(offset, x,
/// is_male)`, by Newton's method from 0 with each step clamped to ±`max_step`. Errors:
/// `OutOfRange` named `name` without both sexes among the rows, or when `t` does not settle
/// (the rows separate the sexes: no finite maximum).
fn fit_one_coefficient(rows: &[(f64, f64, bool)], max_step: f64, name: &'static str) -> Result<f64> {
    let males = rows.iter().filter(|r| r.2).count();
    if males == 0 || males == rows.len() {
        return Err(Error::OutOfRange {
            name,
            detail: format!("{} usable samples, {males} male: need both sexes", rows.len()),
        });
    }
    let mut t = 0.0f64;
    for _ in 0..200 {
        let (mut gradient, mut curvature) = (0.0, 0.0);
        for &(offset, x, male) in rows {
            let p = sigmoid(offset + t * x);
            gradient += (f64::from(u8::from(male)) - p) * x;
            curvature += p * (1.0 - p) * x * x;
        }
        let step = gradient / curvature.max(1e-12);
        t += step.clamp(-max_step, max_step);
        if !(t.abs() < 1e6) {
            break;
        }
        if step.abs() < 1e-10 * t.abs().max(1.0) {
            return Ok(t);
        }
    }
    Err(Error::OutOfRange {
        name,
        detail: format!("the samples separate the sexes ({t:.3e} did not settle): no finite maximum"),
    })
}

/// A fitted logistic regression on standardised inputs.
struct Logistic {
    means: Vec<f64>,
    scales: Vec<f64>,
    coefficients: Vec<f64>,
    intercept: f64,
}

/// Newton's method on the L2-penalised log-likelihood (penalty `ridge` × Σ coefficient², the
/// intercept not penalised); missing inputs are imputed with the mean (0 after
/// standardisation). Deterministic.
fn fit_logistic(samples: &[(Vec<Option<f64>>, bool)], n: usize, ridge: f64) -> Result<Logistic> {
    ensure_finite("ridge", ridge)?;
    let males = samples.iter().filter(|s| s.1).count();
    if ridge < 0.0 || samples.len() < 2 || males == 0 || males == samples.len() {
        return Err(Error::OutOfRange {
            name: "gender training set",
            detail: format!("{} samples, {males} male, ridge {ridge}: need both classes and ridge ≥ 0", samples.len()),
        });
    }
    let mut means = vec![0.0; n];
    let mut scales = vec![1.0; n];
    for k in 0..n {
        let xs: Vec<f64> = samples.iter().filter_map(|s| s.0.get(k).copied().flatten()).collect();
        for &x in &xs {
            ensure_finite("gender feature", x)?;
        }
        if xs.len() >= 2 {
            let m = xs.iter().sum::<f64>() / xs.len() as f64;
            let v = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (xs.len() - 1) as f64;
            means[k] = m;
            scales[k] = if v > 1e-12 { v.sqrt() } else { 1.0 };
        }
    }
    let rows: Vec<(nalgebra::DVector<f64>, f64)> = samples
        .iter()
        .map(|(f, male)| {
            let x = nalgebra::DVector::from_fn(n + 1, |i, _| {
                if i == 0 {
                    1.0
                } else {
                    f.get(i - 1).copied().flatten().map_or(0.0, |x| (x - means[i - 1]) / scales[i - 1])
                }
            });
            (x, if *male { 1.0 } else { 0.0 })
        })
        .collect();
    let mut beta = nalgebra::DVector::<f64>::zeros(n + 1);
    for _ in 0..100 {
        let mut hess = nalgebra::DMatrix::<f64>::zeros(n + 1, n + 1);
        let mut grad = nalgebra::DVector::<f64>::zeros(n + 1);
        for (x, y) in &rows {
            let p = sigmoid(x.dot(&beta));
            grad += (y - p) * x;
            hess += (p * (1.0 - p)).max(1e-9) * x * x.transpose();
        }
        for k in 1..=n {
            grad[k] -= 2.0 * ridge * beta[k];
            hess[(k, k)] += 2.0 * ridge;
        }
        hess[(0, 0)] += 1e-9;
        let step = hess
            .cholesky()
            .ok_or_else(|| Error::Degenerate("gender classifier: singular Hessian".into()))?
            .solve(&grad);
        beta += &step;
        if step.amax() < 1e-10 {
            break;
        }
    }
    Ok(Logistic { means, scales, coefficients: (1..=n).map(|k| beta[k]).collect(), intercept: beta[0] })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 52 finding 13 (`fit_logistic`'s `-` → `+`): the classifier's means and scales are
    /// the present samples' mean and standard deviation (n − 1), a feature no sample has keeps
    /// 0 and 1 with no weight, and the fitted model solves the penalised likelihood's equations
    /// (Σ (y − p) = 0 for the intercept; Σ (y − p) x_k = 2 ridge β_k for each standardised
    /// feature, missing ones imputed at the mean); likewise the combination without a ridge.
    #[test]
    fn the_fit_standardises_by_the_samples_and_solves_the_penalised_likelihood() {
        // Feature 0 in every sample, feature 1 in every third; overlapping classes.
        let data: Vec<(GenderFeatures, bool)> = (0..60)
            .map(|i| {
                let x = i as f64 / 10.0;
                let mut values = [None; NUM_GENDER_FEATURES];
                values[0] = Some(x);
                if i % 3 == 0 {
                    values[1] = Some((i as f64 * 0.7).sin());
                }
                (GenderFeatures { values }, x + 1.5 * (i as f64 * 1.3).sin() > 3.0)
            })
            .collect();
        for ridge in [1.0, 0.25] {
            let c = train_gender_classifier(&data, ridge).unwrap();
            for k in 0..2 {
                let xs: Vec<f64> = data.iter().filter_map(|d| d.0.values[k]).collect();
                let m = xs.iter().sum::<f64>() / xs.len() as f64;
                let sd = (xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (xs.len() - 1) as f64).sqrt();
                assert!((c.means[k] - m).abs() < 1e-12 && (c.scales[k] - sd).abs() < 1e-12, "feature {k}: {c:?}");
            }
            assert_eq!((c.means[2], c.scales[2], c.coefficients[2]), (0.0, 1.0, 0.0));
            let mut grad = [0.0; 3];
            for (f, male) in &data {
                let r = f64::from(u8::from(*male)) - c.male_probability(f);
                grad[0] += r;
                for k in 0..2 {
                    grad[k + 1] += r * f.values[k].map_or(0.0, |x| (x - c.means[k]) / c.scales[k]);
                }
            }
            let want = [0.0, 2.0 * ridge * c.coefficients[0], 2.0 * ridge * c.coefficients[1]];
            for k in 0..3 {
                assert!((grad[k] - want[k]).abs() < 1e-7, "ridge {ridge}, equation {k}: {grad:?} vs {want:?}");
            }
            assert!(c.coefficients[0] > 0.5, "{c:?}");
        }
        let pairs: Vec<(f64, f64, bool)> = (0..40)
            .map(|i| {
                let z = (i as f64 - 20.0) / 5.0;
                let m = if i % 5 == 0 { f64::NAN } else { 0.3 * (i as f64 * 0.9).cos() };
                (z, m, z + 2.0 * (i as f64 * 2.1).sin() > 0.0)
            })
            .collect();
        let c = train_margin_combination(&pairs, 0.0).unwrap();
        let (mut g0, mut g1, mut g2) = (0.0, 0.0, 0.0);
        for &(z, m, male) in &pairs {
            let r = f64::from(u8::from(male)) - c.male_probability(z, m);
            g0 += r;
            g1 += r * (z - c.means[0]) / c.scales[0];
            g2 += r * if m.is_finite() { (m - c.means[1]) / c.scales[1] } else { 0.0 };
        }
        assert!(g0.abs() < 1e-7 && g1.abs() < 1e-7 && g2.abs() < 1e-7, "{g0} {g1} {g2}");
    }

    #[test]
    fn training_recovers_a_separating_direction_and_rejects_one_class() {
        let sample = |k: f64, male: bool| {
            let mut values = [None; NUM_GENDER_FEATURES];
            values[0] = Some(k);
            values[1] = Some(0.3 * k.sin());
            (GenderFeatures { values }, male)
        };
        let data: Vec<_> = (0..200)
            .map(|i| {
                let x = (i as f64 - 100.0) / 30.0;
                // Overlapping classes: male when x + a deterministic wobble > 0.
                sample(x, x + 0.8 * (i as f64 * 1.7).sin() > 0.0)
            })
            .collect();
        let c = train_gender_classifier(&data, 1.0).unwrap();
        assert!(c.coefficients[0] > 1.0, "{:?}", c.coefficients);
        assert!(c.male_probability(&sample(3.0, true).0) > 0.9);
        assert!(c.male_probability(&sample(-3.0, false).0) < 0.1);
        let one_class: Vec<_> = data.iter().map(|(f, _)| (*f, true)).collect();
        assert!(train_gender_classifier(&one_class, 1.0).is_err());
        assert!(train_gender_classifier(&data, -1.0).is_err());
    }

    #[test]
    fn margin_only_recovers_the_slope_and_ignores_the_classifier() {
        // Males drawn with probability σ(9 × margin); the classifier's log-odds are noise that
        // the decision must not read.
        let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(11);
        let samples: Vec<(f64, f64, bool)> = (0..6000)
            .map(|_| {
                let m = rand::Rng::random_range(&mut rng, -0.6..0.6);
                let l = rand::Rng::random_range(&mut rng, -5.0..5.0);
                (l, m, rand::Rng::random::<f64>(&mut rng) < sigmoid(9.0 * m))
            })
            .collect();
        let c = train_margin_only(&samples).unwrap();
        assert!((c.coefficients[1] - 9.0).abs() < 0.8, "{c:?}");
        assert_eq!((c.coefficients[0], c.intercept), (0.0, 0.0));
        assert_eq!(c.male_probability(-4.0, 0.1), c.male_probability(4.0, 0.1), "the log-odds are not read");
        assert!(c.male_probability(0.0, 0.2) > 0.8 && c.male_probability(0.0, -0.2) < 0.2);
        // Perfectly separated margins, one sex, or no usable margin: no finite slope.
        let separated: Vec<_> = samples.iter().map(|&(l, m, _)| (l, m, m > 0.0)).collect();
        assert!(train_margin_only(&separated).is_err());
        let males: Vec<_> = samples.iter().map(|&(l, m, _)| (l, m, true)).collect();
        assert!(train_margin_only(&males).is_err());
        assert!(train_margin_only(&[(0.0, f64::NAN, true), (0.0, 0.0, false)]).is_err());
    }

    #[test]
    fn recalibration_finds_the_intercept_shift_of_biased_sketches() {
        let base = MarginCombination::SHIPPED;
        // Sketches whose evidence reads 0.8 log-odds too female: males drawn with probability
        // σ(z + 0.8) at the combination's own log-odds z. Deterministic draws.
        let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(7);
        let samples: Vec<(f64, f64, bool)> = (0..4000)
            .map(|_| {
                let (l, m) =
                    (rand::Rng::random_range(&mut rng, -4.0..4.0), rand::Rng::random_range(&mut rng, -0.6..0.6));
                let z = base.combined_log_odds(l, m);
                (l, m, rand::Rng::random::<f64>(&mut rng) < sigmoid(z + 0.8))
            })
            .collect();
        let r = recalibrated(&base, &samples).unwrap();
        let shift = r.intercept - base.intercept;
        assert!((shift - 0.8).abs() < 0.15, "shift {shift}");
        assert_eq!(MarginCombination { intercept: base.intercept, ..r }, base, "only the intercept moves");
        // Sketches as the combination expects them: no shift to speak of.
        let fair: Vec<_> = samples
            .iter()
            .map(|&(l, m, _)| (l, m, rand::Rng::random::<f64>(&mut rng) < base.male_probability(l, m)))
            .collect();
        let kept = recalibrated(&base, &fair).unwrap().intercept - base.intercept;
        assert!(kept.abs() < 0.15, "shift {kept}");
        let nll = |c: &MarginCombination| -> f64 {
            samples
                .iter()
                .map(|&(l, m, male)| {
                    let p = c.male_probability(l, m);
                    -if male { p.ln() } else { (1.0 - p).ln() }
                })
                .sum()
        };
        assert!(nll(&r) < nll(&base));
        // One sex only, or nothing usable: no maximum.
        let males: Vec<_> = samples.iter().map(|&(l, m, _)| (l, m, true)).collect();
        assert!(recalibrated(&base, &males).is_err());
        assert!(recalibrated(&base, &[(f64::NAN, f64::NAN, true), (f64::NAN, f64::NAN, false)]).is_err());
        assert!(recalibrated(&base, &[]).is_err());
    }
}

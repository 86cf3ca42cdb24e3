//! Fitting the facing model ([`sketchbody::detect::facing::FacingModel`]): a multinomial
//! logistic regression of the true facing (from a rendered sketch's camera yaw) on the facing
//! features of each sketch's evidence, with an L2 penalty on every coefficient but the bias.

use sketchbody::detect::facing::{Facing, FacingModel, FACING_MODEL_FORMAT, FEATURES, NUM_FEATURES};
use sketchbody::detect::figure::evidence_facing_features;
use sketchbody::error::{Error, Result};

use super::backends::Sample;

/// Gradient steps of [`fit_multinomial`].
const STEPS: usize = 4000;

/// Fits the four-facing softmax model on features `x` (each row [`NUM_FEATURES`] long, the
/// first the bias 1) and classes `y` (0..4, [`sketchbody::detect::facing::FACINGS`]' order) with
/// penalty `ridge` (on the standardised features). Features are standardised for the fit and
/// the coefficients mapped back to raw features. Errors: `OutOfRange` when a class has no row.
pub fn fit_multinomial(x: &[[f64; NUM_FEATURES]], y: &[usize], ridge: f64) -> Result<Vec<Vec<f64>>> {
    let n = x.len();
    for k in 0..4 {
        if !y.contains(&k) {
            return Err(Error::OutOfRange { name: "facing rows", detail: format!("no row of class {k} in {n}") });
        }
    }
    let mut mean = [0.0; NUM_FEATURES];
    let mut sd = [1.0; NUM_FEATURES];
    for f in 1..NUM_FEATURES {
        mean[f] = x.iter().map(|r| r[f]).sum::<f64>() / n as f64;
        let v = x.iter().map(|r| (r[f] - mean[f]).powi(2)).sum::<f64>() / n as f64;
        sd[f] = if v > 1e-12 { v.sqrt() } else { 1.0 };
    }
    let z: Vec<[f64; NUM_FEATURES]> =
        x.iter().map(|r| std::array::from_fn(|f| if f == 0 { 1.0 } else { (r[f] - mean[f]) / sd[f] })).collect();
    let mut w = vec![[0.0; NUM_FEATURES]; 4];
    let rate = 0.5;
    for _ in 0..STEPS {
        let mut grad = vec![[0.0; NUM_FEATURES]; 4];
        for (r, &c) in z.iter().zip(y) {
            let s: Vec<f64> = w.iter().map(|wk| wk.iter().zip(r).map(|(a, b)| a * b).sum()).collect();
            let p = sketchbody::detect::facing::softmax(&s);
            for k in 0..4 {
                let e = p[k] - f64::from(u8::from(k == c));
                for f in 0..NUM_FEATURES {
                    grad[k][f] += e * r[f] / n as f64;
                }
            }
        }
        for k in 0..4 {
            for f in 0..NUM_FEATURES {
                let pen = if f == 0 { 0.0 } else { ridge * w[k][f] };
                w[k][f] -= rate * (grad[k][f] + pen);
            }
        }
    }
    Ok(w.iter()
        .map(|wk| {
            let mut raw = vec![0.0; NUM_FEATURES];
            raw[0] = wk[0];
            for f in 1..NUM_FEATURES {
                raw[f] = wk[f] / sd[f];
                raw[0] -= wk[f] * mean[f] / sd[f];
            }
            raw
        })
        .collect())
}

/// The facing model fitted on `samples` (those with a yaw and evidence of a figure). Errors:
/// as [`fit_multinomial`].
pub fn fit_facing(samples: &[Sample], ridge: f64, provenance: &str) -> Result<FacingModel> {
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for s in samples {
        let Some(yaw) = s.yaw_deg else { continue };
        if s.evidence.sketch.is_none() && s.evidence.blazepose.is_none() {
            continue;
        }
        x.push(evidence_facing_features(&s.evidence));
        y.push(Facing::of_yaw(yaw).index().unwrap_or(0));
    }
    Ok(FacingModel {
        format: FACING_MODEL_FORMAT.into(),
        version: 1,
        provenance: provenance.into(),
        features: FEATURES.iter().map(|f| f.to_string()).collect(),
        weights: fit_multinomial(&x, &y, ridge)?,
    })
}

/// The decided facing ([`sketchbody::detect::facing::decided`]) of `model` against the true one
/// on `samples` with a yaw: `table[true][decided]`, true in front, back, left, right, decided the
/// same then `unknown`.
pub fn confusion(samples: &[Sample], model: &FacingModel) -> [[usize; 5]; 4] {
    let mut t = [[0usize; 5]; 4];
    for s in samples {
        let Some(yaw) = s.yaw_deg else { continue };
        if s.evidence.sketch.is_none() && s.evidence.blazepose.is_none() {
            continue;
        }
        let p = model.probabilities(&evidence_facing_features(&s.evidence));
        let d = sketchbody::detect::facing::decided(&p).index().unwrap_or(4);
        t[Facing::of_yaw(yaw).index().unwrap_or(0)][d] += 1;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Classes separated by one feature are recovered, the probabilities follow it, and a
    /// class without rows is refused.
    #[test]
    fn the_fit_separates_classes_by_their_feature() {
        let mut x = Vec::new();
        let mut y = Vec::new();
        for i in 0..200 {
            let c = i % 4;
            let mut r = [0.0; NUM_FEATURES];
            r[0] = 1.0;
            r[2] = [1.0, -1.0, 0.0, 0.0][c] + 0.01 * (i as f64 % 7.0);
            r[10] = [0.0, 0.0, -1.0, 1.0][c];
            x.push(r);
            y.push(c);
        }
        let w = fit_multinomial(&x, &y, 1e-3).unwrap();
        let m = FacingModel {
            format: FACING_MODEL_FORMAT.into(),
            version: 1,
            provenance: "test".into(),
            features: FEATURES.iter().map(|f| f.to_string()).collect(),
            weights: w,
        };
        for (r, &c) in x.iter().zip(&y) {
            let p = m.probabilities(r);
            assert!(p[c] > 0.8, "class {c}: {p:?}");
        }
        assert!(fit_multinomial(&x[..1], &y[..1], 1e-3).is_err());
    }
}

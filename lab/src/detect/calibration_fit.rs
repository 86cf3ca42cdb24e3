//! Fitting the detector's calibrated confidences ([`sketchbody::detect::calibration`]): one
//! penalised logistic model per backend and use.

use nalgebra::{DMatrix, DVector};
use sketchbody::detect::calibration::Coefficients;
use sketchbody::error::{Error, Result};

/// Fits a logistic model to rows `x` (each starting with 1) and outcomes `y` ∈ {0, 1} by Newton's
/// method with an L2 penalty `ridge` on every coefficient but the intercept. Errors:
/// `OutOfRange` for no rows, rows of differing lengths or non-finite features; `Degenerate` when
/// the Newton system is singular.
pub fn fit_logistic(x: &[Vec<f64>], y: &[bool], ridge: f64) -> Result<Coefficients> {
    let n = x.len();
    if n == 0 || n != y.len() {
        return Err(Error::OutOfRange { name: "calibration rows", detail: format!("{n} rows, {} outcomes", y.len()) });
    }
    let k = x[0].len();
    if x.iter().any(|r| r.len() != k || r.iter().any(|v| !v.is_finite())) {
        return Err(Error::OutOfRange { name: "calibration rows", detail: "ragged or non-finite features".into() });
    }
    let mut w = DVector::<f64>::zeros(k);
    for _ in 0..50 {
        let mut g = DVector::<f64>::zeros(k);
        let mut h = DMatrix::<f64>::zeros(k, k);
        for (r, &t) in x.iter().zip(y) {
            let xr = DVector::from_column_slice(r);
            let p = 1.0 / (1.0 + (-w.dot(&xr)).exp());
            g += &xr * (p - if t { 1.0 } else { 0.0 });
            h += &xr * xr.transpose() * (p * (1.0 - p)).max(1e-9);
        }
        for i in 1..k {
            g[i] += ridge * w[i];
            h[(i, i)] += ridge;
        }
        let step = h.lu().solve(&g).ok_or_else(|| Error::Degenerate("singular logistic Newton system".into()))?;
        w -= &step;
        if step.amax() < 1e-10 {
            break;
        }
    }
    Ok(w.iter().copied().collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use sketchbody::detect::calibration::predict;

    /// Data drawn from a known logistic model is fitted back close to it, and the fitted
    /// probabilities are calibrated (mean prediction = observed rate per half).
    #[test]
    fn logistic_fit_recovers_a_known_model() {
        let truth = [0.5, 2.0, -1.5];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let (mut x, mut y) = (Vec::new(), Vec::new());
        for _ in 0..4000 {
            let r = vec![1.0, rng.random_range(-2.0..2.0), rng.random_range(-1.0..1.0)];
            let p = predict(&truth, &r).unwrap();
            y.push(rng.random::<f64>() < p);
            x.push(r);
        }
        let w = fit_logistic(&x, &y, 1e-6).unwrap();
        for (a, b) in w.iter().zip(truth) {
            assert!((a - b).abs() < 0.25, "{w:?} vs {truth:?}");
        }
        let hi: Vec<usize> = (0..x.len()).filter(|&i| x[i][1] > 0.0).collect();
        let mean_p = hi.iter().map(|&i| predict(&w, &x[i]).unwrap()).sum::<f64>() / hi.len() as f64;
        let rate = hi.iter().filter(|&&i| y[i]).count() as f64 / hi.len() as f64;
        assert!((mean_p - rate).abs() < 0.01, "{mean_p} vs {rate}");
        assert!(fit_logistic(&[], &[], 0.0).is_err());
        assert!(fit_logistic(&[vec![1.0, f64::NAN]], &[true], 0.0).is_err());
    }
}

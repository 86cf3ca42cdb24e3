//! Fitting the GMM prior: k-means++ seeding, Lloyd iterations, then EM with full covariances
//! regularised by `ε · diag(global variance)`. Seeded; deterministic.

use nalgebra::{DMatrix, DVector};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};

use super::super::gmm::Gmm;

/// EM settings.
#[derive(Clone, Copy, Debug)]
pub struct EmOptions {
    /// Number of mixture components.
    pub components: usize,
    /// ε: each covariance gets ε times the data's per-dimension variance added to its diagonal.
    pub regularisation: f64,
    /// Iteration cap.
    pub max_iterations: usize,
    /// Stop when the mean log-likelihood per point changes by less than this (it can fall slightly
    /// because of the regularisation, so a change either way counts).
    pub tolerance: f64,
}

impl Default for EmOptions {
    fn default() -> Self {
        EmOptions { components: 30, regularisation: 0.01, max_iterations: 500, tolerance: 1e-7 }
    }
}

/// The fitted mixture, its mean log-likelihood per point and the EM iterations run.
pub struct EmFit {
    /// The mixture.
    pub gmm: Gmm,
    /// Mean log-likelihood of the data, nats per point.
    pub mean_log_likelihood: f64,
    /// EM iterations run.
    pub iterations: usize,
}

fn dist2(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).norm_squared()
}

/// k-means++ seeding followed by up to 50 Lloyd iterations; returns the cluster of each point.
fn kmeans(x: &[DVector<f64>], k: usize, rng: &mut ChaCha8Rng) -> Vec<usize> {
    let n = x.len();
    let mut centres = vec![x[rng.random_range(0..n)].clone()];
    let mut d2: Vec<f64> = x.iter().map(|p| dist2(p, &centres[0])).collect();
    while centres.len() < k {
        let total: f64 = d2.iter().sum();
        let next = if total > 0.0 {
            let target = rng.random::<f64>() * total;
            let mut acc = 0.0;
            d2.iter()
                .position(|d| {
                    acc += d;
                    acc > target
                })
                .unwrap_or(n - 1)
        } else {
            rng.random_range(0..n)
        };
        centres.push(x[next].clone());
        for (d, p) in d2.iter_mut().zip(x) {
            *d = d.min(dist2(p, &x[next]));
        }
    }
    let nearest = |p: &DVector<f64>, centres: &[DVector<f64>]| {
        (0..centres.len())
            .min_by(|&a, &b| dist2(p, &centres[a]).total_cmp(&dist2(p, &centres[b])).then(a.cmp(&b)))
            .unwrap_or(0)
    };
    let mut assign: Vec<usize> = x.iter().map(|p| nearest(p, &centres)).collect();
    for _ in 0..50 {
        for (c, centre) in centres.iter_mut().enumerate() {
            let members: Vec<&DVector<f64>> = x.iter().zip(&assign).filter(|(_, &a)| a == c).map(|(p, _)| p).collect();
            if !members.is_empty() {
                *centre = members.iter().fold(DVector::zeros(p_dims(x)), |s, p| s + *p) / members.len() as f64;
            }
        }
        let next: Vec<usize> = x.iter().map(|p| nearest(p, &centres)).collect();
        if next == assign {
            break;
        }
        assign = next;
    }
    assign
}

fn p_dims(x: &[DVector<f64>]) -> usize {
    x[0].len()
}

/// Weighted mean and regularised covariance of `x` with weights `r` (total `nk`).
fn moments(x: &[DVector<f64>], r: &[f64], nk: f64, reg: &DMatrix<f64>) -> (DVector<f64>, DMatrix<f64>) {
    let d = p_dims(x);
    let mean = x.iter().zip(r).fold(DVector::zeros(d), |s, (p, w)| s + p * *w) / nk;
    let mut cov = DMatrix::zeros(d, d);
    for (p, w) in x.iter().zip(r) {
        let c = p - &mean;
        cov += &c * c.transpose() * *w;
    }
    (mean, cov / nk + reg)
}

/// Fits a GMM to the rows of `data` (each of the same length ≥ 1; at least `components` rows).
pub fn fit_gmm(data: &[Vec<f64>], opts: &EmOptions, rng: &mut ChaCha8Rng) -> Result<EmFit> {
    let (n, k) = (data.len(), opts.components);
    if k == 0 || n < k || data[0].is_empty() {
        return Err(Error::OutOfRange { name: "GMM fit sizes", detail: format!("{n} points for {k} components") });
    }
    let x: Vec<DVector<f64>> = data.iter().map(|r| DVector::from_column_slice(r)).collect();
    let d = p_dims(&x);
    let ones = vec![1.0; n];
    let (_, global) = moments(&x, &ones, n as f64, &DMatrix::zeros(d, d));
    let reg = DMatrix::from_diagonal(&(global.diagonal() * opts.regularisation));
    let assign = kmeans(&x, k, rng);
    let mut resp: Vec<Vec<f64>> =
        (0..k).map(|c| assign.iter().map(|&a| if a == c { 1.0 } else { 0.0 }).collect()).collect();
    let mut prev = f64::NEG_INFINITY;
    let mut iterations = 0;
    loop {
        // M step (from the current responsibilities).
        let mut weights = Vec::with_capacity(k);
        let mut means = Vec::with_capacity(k);
        let mut covs = Vec::with_capacity(k);
        for r in &resp {
            let nk: f64 = r.iter().sum();
            if nk < 1e-8 {
                weights.push(1e-8);
                means.push(DVector::zeros(d));
                covs.push(&global + &reg);
            } else {
                let (m, s) = moments(&x, r, nk, &reg);
                weights.push(nk);
                means.push(m);
                covs.push(s);
            }
        }
        let total: f64 = weights.iter().sum();
        let weights: Vec<f64> = weights.iter().map(|w| w / total).collect();
        let gmm = Gmm::new(weights, means, covs)?;
        // E step.
        let mut ll = 0.0;
        let mut logs = vec![vec![0.0; n]; k];
        for (i, p) in data.iter().enumerate() {
            let terms: Vec<f64> = (0..k).map(|c| gmm.component_log_density(c, p)).collect();
            let max = terms.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            let lse = max + terms.iter().map(|t| (t - max).exp()).sum::<f64>().ln();
            ll += lse;
            for c in 0..k {
                logs[c][i] = (terms[c] - lse).exp();
            }
        }
        let mean_ll = ll / n as f64;
        iterations += 1;
        if (mean_ll - prev).abs() < opts.tolerance || iterations >= opts.max_iterations {
            return Ok(EmFit { gmm, mean_log_likelihood: mean_ll, iterations });
        }
        prev = mean_ll;
        resp = logs;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn separates_two_clusters_reproducibly() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let noise = Normal::new(0.0, 0.1).unwrap();
        let data: Vec<Vec<f64>> = (0..200)
            .map(|i| {
                let c = if i % 4 == 0 { 5.0 } else { -1.0 };
                vec![c + noise.sample(&mut rng), noise.sample(&mut rng)]
            })
            .collect();
        let opts = EmOptions { components: 2, ..EmOptions::default() };
        let fit = fit_gmm(&data, &opts, &mut ChaCha8Rng::seed_from_u64(9)).unwrap();
        let again = fit_gmm(&data, &opts, &mut ChaCha8Rng::seed_from_u64(9)).unwrap();
        assert_eq!(fit.gmm.weights(), again.gmm.weights());
        let mut w: Vec<f64> = fit.gmm.weights().to_vec();
        w.sort_by(f64::total_cmp);
        assert!((w[0] - 0.25).abs() < 1e-6 && (w[1] - 0.75).abs() < 1e-6, "weights {w:?}");
        assert!(fit_gmm(&data[..1], &opts, &mut ChaCha8Rng::seed_from_u64(9)).is_err());
    }
}

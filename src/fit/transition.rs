//! The SIR transition of paper eq. (9), sampled exactly: `N(y; y_prev, Σ) · Σ_k π_k N(y; μ_k, C_k)`
//! is, up to normalisation, the mixture `Σ_k π'_k N(y; m_k, C'_k)` with
//! `C'_k = (Σ⁻¹ + C_k⁻¹)⁻¹`, `m_k = C'_k (Σ⁻¹ y_prev + C_k⁻¹ μ_k)` and
//! `π'_k ∝ π_k N(y_prev; μ_k, Σ + C_k)`.

use nalgebra::{DMatrix, DVector};
use rand::Rng;
use rand_distr::StandardNormal;

use crate::body::Gmm;
use crate::error::{Error, Result};

/// Per-component matrices of the product, precomputed once per fit.
struct ProductComponent {
    /// ln π_k − ½ ln det(Σ + C_k) (the shared −d/2 ln 2π is dropped).
    log_weight: f64,
    mean: DVector<f64>,
    /// Lower Cholesky factor of Σ + C_k (for the component weights).
    chol_sum: DMatrix<f64>,
    /// C'_k Σ⁻¹ (maps y_prev into the component mean).
    gain: DMatrix<f64>,
    /// C'_k C_k⁻¹ μ_k.
    offset: DVector<f64>,
    /// Lower Cholesky factor of C'_k (for drawing).
    chol_post: DMatrix<f64>,
}

/// The exact eq. (9) sampler for one prior and one diagonal transition covariance Σ.
pub struct Transition {
    components: Vec<ProductComponent>,
}

fn cholesky(m: DMatrix<f64>, what: &str) -> Result<DMatrix<f64>> {
    nalgebra::Cholesky::new(m)
        .map(|c| c.l())
        .ok_or_else(|| Error::CorruptData(format!("{what} is not positive definite")))
}

impl Transition {
    /// Builds the sampler for `prior` and `Σ = diag(sigma_diag)` (same length as the prior's
    /// dimension, all > 0).
    pub fn new(prior: &Gmm, sigma_diag: &[f64]) -> Result<Transition> {
        let d = prior.dims();
        if sigma_diag.len() != d || sigma_diag.iter().any(|&s| !(s > 0.0 && s.is_finite())) {
            return Err(Error::OutOfRange {
                name: "transition covariance",
                detail: format!("need {d} positive entries"),
            });
        }
        let sigma = DMatrix::from_diagonal(&DVector::from_column_slice(sigma_diag));
        let sigma_inv = DMatrix::from_diagonal(&DVector::from_iterator(d, sigma_diag.iter().map(|s| 1.0 / s)));
        let mut components = Vec::with_capacity(prior.num_components());
        for ((&pi, mu), c) in prior.weights().iter().zip(prior.means()).zip(prior.covariances()) {
            let chol_sum = cholesky(&sigma + c, "Σ + C_k")?;
            let log_det: f64 = chol_sum.diagonal().iter().map(|v| 2.0 * v.ln()).sum();
            let c_inv =
                c.clone().try_inverse().ok_or_else(|| Error::CorruptData("GMM covariance is singular".into()))?;
            let post = (&sigma_inv + &c_inv)
                .try_inverse()
                .ok_or_else(|| Error::CorruptData("transition product covariance is singular".into()))?;
            let post = (&post + post.transpose()) * 0.5;
            components.push(ProductComponent {
                log_weight: pi.ln() - 0.5 * log_det,
                mean: mu.clone(),
                chol_sum,
                gain: &post * &sigma_inv,
                offset: &post * (&c_inv * mu),
                chol_post: cholesky(post, "C'_k")?,
            });
        }
        Ok(Transition { components })
    }

    /// Draws one successor of `prev` (length = the prior's dimension).
    pub fn sample<R: Rng + ?Sized>(&self, prev: &[f64], rng: &mut R) -> Vec<f64> {
        let y = DVector::from_column_slice(prev);
        let logs: Vec<f64> = self
            .components
            .iter()
            .map(|c| {
                let diff = &y - &c.mean;
                let z = c.chol_sum.solve_lower_triangular(&diff).unwrap_or(diff);
                c.log_weight - 0.5 * z.norm_squared()
            })
            .collect();
        let max = logs.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let probs: Vec<f64> = logs.iter().map(|l| (l - max).exp()).collect();
        let total: f64 = probs.iter().sum();
        let mut u: f64 = rng.random::<f64>() * total;
        let mut k = probs.len() - 1;
        for (i, p) in probs.iter().enumerate() {
            if u < *p {
                k = i;
                break;
            }
            u -= p;
        }
        let c = &self.components[k];
        let z = DVector::from_iterator(y.len(), (0..y.len()).map(|_| rng.sample::<f64, _>(StandardNormal)));
        let mean = &c.gain * &y + &c.offset;
        (mean + &c.chol_post * z).iter().copied().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// One 1-D component: the product of N(y; a, s) and N(y; m, c) is N((a c + m s)/(s + c), s c/(s + c)).
    #[test]
    fn one_dimensional_product_has_the_closed_form_moments() {
        let prior =
            Gmm::new(vec![1.0], vec![DVector::from_vec(vec![2.0])], vec![DMatrix::from_element(1, 1, 4.0)]).unwrap();
        let t = Transition::new(&prior, &[1.0]).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let n = 40000;
        let xs: Vec<f64> = (0..n).map(|_| t.sample(&[-1.0], &mut rng)[0]).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!((mean - (-4.0 + 2.0 * 1.0) / 5.0).abs() < 0.02, "mean {mean}");
        assert!((var - 0.8).abs() < 0.03, "variance {var}");
    }

    /// Two far-apart components: the one nearer the previous sample dominates.
    #[test]
    fn component_choice_follows_the_previous_sample() {
        let means = vec![DVector::from_vec(vec![-10.0]), DVector::from_vec(vec![10.0])];
        let covs = vec![DMatrix::from_element(1, 1, 1.0), DMatrix::from_element(1, 1, 1.0)];
        let prior = Gmm::new(vec![0.5, 0.5], means, covs).unwrap();
        let t = Transition::new(&prior, &[1.0]).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let positive = (0..1000).filter(|_| t.sample(&[9.0], &mut rng)[0] > 0.0).count();
        assert!(positive > 990, "{positive}");
        assert!(Transition::new(&prior, &[0.0]).is_err());
    }
}

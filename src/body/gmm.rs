//! Gaussian mixture prior over PCA shape weights (paper §II-C): evaluation and sampling.
//! Fitting (EM) is build-time code in `body::build::em`.

use nalgebra::{DMatrix, DVector};
use rand::Rng;
use rand_distr::StandardNormal;

use crate::error::{Error, Result};

/// A Gaussian mixture with full covariances over the first [`Gmm::dims`] PCA weights of a shape
/// space (same units as [`super::ShapeSpace::synthesize`]'s weights: metres along unit-norm basis
/// vectors). Immutable after construction; `Send + Sync`.
#[derive(Clone, Debug)]
pub struct Gmm {
    weights: Vec<f64>,
    means: Vec<DVector<f64>>,
    covariances: Vec<DMatrix<f64>>,
    /// Lower Cholesky factors of the covariances.
    chol: Vec<DMatrix<f64>>,
    /// ln of weight − ½ ln det Σ − (d/2) ln 2π, per component.
    log_norm: Vec<f64>,
}

impl Gmm {
    /// Builds a mixture from component weights (positive, summing to 1 within 1e-4; kept as given
    /// and normalised only inside the density),
    /// means (each of length `dims`) and covariances (`dims × dims`, symmetric positive definite).
    /// Any violation is an [`Error::CorruptData`] naming the component.
    pub fn new(weights: Vec<f64>, means: Vec<DVector<f64>>, covariances: Vec<DMatrix<f64>>) -> Result<Gmm> {
        let k = weights.len();
        if k == 0 || means.len() != k || covariances.len() != k {
            return Err(Error::CorruptData(format!(
                "GMM needs matching non-zero counts of weights, means and covariances (got {}, {}, {})",
                k,
                means.len(),
                covariances.len()
            )));
        }
        let dims = means[0].len();
        if dims == 0 {
            return Err(Error::CorruptData("GMM has zero dimensions".into()));
        }
        let total: f64 = weights.iter().sum();
        if weights.iter().any(|w| !w.is_finite() || *w <= 0.0) || (total - 1.0).abs() > 1e-4 {
            return Err(Error::CorruptData(format!("GMM weights must be positive and sum to 1 (sum {total})")));
        }
        let mut chol = Vec::with_capacity(k);
        let mut log_norm = Vec::with_capacity(k);
        for c in 0..k {
            let (m, s) = (&means[c], &covariances[c]);
            if m.len() != dims || s.nrows() != dims || s.ncols() != dims {
                return Err(Error::CorruptData(format!("GMM component {c} does not have {dims} dimensions")));
            }
            if m.iter().chain(s.iter()).any(|v| !v.is_finite()) {
                return Err(Error::CorruptData(format!("GMM component {c} has a non-finite mean or covariance")));
            }
            let l = s
                .clone()
                .cholesky()
                .ok_or_else(|| Error::CorruptData(format!("GMM covariance {c} is not positive definite")))?
                .l();
            let log_det: f64 = 2.0 * l.diagonal().iter().map(|d| d.ln()).sum::<f64>();
            let w = weights[c] / total;
            log_norm.push(w.ln() - 0.5 * log_det - 0.5 * dims as f64 * (2.0 * std::f64::consts::PI).ln());
            chol.push(l);
        }
        Ok(Gmm { weights, means, covariances, chol, log_norm })
    }

    /// Number of weights a point has.
    pub fn dims(&self) -> usize {
        self.means[0].len()
    }

    /// Number of mixture components.
    pub fn num_components(&self) -> usize {
        self.weights.len()
    }

    /// Component weights (sum 1 within 1e-4).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Component means.
    pub fn means(&self) -> &[DVector<f64>] {
        &self.means
    }

    /// Component covariances.
    pub fn covariances(&self) -> &[DMatrix<f64>] {
        &self.covariances
    }

    /// Natural log of the mixture density at `x` (`x.len()` must equal [`Gmm::dims`], entries finite).
    pub fn log_pdf(&self, x: &[f64]) -> Result<f64> {
        if x.len() != self.dims() {
            return Err(Error::OutOfRange {
                name: "GMM point length",
                detail: format!("got {} weights, the prior has {} dimensions", x.len(), self.dims()),
            });
        }
        for &v in x {
            crate::error::ensure_finite("shape weight", v)?;
        }
        let terms: Vec<f64> = (0..self.weights.len()).map(|c| self.component_log_density(c, x)).collect();
        let max = terms.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        Ok(max + terms.iter().map(|t| (t - max).exp()).sum::<f64>().ln())
    }

    /// ln(weight_c · N(x; mean_c, cov_c)) for a point of the right length (unchecked).
    pub(crate) fn component_log_density(&self, c: usize, x: &[f64]) -> f64 {
        let d = DVector::from_column_slice(x) - &self.means[c];
        let z = self.chol[c].solve_lower_triangular(&d).unwrap_or(d);
        self.log_norm[c] - 0.5 * z.norm_squared()
    }

    /// Draws one point: a component by weight, then its Gaussian (mean + L·z, z standard normal).
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec<f64> {
        let u: f64 = rng.random();
        let mut acc = 0.0;
        let mut c = self.weights.len() - 1;
        for (i, w) in self.weights.iter().enumerate() {
            acc += w;
            if u < acc {
                c = i;
                break;
            }
        }
        let z = DVector::from_iterator(self.dims(), (0..self.dims()).map(|_| rng.sample::<f64, _>(StandardNormal)));
        (&self.means[c] + &self.chol[c] * z).iter().copied().collect()
    }

    /// Per dimension, the smallest and largest of `mean ± k_sd · sd` over the components: the
    /// box in which the prior puts essentially all its mass for `k_sd` ≈ 3 (the fit keeps its
    /// weights in it, [`crate::fit::PRIOR_RANGE_SD`]).
    pub fn range(&self, k_sd: f64) -> Vec<(f64, f64)> {
        (0..self.dims())
            .map(|d| {
                self.means.iter().zip(&self.covariances).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (m, c)| {
                    let sd = c[(d, d)].max(0.0).sqrt();
                    (lo.min(m[d] - k_sd * sd), hi.max(m[d] + k_sd * sd))
                })
            })
            .collect()
    }

    /// The mixture's marginal over its first `dims` weights (1..=[`Gmm::dims`]): same component
    /// weights, leading sub-vectors of the means and leading blocks of the covariances.
    pub fn marginal(&self, dims: usize) -> Result<Gmm> {
        if dims == 0 || dims > self.dims() {
            return Err(Error::OutOfRange {
                name: "GMM marginal dimensions",
                detail: format!("{dims} not in 1..={}", self.dims()),
            });
        }
        let means = self.means.iter().map(|m| m.rows(0, dims).into_owned()).collect();
        let covs = self.covariances.iter().map(|s| s.view((0, 0), (dims, dims)).into_owned()).collect();
        Gmm::new(self.weights.clone(), means, covs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn two_component() -> Gmm {
        let means = vec![DVector::from_vec(vec![0.0, 0.0]), DVector::from_vec(vec![3.0, 1.0])];
        let covs = vec![DMatrix::identity(2, 2), DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.5, 1.0])];
        Gmm::new(vec![0.25, 0.75], means, covs).unwrap()
    }

    #[test]
    fn log_pdf_matches_closed_form_for_one_component() {
        let g =
            Gmm::new(vec![1.0], vec![DVector::from_vec(vec![1.0])], vec![DMatrix::from_element(1, 1, 4.0)]).unwrap();
        let expected = -0.5 * (2.0 * std::f64::consts::PI * 4.0).ln() - 0.5 * (2.0f64 * 2.0) / 4.0;
        let got = g.log_pdf(&[3.0]).unwrap();
        assert!((got - expected).abs() < 1e-12, "got {got}, expected {expected} (eps 1e-12)");
    }

    #[test]
    fn samples_follow_the_mixture_mean_and_are_reproducible() {
        let g = two_component();
        let draw = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            (0..20000).map(|_| g.sample(&mut rng)).collect::<Vec<_>>()
        };
        let a = draw(7);
        assert_eq!(a, draw(7));
        let mean_x: f64 = a.iter().map(|p| p[0]).sum::<f64>() / a.len() as f64;
        assert!((mean_x - 2.25).abs() < 0.05, "sample mean {mean_x}, expected 2.25 (eps 0.05)");
    }

    #[test]
    fn rejects_bad_points_and_bad_parameters() {
        let g = two_component();
        assert!(matches!(g.log_pdf(&[1.0]), Err(Error::OutOfRange { .. })));
        assert!(matches!(g.log_pdf(&[1.0, f64::NAN]), Err(Error::NonFinite { .. })));
        let bad = Gmm::new(vec![1.0], vec![DVector::from_vec(vec![0.0])], vec![DMatrix::from_element(1, 1, -1.0)]);
        assert!(matches!(bad, Err(Error::CorruptData(m)) if m.contains("positive definite")));
        assert!(Gmm::new(vec![0.5], vec![DVector::from_vec(vec![0.0])], vec![DMatrix::identity(1, 1)]).is_err());
    }

    #[test]
    fn marginal_keeps_leading_dimensions() {
        let g = two_component().marginal(1).unwrap();
        assert_eq!(g.dims(), 1);
        assert_eq!(g.covariances()[1][(0, 0)], 2.0);
        assert!(two_component().marginal(3).is_err());
    }
}

//! The both-sexes shape space: gender as a continuous shape weight, built at load time from the
//! model's two gendered spaces (the `.skbm` format is unchanged).
//!
//! MakeHuman's gender macro blends its female and male targets linearly (0 = female … 1 = male,
//! `../shared/data/makehuman.md`); the gendered training sets use the ends only. The blended
//! space models a human at gender `t` as its gendered counterpart moved by the fraction of the
//! mean male − female difference δ that separates `t` from its own end (exact for MakeHuman's
//! macro targets when the other macros are the population average, an approximation otherwise).
//!
//! Construction (deterministic, no random step):
//! 1. Every shape of either space lies in the span of both bases and δ (≤ 33 vectors); they are
//!    orthonormalised (modified Gram–Schmidt, f64) and all later work is in that small frame.
//! 2. Component 0 is δ / |δ| ("the gender weight"); components 1.. are the principal axes,
//!    orthogonal to it, of the population covariance: the two gendered populations (PCA weights
//!    with the stored variances) at the ends and any shifted in-between levels of
//!    [`GENDER_LEVELS`], weighted by [`LEVEL_WEIGHTS`] (default: the ends only).
//! 3. The prior is exact, not re-fitted: every gendered GMM component mapped through the (affine)
//!    change of coordinates, once per level, and shifted to it (its covariance gets the stored
//!    variances of the gendered components the GMM does not cover, plus a ridge of 1e-3 × the
//!    population variance per axis so every covariance stays positive definite).
//! 4. Joints: the least-squares linear map from blended weights to joints over both gendered
//!    spaces (means weighted 100 : 1 against each component's ±1 sd displacement).
//!
//! The gender value of a weight vector is `(w₀ − f₀) / (m₀ − f₀)`: 0 at the female mean shape,
//! 1 at the male mean.

use std::sync::OnceLock;

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::gender::Gender;
use super::gmm::Gmm;
use super::model::{BodyModel, ShapeSpace};
use crate::error::{Error, Result};
use crate::skeleton::{Joints3, NUM_JOINTS};

/// Components kept in the blended space (as many as each gendered space stores in the shipped
/// model; fewer when the span is smaller).
pub const BLEND_COMPONENTS: usize = 16;

/// Gender levels the prior covers: the two ends and two in-between levels.
pub const GENDER_LEVELS: [f64; 4] = [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0];

/// Prior mass of each level of [`GENDER_LEVELS`] (levels of mass 0 are left out). Default: the
/// ends only, so the prior is the two gendered priors side by side; the gender value still
/// varies continuously with each population's spread along the gender axis (the choice:
/// docs/benchmarks-history.md, "How the fit's defaults were chosen").
pub const LEVEL_WEIGHTS: [f64; 4] = [0.5, 0.0, 0.0, 0.5];

/// Default fitting dimension of the blended space: the gender weight plus the 4 shape weights
/// each gendered space fits by default (96% of its energy).
pub const BLEND_DEFAULT_DIM: usize = 5;

/// The both-sexes space with its gender axis. Immutable; `Send + Sync`.
#[derive(Clone, Debug)]
pub struct BlendedSpace {
    space: ShapeSpace,
    /// Weight 0 of the female and the male mean shape.
    ends: [f64; 2],
    /// Gender level ([`GENDER_LEVELS`]) each prior component represents.
    levels: Vec<f64>,
}

impl BlendedSpace {
    /// The linear space (vertices, joints, variances, GMM prior); weight 0 is the gender axis.
    pub fn space(&self) -> &ShapeSpace {
        &self.space
    }

    /// Gender value of a weight vector: 0 at the female mean shape, 1 at the male mean, linear
    /// in weight 0 (not clamped; the prior keeps it within about −0.3..1.3). An empty vector is
    /// the space's mean (0.5).
    pub fn gender_value(&self, weights: &[f64]) -> f64 {
        let w0 = weights.first().copied().unwrap_or(0.0);
        (w0 - self.ends[0]) / (self.ends[1] - self.ends[0])
    }

    /// Weight 0 of the shape at gender value `t` (the inverse of [`BlendedSpace::gender_value`]).
    pub fn gender_weight(&self, t: f64) -> f64 {
        self.ends[0] + t * (self.ends[1] - self.ends[0])
    }

    /// The prior with mass `male` on the male end and `1 − male` on the female end (a
    /// per-sketch [`LEVEL_WEIGHTS`], e.g. from [`crate::fit::GenderClassifier`]): every
    /// component of level `t` is reweighted by `(1 − t)(1 − male) + t · male` relative to the
    /// default ends-only prior, then the weights are renormalised; means and covariances are
    /// unchanged. `male` is clamped to 0.001..=0.999 so neither end is ruled out. Errors:
    /// non-finite `male` ([`Error::NonFinite`]).
    pub fn prior_with_male_mass(&self, male: f64) -> Result<Gmm> {
        crate::error::ensure_finite("male prior", male)?;
        let m = male.clamp(0.001, 0.999);
        let gmm = self.space.gmm();
        let mut weights: Vec<f64> =
            gmm.weights().iter().zip(&self.levels).map(|(w, t)| w * ((1.0 - t) * (1.0 - m) + t * m)).collect();
        let total: f64 = weights.iter().sum();
        weights.iter_mut().for_each(|w| *w /= total);
        Gmm::new(weights, gmm.means().to_vec(), gmm.covariances().to_vec())
    }

    /// Builds the space from a model's two gendered spaces (module documentation). Errors:
    /// [`Error::CorruptData`] when the two means coincide (no gender axis) or a prior covariance
    /// is not positive definite.
    pub fn new(model: &BodyModel) -> Result<BlendedSpace> {
        let spaces = [model.space(Gender::Female), model.space(Gender::Male)];
        let n3 = 3 * spaces[0].num_vertices();
        let flat = |v: &[[f32; 3]]| -> Vec<f64> { v.iter().flat_map(|p| p.iter().map(|&c| c as f64)).collect() };
        let means = [flat(spaces[0].mean()), flat(spaces[1].mean())];
        let centre: Vec<f64> = means[0].iter().zip(&means[1]).map(|(a, b)| 0.5 * (a + b)).collect();
        let delta: Vec<f64> = means[1].iter().zip(&means[0]).map(|(a, b)| a - b).collect();
        if delta.iter().map(|d| d * d).sum::<f64>().sqrt() < 1e-6 {
            return Err(Error::CorruptData("the female and male mean shapes coincide: no gender axis".into()));
        }

        // 1. Orthonormal frame Q of span(B_f, B_m, δ), δ first.
        let mut frame: Vec<Vec<f64>> = Vec::new();
        let mut candidates: Vec<Vec<f64>> = vec![delta.clone()];
        for s in spaces {
            for k in 0..s.num_components() {
                candidates.push(s.basis_vector(k).unwrap_or(&[]).iter().map(|&b| b as f64).collect());
            }
        }
        for mut v in candidates {
            let norm0 = dot(&v, &v).sqrt();
            for q in &frame {
                let p = dot(&v, q);
                v.iter_mut().zip(q).for_each(|(a, b)| *a -= p * b);
            }
            let norm = dot(&v, &v).sqrt();
            if norm > 1e-6 * norm0.max(1e-12) && norm > 1e-9 {
                v.iter_mut().for_each(|a| *a /= norm);
                frame.push(v);
            }
        }
        let r = frame.len();
        let coords = |v: &[f64]| -> DVector<f64> { DVector::from_iterator(r, frame.iter().map(|q| dot(q, v))) };
        // Mean offsets a_g and bases M_g (r × K_g) in the frame.
        let offsets: Vec<DVector<f64>> =
            means.iter().map(|m| coords(&m.iter().zip(&centre).map(|(a, c)| a - c).collect::<Vec<_>>())).collect();
        let bases: Vec<DMatrix<f64>> = spaces
            .iter()
            .map(|s| {
                let cols: Vec<DVector<f64>> = (0..s.num_components())
                    .map(|k| coords(&s.basis_vector(k).unwrap_or(&[]).iter().map(|&b| b as f64).collect::<Vec<_>>()))
                    .collect();
                DMatrix::from_columns(&cols)
            })
            .collect();
        let delta_c = &offsets[1] - &offsets[0];

        // 2. Population covariance (about the population mean) and the axes.
        let mut second = DMatrix::<f64>::zeros(r, r);
        let mut mean = DVector::<f64>::zeros(r);
        for (g, s) in spaces.iter().enumerate() {
            let lambda = DMatrix::from_diagonal(&DVector::from_column_slice(s.variances()));
            let within = &bases[g] * lambda * bases[g].transpose();
            for (&t, &p) in GENDER_LEVELS.iter().zip(&LEVEL_WEIGHTS) {
                let Some(shift) = level_shift(g, t).filter(|_| p > 0.0) else { continue };
                let share = if t == 0.0 || t == 1.0 { p } else { 0.5 * p };
                let m = &offsets[g] + shift * &delta_c;
                second += share * (&within + &m * m.transpose());
                mean += share * m;
            }
        }
        let cov = second - &mean * mean.transpose();
        let axis0 = delta_c.normalize();
        let projector = DMatrix::<f64>::identity(r, r) - &axis0 * axis0.transpose();
        let eig = SymmetricEigen::new(&projector * &cov * &projector);
        let mut order: Vec<usize> = (0..r).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let kept = BLEND_COMPONENTS.min(r);
        let mut axes = vec![axis0.clone()];
        axes.extend(order.iter().take(kept - 1).map(|&i| eig.eigenvectors.column(i).into_owned()));
        let u = DMatrix::from_columns(&axes); // r × kept, orthonormal columns
        let variances: Vec<f64> = axes.iter().map(|a| (a.transpose() * &cov * a)[(0, 0)].max(1e-12)).collect();
        let total: f64 = cov.trace();
        let mut acc = 0.0;
        let cumulative_energy: Vec<f64> = variances
            .iter()
            .map(|v| {
                acc += v;
                (acc / total).min(1.0)
            })
            .collect();

        // Vertex mean (the population mean) and basis in full coordinates.
        let mut full_mean = centre.clone();
        for (q, &c) in frame.iter().zip(mean.iter()) {
            full_mean.iter_mut().zip(q).for_each(|(a, b)| *a += c * b);
        }
        let mut basis = vec![0f32; kept * n3];
        for k in 0..kept {
            let mut col = vec![0f64; n3];
            for (q, &c) in frame.iter().zip(u.column(k).iter()) {
                col.iter_mut().zip(q).for_each(|(a, b)| *a += c * b);
            }
            basis[k * n3..(k + 1) * n3].iter_mut().zip(&col).for_each(|(o, &v)| *o = v as f32);
        }

        // 3. The exact prior in blended weights.
        let to_blend = |g: usize, x: &DVector<f64>| -> DVector<f64> { u.transpose() * (&offsets[g] + x - &mean) };
        let ridge: Vec<f64> = variances.iter().map(|v| 1e-3 * v).collect();
        let (mut weights, mut gmeans, mut gcovs, mut levels) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (g, s) in spaces.iter().enumerate() {
            let gmm = s.gmm();
            let d = gmm.dims();
            let m_cov = bases[g].columns(0, d).into_owned();
            let rest = s.num_components() - d;
            let m_rest = bases[g].columns(d, rest).into_owned();
            let rest_var = DMatrix::from_diagonal(&DVector::from_column_slice(&s.variances()[d..]));
            let rest_cov = &m_rest * rest_var * m_rest.transpose();
            for (&t, &p) in GENDER_LEVELS.iter().zip(&LEVEL_WEIGHTS) {
                let Some(shift) = level_shift(g, t).filter(|_| p > 0.0) else { continue };
                let share = if t == 0.0 || t == 1.0 { p } else { 0.5 * p };
                for c in 0..gmm.num_components() {
                    let x = &m_cov * &gmm.means()[c] + shift * &delta_c;
                    let inner = &m_cov * &gmm.covariances()[c] * m_cov.transpose() + &rest_cov;
                    let mut cv = u.transpose() * inner * &u;
                    for (k, rv) in ridge.iter().enumerate() {
                        cv[(k, k)] += rv;
                    }
                    cv = 0.5 * (&cv + cv.transpose());
                    weights.push(share * gmm.weights()[c]);
                    levels.push(t);
                    gmeans.push(to_blend(g, &x));
                    gcovs.push(cv);
                }
            }
        }
        let total_w: f64 = weights.iter().sum();
        weights.iter_mut().for_each(|w| *w /= total_w);
        let gmm = Gmm::new(weights, gmeans, gcovs)?;

        // 4. Joints: least squares from blended weights to joints over both gendered spaces.
        let (mean_joints, joint_basis) = fit_joint_map(spaces, &offsets, &bases, &u, &mean)?;

        let ends = [to_blend(0, &DVector::zeros(r))[0], to_blend(1, &DVector::zeros(r))[0]];
        let space = ShapeSpace {
            mean: full_mean.chunks_exact(3).map(|c| [c[0] as f32, c[1] as f32, c[2] as f32]).collect(),
            mean_joints,
            basis,
            joint_basis,
            variances,
            cumulative_energy,
            default_dim: BLEND_DEFAULT_DIM.min(kept),
            gmm,
        };
        Ok(BlendedSpace { space, ends, levels })
    }
}

/// How far along δ a gender-`g` population is moved to represent level `t` (`None`: that
/// population does not represent the level — each end is represented by its own sex only).
fn level_shift(g: usize, t: f64) -> Option<f64> {
    match (g, t) {
        (0, t) if t < 1.0 => Some(t),
        (1, t) if t > 0.0 => Some(t - 1.0),
        _ => None,
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Least-squares `joints = mean_joints + Σ w_k joint_basis_k` over both gendered spaces: rows for
/// each space's mean (weight 100) and each of its components at ±1 sd (weight 1).
fn fit_joint_map(
    spaces: [&ShapeSpace; 2],
    offsets: &[DVector<f64>],
    bases: &[DMatrix<f64>],
    u: &DMatrix<f64>,
    mean: &DVector<f64>,
) -> Result<(Joints3, Vec<Joints3>)> {
    let kept = u.ncols();
    let mut rows: Vec<(DVector<f64>, DVector<f64>)> = Vec::new(); // (design row, 45 targets)
    let flat_joints = |j: &Joints3| DVector::from_iterator(3 * NUM_JOINTS, j.iter().flat_map(|p| p.iter().copied()));
    for (g, s) in spaces.iter().enumerate() {
        let w_mean = 100.0;
        let x = u.transpose() * (&offsets[g] - mean);
        let mut row = DVector::zeros(kept + 1);
        row[0] = 1.0;
        row.rows_mut(1, kept).copy_from(&x);
        rows.push((w_mean * row, w_mean * flat_joints(s.mean_joints())));
        for k in 0..s.num_components() {
            let sd = s.variances()[k].sqrt();
            let dx = u.transpose() * bases[g].column(k) * sd;
            let mut row = DVector::zeros(kept + 1);
            row.rows_mut(1, kept).copy_from(&dx);
            let jb = s.joint_basis_vector(k).ok_or_else(|| Error::CorruptData("missing joint basis".into()))?;
            rows.push((row, sd * flat_joints(jb)));
        }
    }
    let a = DMatrix::from_rows(&rows.iter().map(|(r, _)| r.transpose()).collect::<Vec<_>>());
    let b = DMatrix::from_rows(&rows.iter().map(|(_, t)| t.transpose()).collect::<Vec<_>>());
    let mut ata = a.transpose() * &a;
    for i in 0..ata.nrows() {
        ata[(i, i)] += 1e-12;
    }
    let sol = ata
        .cholesky()
        .ok_or_else(|| Error::CorruptData("blended joint map is singular".into()))?
        .solve(&(a.transpose() * b)); // (kept + 1) × 45
    let joints_of = |i: usize| -> Joints3 { std::array::from_fn(|j| std::array::from_fn(|c| sol[(i, 3 * j + c)])) };
    Ok((joints_of(0), (1..=kept).map(joints_of).collect()))
}

/// Lazily built [`BlendedSpace`] of a model (cloning a model clones a built one).
#[derive(Clone, Debug, Default)]
pub(crate) struct BlendCell(OnceLock<BlendedSpace>);

impl BodyModel {
    /// The both-sexes space with gender as weight 0 ([`BlendedSpace`]), built on first use (a
    /// few tens of milliseconds) and then shared. Thread-safe.
    pub fn blended(&self) -> Result<&BlendedSpace> {
        if let Some(b) = self.blend.0.get() {
            return Ok(b);
        }
        let built = BlendedSpace::new(self)?;
        Ok(self.blend.0.get_or_init(|| built))
    }
}

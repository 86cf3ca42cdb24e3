//! A validated 2-D input and the model of eqs. (1)–(3) over a chosen basis subset.

use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Vector3};

use super::dictionary::Dictionary;
use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::skeleton::{Joints2, BONES, JOINT_NAMES, NUM_BONES, NUM_JOINTS};

/// Fewest visible joints the solver accepts.
pub const MIN_VISIBLE: usize = 8;
/// Largest accepted |coordinate| of a 2-D joint, pixels.
pub const MAX_COORD: f64 = 1.0e6;
/// Smallest accepted extent (bounding-box diagonal) of the visible joints, pixels.
pub const MIN_EXTENT: f64 = 4.0;

/// A checked 2-D pose: all 15 joints finite, at least [`MIN_VISIBLE`] visible, not degenerate.
#[derive(Clone, Debug)]
pub struct Problem<'a> {
    /// The dictionary.
    pub dict: &'a Dictionary,
    /// Joint positions, pixels.
    pub uv: [[f64; 2]; NUM_JOINTS],
    /// Indices of the visible joints (their residuals count).
    pub vis: Vec<usize>,
    /// Weight of the prior residuals `prior_w · w_k / σ_k`, pixels (0 = pure eq. 3).
    pub prior_w: f64,
    /// The pose the bases are added to (45 values, metres): the dictionary's mean μ, or an
    /// start composed from exemplars (see [`Problem::with_base`] and [`super::exemplar`]).
    pub base: DVector<f64>,
    /// Per basis b, `C_b = Σ_visible p B_bp B_bpᵀ` as (xx, xy, xz, yy, yz, zz), m²: the squared
    /// norm of the basis's projection under camera rows P (2 × 3, no translation) is ⟨PᵀP, C_b⟩.
    pub basis_gram: Arc<Vec<[f64; 6]>>,
}

impl<'a> Problem<'a> {
    /// Validates `j`: every position finite (invisible ones too: they are kept as guesses) and
    /// within ±[`MAX_COORD`]; at least [`MIN_VISIBLE`] visible; visible joints spanning at least
    /// [`MIN_EXTENT`] px and not collinear (second singular value of their spread ≥ 1e-3 of the
    /// first); no bone with both ends visible and closer than 1e-6 of the extent.
    ///
    /// `prior_m` (metres, ≥ 0) sets the weight prior: `prior_w = s̄ · prior_m` where s̄ (px/m) is
    /// the RMS spread of the visible 2-D joints over that of the mean pose's x, y (a fixed
    /// scale of the problem, so the objective stays a sum of squares in pixels).
    pub fn new(dict: &'a Dictionary, j: &Joints2, prior_m: f64) -> Result<Problem<'a>> {
        for (k, p) in j.xy.iter().enumerate() {
            if !p[0].is_finite() || !p[1].is_finite() {
                return Err(Error::TooFewJoints {
                    detail: format!("{} = ({}, {}) is not finite; all 15 joints need finite positions (mark unknown ones invisible)", JOINT_NAMES[k], p[0], p[1]),
                });
            }
            if p[0].abs() > MAX_COORD || p[1].abs() > MAX_COORD {
                return Err(Error::OutOfRange {
                    name: "joint position",
                    detail: format!("{} = ({}, {}) exceeds ±{MAX_COORD} px", JOINT_NAMES[k], p[0], p[1]),
                });
            }
        }
        let vis: Vec<usize> = (0..NUM_JOINTS).filter(|&k| j.visible[k]).collect();
        if vis.len() < MIN_VISIBLE {
            return Err(Error::TooFewJoints {
                detail: format!("{} visible, at least {MIN_VISIBLE} needed", vis.len()),
            });
        }
        let n = vis.len() as f64;
        let (mx, my) =
            (vis.iter().map(|&k| j.xy[k][0]).sum::<f64>() / n, vis.iter().map(|&k| j.xy[k][1]).sum::<f64>() / n);
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for &k in &vis {
            let (dx, dy) = (j.xy[k][0] - mx, j.xy[k][1] - my);
            sxx += dx * dx;
            sxy += dx * dy;
            syy += dy * dy;
            for a in 0..2 {
                lo[a] = lo[a].min(j.xy[k][a]);
                hi[a] = hi[a].max(j.xy[k][a]);
            }
        }
        let extent = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
        if extent < MIN_EXTENT {
            return Err(Error::Degenerate(format!(
                "visible joints span {extent:.3} px (at least {MIN_EXTENT} needed)"
            )));
        }
        let tr = sxx + syy;
        let disc = ((sxx - syy).powi(2) + 4.0 * sxy * sxy).sqrt();
        let (l1, l2) = (0.5 * (tr + disc), (0.5 * (tr - disc)).max(0.0));
        if l2.sqrt() < 1e-3 * l1.sqrt() {
            return Err(Error::Degenerate("visible joints are collinear".into()));
        }
        for &(a, b) in BONES.iter() {
            if j.visible[a] && j.visible[b] {
                let d = (j.xy[a][0] - j.xy[b][0]).hypot(j.xy[a][1] - j.xy[b][1]);
                if d <= 1e-6 * extent {
                    return Err(Error::CoincidentJoints {
                        a: JOINT_NAMES[a],
                        b: JOINT_NAMES[b],
                        x: j.xy[a][0],
                        y: j.xy[a][1],
                    });
                }
            }
        }
        let (mut mx3, mut my3) = (0.0, 0.0);
        for &k in &vis {
            mx3 += dict.mean[3 * k] / n;
            my3 += dict.mean[3 * k + 1] / n;
        }
        let spread3: f64 =
            vis.iter().map(|&k| (dict.mean[3 * k] - mx3).powi(2) + (dict.mean[3 * k + 1] - my3).powi(2)).sum();
        let s_bar = if spread3 > 0.0 { (tr / spread3).sqrt() } else { 0.0 };
        let basis_gram = dict
            .bases
            .column_iter()
            .map(|col| {
                let mut c = [0.0; 6];
                for &p in &vis {
                    let (x, y, z) = (col[3 * p], col[3 * p + 1], col[3 * p + 2]);
                    for (ci, v) in c.iter_mut().zip([x * x, x * y, x * z, y * y, y * z, z * z]) {
                        *ci += v;
                    }
                }
                c
            })
            .collect();
        Ok(Problem {
            dict,
            uv: j.xy,
            vis,
            prior_w: s_bar * prior_m,
            base: dict.mean.clone(),
            basis_gram: Arc::new(basis_gram),
        })
    }

    /// The same problem with the bases added to `base` (45 values, metres).
    pub fn with_base(&self, base: DVector<f64>) -> Problem<'a> {
        Problem { base, ..self.clone() }
    }

    /// The prior residuals `prior_w · w_k / σ_{bases[k]}`, pixels.
    pub fn prior_residuals(&self, bases: &[usize], w: &[f64]) -> Vec<f64> {
        bases.iter().zip(w).map(|(&b, &wk)| self.prior_w * wk / self.dict.sigma[b]).collect()
    }

    /// The full objective: reprojection (eq. 3, squared) plus the prior residuals, px².
    pub fn total_objective(&self, cam: &WeakPerspective, bases: &[usize], w: &[f64]) -> f64 {
        self.objective(cam, &self.pose(bases, w)) + self.prior_residuals(bases, w).iter().map(|r| r * r).sum::<f64>()
    }

    /// 3-D joints base + Σ_k B_{bases[k]} w_k, metres (base = μ unless [`Problem::with_base`]).
    pub fn pose(&self, bases: &[usize], w: &[f64]) -> [Vector3<f64>; NUM_JOINTS] {
        let mut v = self.base.clone();
        for (&b, &wk) in bases.iter().zip(w) {
            v.axpy(wk, &self.dict.bases.column(b), 1.0);
        }
        std::array::from_fn(|p| Vector3::new(v[3 * p], v[3 * p + 1], v[3 * p + 2]))
    }

    /// Reprojection residuals (predicted − observed, u then v per visible joint), pixels.
    pub fn residuals(&self, cam: &WeakPerspective, x: &[Vector3<f64>; NUM_JOINTS]) -> Vec<f64> {
        let mut r = Vec::with_capacity(2 * self.vis.len());
        for &p in &self.vis {
            let q = cam.project(&x[p]);
            r.push(q[0] - self.uv[p][0]);
            r.push(q[1] - self.uv[p][1]);
        }
        r
    }

    /// Objective of eq. (3) squared: Σ over visible joints of the squared reprojection error, px².
    pub fn objective(&self, cam: &WeakPerspective, x: &[Vector3<f64>; NUM_JOINTS]) -> f64 {
        self.residuals(cam, x).iter().map(|r| r * r).sum()
    }

    /// RMS reprojection error per visible joint (Euclidean), pixels.
    pub fn rms(&self, cam: &WeakPerspective, x: &[Vector3<f64>; NUM_JOINTS]) -> f64 {
        (self.objective(cam, x) / self.vis.len() as f64).sqrt()
    }

    /// The linear model of the projections in the weights: `A w ≈ r0` with `A` (2V + k rows ×
    /// k) the projected bases (without translation) over the prior rows `diag(prior_w / σ)`,
    /// and `r0` the observed minus projected base pose over k zeros.
    pub fn linear_system(&self, cam: &WeakPerspective, bases: &[usize]) -> (DMatrix<f64>, DVector<f64>) {
        let m = 2 * self.vis.len() + bases.len();
        let v2 = 2 * self.vis.len();
        let mut a = DMatrix::zeros(m, bases.len());
        let mean = self.pose(&[], &[]);
        let mut r0 = DVector::zeros(m);
        for (i, &p) in self.vis.iter().enumerate() {
            let q = cam.project(&mean[p]);
            r0[2 * i] = self.uv[p][0] - q[0];
            r0[2 * i + 1] = self.uv[p][1] - q[1];
            for (k, &b) in bases.iter().enumerate() {
                let col = self.dict.bases.column(b);
                let y = cam.r * Vector3::new(col[3 * p], col[3 * p + 1], col[3 * p + 2]);
                a[(2 * i, k)] = cam.sx * y.x;
                a[(2 * i + 1, k)] = -cam.sy * y.y;
            }
        }
        for (k, &b) in bases.iter().enumerate() {
            a[(v2 + k, k)] = self.prior_w / self.dict.sigma[b];
        }
        (a, r0)
    }

    /// The limb-length constraint of eq. (3) restricted to `bases` (bone vectors of the base pose).
    pub fn constraint(&self, bases: &[usize]) -> LengthConstraint {
        let d = &self.dict;
        let mut e = DVector::zeros(3 * NUM_BONES);
        let mut em = DMatrix::zeros(3 * NUM_BONES, bases.len());
        for (b, &(p, c)) in BONES.iter().enumerate() {
            for a in 0..3 {
                e[3 * b + a] = self.base[3 * c + a] - self.base[3 * p + a];
                for (k, &col) in bases.iter().enumerate() {
                    em[(3 * b + a, k)] = d.bases[(3 * c + a, col)] - d.bases[(3 * p + a, col)];
                }
            }
        }
        LengthConstraint { e, em, sum_sq: d.sum_sq_lengths() }
    }
}

/// `g(w) = ‖e + E w‖² − Σ l²`: the summed squared bone lengths minus the dictionary's, m².
#[derive(Clone, Debug)]
pub struct LengthConstraint {
    /// Bone vectors of the base pose (42).
    pub e: DVector<f64>,
    /// Bone vectors of the chosen bases (42 × k).
    pub em: DMatrix<f64>,
    /// Σ l², m².
    pub sum_sq: f64,
}

impl LengthConstraint {
    /// g(w), m².
    pub fn value(&self, w: &DVector<f64>) -> f64 {
        (&self.e + &self.em * w).norm_squared() - self.sum_sq
    }
    /// ∇g(w) = 2 Eᵀ(e + E w).
    pub fn gradient(&self, w: &DVector<f64>) -> DVector<f64> {
        self.em.transpose() * (&self.e + &self.em * w) * 2.0
    }
    /// Moves `w` along `n` onto `g = target`: the real root `s` of smallest |s| of
    /// `g(w + s n) = target` (a quadratic in `s`), or `None` when there is none.
    pub fn retract(&self, w: &DVector<f64>, n: &DVector<f64>, target: f64) -> Option<DVector<f64>> {
        let en = &self.em * n;
        let base = &self.e + &self.em * w;
        let (a, b, c) = (en.norm_squared(), 2.0 * base.dot(&en), base.norm_squared() - self.sum_sq - target);
        if c == 0.0 {
            return Some(w.clone());
        }
        if !(a > 0.0) {
            return None;
        }
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            return None;
        }
        // Numerically stable roots; pick the smaller magnitude.
        let qv = -0.5 * (b + b.signum() * disc.sqrt());
        let (s1, s2) = (qv / a, if qv != 0.0 { c / qv } else { f64::INFINITY });
        let s = if s1.abs() < s2.abs() { s1 } else { s2 };
        s.is_finite().then(|| w + n * s)
    }
}

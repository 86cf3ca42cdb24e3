//! Joint Levenberg–Marquardt refinement of all continuous parameters of eq. (3) for a fixed
//! basis subset: rotation (left increment R ← exp([δ]×) R), sx, sy, tx, ty and the weights Ω,
//! minimising Σ‖reprojection residual‖² over the visible joints (plus the weight-prior
//! residuals when [`PoseOptions::prior`] > 0) with |g(Ω)| ≤ κ Σl² kept
//! exactly at every iterate (active-set):
//!
//! - each iteration first tries the plain LM step (Marquardt-scaled damping); if its Ω is
//!   feasible it is the candidate;
//! - otherwise the step is recomputed with Ω restricted to the tangent space of the violated
//!   bound (Ω + T z, T an orthonormal basis of ∇g⊥) and retracted exactly onto that bound along
//!   ∇g (a scalar quadratic);
//! - a candidate is accepted when it lowers the objective (damping ÷3), else damping ×4.
//!
//! With [`PoseOptions::equal_scales`] one scale s = sx = sy is refined (a start with sx ≠ sy
//! first takes their mean).
//!
//! Stops after 3 accepted steps in a row each lowering the objective by < 1e-12 relative, when
//! the damping exceeds 1e16, or after 500 iterations. The rotation prior α plays no part here:
//! it acts through the pursuit's starting point.

use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, Vector3};

use super::dictionary::Dictionary;
use super::options::PoseOptions;
use super::problem::{LengthConstraint, Problem};
use super::pursuit::{finish, PoseEstimate};
use super::qcls;
use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::skeleton::Joints2;

/// Refines `start` (its bases, weights, camera and base pose) on `joints`
/// (see the module doc). The basis set is kept. A start whose weights violate the constraint is first moved onto it (weights
/// re-solved for the start camera). Errors as [`super::estimate_pose`], plus `OutOfRange` for a
/// basis index ≥ K, a weight count ≠ basis count or more than 32 bases, `NonFinite` for a
/// non-finite weight or base-pose value, and camera errors.
pub fn refine_pose(
    dict: &Dictionary,
    joints: &Joints2,
    opts: &PoseOptions,
    start: &PoseEstimate,
) -> Result<PoseEstimate> {
    opts.validate()?;
    let prob = Problem::new(dict, joints, opts.prior)?;
    start.camera.validate()?;
    let k = start.bases.len();
    if k != start.weights.len() || k > super::options::MAX_BASES || k == 0 {
        return Err(Error::OutOfRange {
            name: "start bases",
            detail: format!("{k} bases with {} weights (1..=32, equal counts)", start.weights.len()),
        });
    }
    for (i, &b) in start.bases.iter().enumerate() {
        if b >= dict.num_bases() || start.bases[..i].contains(&b) {
            return Err(Error::OutOfRange {
                name: "start bases",
                detail: format!("index {b} is repeated or not below {}", dict.num_bases()),
            });
        }
        crate::error::ensure_finite("start weight", start.weights[i])?;
    }
    for q in start.base.iter().flatten() {
        crate::error::ensure_finite("start base pose", *q)?;
    }
    refine_problem(&prob.with_base(super::dictionary::pose_to_vec(&start.base)), opts, start)
}

/// Orthonormal basis (k × (k−1)) of the complement of `n` (Householder).
fn tangent_basis(n: &DVector<f64>) -> DMatrix<f64> {
    let k = n.len();
    let u = n.normalize();
    let mut v = u.clone();
    v[0] += if u[0] >= 0.0 { 1.0 } else { -1.0 };
    let vv = v.norm_squared();
    let mut h = DMatrix::<f64>::identity(k, k);
    if vv > 0.0 {
        h -= &v * v.transpose() * (2.0 / vv);
    }
    h.columns(1, k - 1).into_owned()
}

/// Jacobian of the residuals; columns δ (3), sx, sy, tx, ty, Ω. With `equal` the scale column
/// sx carries both axes' derivatives and the sy column is zero (its step is then 0).
fn jacobian(prob: &Problem, cam: &WeakPerspective, bases: &[usize], w: &[f64], equal: bool) -> DMatrix<f64> {
    let x = prob.pose(bases, w);
    let m = 2 * prob.vis.len();
    let mut j = DMatrix::zeros(m + bases.len(), 7 + bases.len());
    for (k, &b) in bases.iter().enumerate() {
        j[(m + k, 7 + k)] = prob.prior_w / prob.dict.sigma[b];
    }
    for (i, &p) in prob.vis.iter().enumerate() {
        let y = cam.r * x[p];
        let (ru, rv) = (2 * i, 2 * i + 1);
        // d(RX)/dδ = −[Y]×: row x = (0, Y3, −Y2), row y = (−Y3, 0, Y1).
        j[(ru, 1)] = cam.sx * y.z;
        j[(ru, 2)] = -cam.sx * y.y;
        j[(rv, 0)] = cam.sy * y.z;
        j[(rv, 2)] = -cam.sy * y.x;
        j[(ru, 3)] = y.x;
        j[(rv, if equal { 3 } else { 4 })] = -y.y;
        j[(ru, 5)] = 1.0;
        j[(rv, 6)] = 1.0;
        for (k, &b) in bases.iter().enumerate() {
            let col = prob.dict.bases.column(b);
            let yb = cam.r * Vector3::new(col[3 * p], col[3 * p + 1], col[3 * p + 2]);
            j[(ru, 7 + k)] = cam.sx * yb.x;
            j[(rv, 7 + k)] = -cam.sy * yb.y;
        }
    }
    j
}

fn apply(cam: &WeakPerspective, d: &[f64], equal: bool) -> Option<WeakPerspective> {
    let rot = Rotation3::new(Vector3::new(d[0], d[1], d[2]));
    let r: Matrix3<f64> = rot.matrix() * cam.r;
    let sy = if equal { cam.sx + d[3] } else { cam.sy + d[4] };
    let c = WeakPerspective { sx: cam.sx + d[3], sy, r, t: [cam.t[0] + d[5], cam.t[1] + d[6]] };
    (c.sx > 0.0 && c.sy > 0.0 && d.iter().all(|v| v.is_finite())).then_some(c)
}

/// The normal equations JᵀJ and Jᵀr of one linearisation, formed once and reused by every
/// damping retry of that iteration.
struct Normal {
    h: DMatrix<f64>,
    g: DVector<f64>,
}

impl Normal {
    fn new(j: &DMatrix<f64>, r: &DVector<f64>) -> Normal {
        Normal { h: j.transpose() * j, g: j.transpose() * r }
    }

    /// Damped solve (JᵀJ + λ·diag(JᵀJ) + tiny) δ = −Jᵀr.
    fn step(&self, lambda: f64) -> Option<DVector<f64>> {
        let mut h = self.h.clone();
        let maxd = (0..h.nrows()).map(|i| h[(i, i)]).fold(0.0, f64::max);
        for i in 0..h.nrows() {
            h[(i, i)] += lambda * h[(i, i)] + 1e-15 * maxd + f64::MIN_POSITIVE;
        }
        h.cholesky().map(|c| -c.solve(&self.g))
    }
}

pub(crate) fn refine_problem(prob: &Problem, opts: &PoseOptions, start: &PoseEstimate) -> Result<PoseEstimate> {
    let bases = start.bases.clone();
    let k = bases.len();
    let con: LengthConstraint = prob.constraint(&bases);
    let bound = opts.kappa * con.sum_sq;
    let equal = opts.equal_scales;
    let mut cam = start.camera;
    if equal {
        let s = 0.5 * (cam.sx + cam.sy);
        (cam.sx, cam.sy) = (s, s);
    }
    let mut w = DVector::from_column_slice(&start.weights);
    let g0 = con.value(&w);
    if g0 > bound || g0 < -bound {
        let (a, r0) = prob.linear_system(&cam, &bases);
        w = qcls::solve(&a, &r0, &con, -bound, bound).w;
    }
    let objective = |c: &WeakPerspective, w: &DVector<f64>| prob.total_objective(c, &bases, w.as_slice());
    let mut f = objective(&cam, &w);
    let mut lambda = 1e-3;
    let mut small = 0;
    for _ in 0..500 {
        let j = jacobian(prob, &cam, &bases, w.as_slice(), equal);
        let mut r = prob.residuals(&cam, &prob.pose(&bases, w.as_slice()));
        r.extend(prob.prior_residuals(&bases, w.as_slice()));
        let r = DVector::from_vec(r);
        let full = Normal::new(&j, &r);
        // The tangent-space system of this linearisation (built on first use): n = ∇g at w,
        // T its orthonormal complement, and the normal equations of [J_camera, J_Ω T].
        // Computed once on first use; `Some(None)` when the tangent space is degenerate.
        #[allow(clippy::type_complexity)]
        let mut tangent: Option<Option<(DVector<f64>, DMatrix<f64>, Normal)>> = None;
        let mut accepted = false;
        while !accepted && lambda <= 1e16 {
            let cand = full.step(lambda).and_then(|d| {
                let c = apply(&cam, d.as_slice(), equal)?;
                let nw = &w + d.rows(7, k);
                let g = con.value(&nw);
                if g <= bound && g >= -bound {
                    return Some((c, nw));
                }
                let target = if g > bound { bound } else { -bound };
                let (n, t, reduced) = tangent
                    .get_or_insert_with(|| {
                        let n = con.gradient(&w);
                        if !(n.norm() > 0.0) {
                            return None;
                        }
                        // With one weight the tangent space is empty: a camera-only step.
                        let t = tangent_basis(&n);
                        let mut jr = DMatrix::zeros(j.nrows(), 7 + k - 1);
                        jr.columns_mut(0, 7).copy_from(&j.columns(0, 7));
                        jr.columns_mut(7, k - 1).copy_from(&(j.columns(7, k) * &t));
                        let reduced = Normal::new(&jr, &r);
                        Some((n, t, reduced))
                    })
                    .as_ref()?;
                let dr = reduced.step(lambda)?;
                let c = apply(&cam, dr.as_slice(), equal)?;
                let nw = &w + t * dr.rows(7, k - 1);
                let nw = con.retract(&nw, n, target)?;
                Some((c, nw))
            });
            match cand {
                Some((c, nw)) => {
                    let nf = objective(&c, &nw);
                    if nf < f {
                        small = if f - nf < 1e-12 * f { small + 1 } else { 0 };
                        cam = c;
                        w = nw;
                        f = nf;
                        lambda = (lambda / 3.0).max(1e-12);
                        accepted = true;
                    } else {
                        lambda *= 4.0;
                    }
                }
                None => lambda *= 4.0,
            }
        }
        if !accepted || small >= 3 || f == 0.0 {
            break;
        }
    }
    // Re-orthonormalise the rotation (it accumulates products of exact rotations).
    cam.r = super::camera_fit::project_so3(&cam.r)?;
    Ok(PoseEstimate { base_parts: start.base_parts, ..finish(prob, cam, bases, w.iter().copied().collect()) })
}

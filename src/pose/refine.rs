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

#[cfg(test)]
mod tests {
    //! The refinement on the fixed problem of the pursuit's tests (a hand-made dictionary whose
    //! right answer is known).
    use super::*;
    use crate::pose::dictionary::POSE_DIM;
    use crate::pose::pursuit::tests::{fixture, observe, options, true_camera, ARM, LEG, SHRUG, W_ARM, W_LEG};

    /// A poor start: both true bases at weight 0 under a camera turned by 0.3 rad and scaled
    /// wrongly.
    fn poor_start(d: &Dictionary, j: &Joints2) -> PoseEstimate {
        let prob = Problem::new(d, j, 0.0).unwrap();
        let cam = WeakPerspective {
            sx: 190.0,
            sy: 210.0,
            r: Rotation3::new(Vector3::new(0.12, -0.25, 0.1)).into_inner(),
            t: [185.0, 470.0],
        };
        finish(&prob, cam, vec![ARM, LEG], vec![0.0, 0.0])
    }

    #[test]
    fn tangent_basis_is_orthonormal_and_orthogonal_to_the_normal() {
        for n in [vec![3.0, -4.0], vec![-1.0, 2.0, 0.5], vec![0.0, 0.0, 2.0, 1.0], vec![-2.0, 0.0, 0.0]] {
            let n = DVector::from_vec(n);
            let t = tangent_basis(&n);
            assert_eq!((t.nrows(), t.ncols()), (n.len(), n.len() - 1));
            let gram = t.transpose() * &t;
            assert!((gram - DMatrix::identity(n.len() - 1, n.len() - 1)).norm() < 1e-14, "{n}");
            assert!((t.transpose() * &n).norm() < 1e-14 * n.norm(), "{n}");
        }
    }

    #[test]
    fn reaches_the_exact_solution_from_a_poor_start() {
        let d = fixture();
        let j = observe(&d, &[(ARM, W_ARM), (LEG, W_LEG)], 0.0);
        let opts = PoseOptions { refine: true, equal_scales: false, ..options() };
        let start = PoseEstimate { base_parts: Some([1, 2, 3, 4, 5]), ..poor_start(&d, &j) };
        assert!(start.rms > 10.0, "{}", start.rms);
        let est = refine_pose(&d, &j, &opts, &start).unwrap();
        assert_eq!(est.bases, [ARM, LEG]);
        assert_eq!(est.base_parts, start.base_parts);
        assert!(est.rms < 1e-7, "rms {}", est.rms);
        assert!((est.weights[0] - W_ARM).abs() < 1e-8 && (est.weights[1] - W_LEG).abs() < 1e-8, "{:?}", est.weights);
        let c = true_camera();
        assert!((est.camera.r - c.r).norm() < 1e-8, "{}", est.camera.r);
        assert!((est.camera.sx - c.sx).abs() < 1e-6 && (est.camera.sy - c.sy).abs() < 1e-6, "{:?}", est.camera);
        assert!((est.camera.t[0] - c.t[0]).abs() < 1e-6 && (est.camera.t[1] - c.t[1]).abs() < 1e-6);
        // The rotation is a rotation.
        assert!((est.camera.r * est.camera.r.transpose() - Matrix3::identity()).norm() < 1e-12);
        // With equal scales the two scales stay one (from the mean of the start's).
        let eq = refine_pose(&d, &j, &PoseOptions { equal_scales: true, ..opts }, &start).unwrap();
        assert_eq!(eq.camera.sx, eq.camera.sy);
        assert!(eq.rms < 1e-7 && (eq.camera.sx - 250.0).abs() < 1e-6, "{:?}", eq);
    }

    /// With noisy joints the minimum is not zero, so the refinement cannot end on f = 0: it ends
    /// when no step lowers the objective (here after two steps gaining less than 1e-12 of it) at
    /// a stationary point near the truth, which a second refinement cannot improve.
    #[test]
    fn stops_at_a_noisy_minimum_after_small_gains() {
        let d = fixture();
        let j = observe(&d, &[(ARM, W_ARM), (LEG, W_LEG)], 3.0);
        let opts = PoseOptions { refine: true, equal_scales: false, ..options() };
        let start = poor_start(&d, &j);
        let est = refine_pose(&d, &j, &opts, &start).unwrap();
        assert!(est.rms > 0.1 && est.rms < 3.0, "rms {}", est.rms);
        assert!((est.weights[0] - W_ARM).abs() < 0.05 && (est.weights[1] - W_LEG).abs() < 0.05, "{:?}", est.weights);
        let again = refine_pose(&d, &j, &opts, &est).unwrap();
        assert!(again.rms <= est.rms && est.rms - again.rms <= 1e-9 * est.rms, "{} then {}", est.rms, again.rms);
    }

    /// The lower side of the length bound. The fixture's bases barely change the bone lengths,
    /// so SHRUG is replaced by "right wrist up" (toward its elbow: it shortens the forearm), and
    /// the truth (weight 0.1 on it, none on ARM) is shorter than κ Σl² allows. Steps that would cross below
    /// −κ Σl² are moved back onto that side, and the refinement ends on it.
    #[test]
    fn the_lower_side_of_the_length_bound_is_kept() {
        let mut d = fixture();
        let mut wrist_up = DVector::zeros(POSE_DIM);
        wrist_up[3 * 4 + 1] = 1.0;
        d.bases.set_column(SHRUG, &wrist_up);
        let j = observe(&d, &[(SHRUG, 0.1)], 0.0);
        let prob = Problem::new(&d, &j, 0.0).unwrap();
        let sum = d.sum_sq_lengths();
        let g_true = prob.constraint(&[ARM, SHRUG]).value(&DVector::from_vec(vec![0.0, 0.1]));
        assert!(g_true < -0.02 * sum, "the truth is below the bound: {}", g_true / sum);
        let opts = PoseOptions { refine: true, equal_scales: false, kappa: 0.01, ..options() };
        let start = finish(&prob, true_camera(), vec![ARM, SHRUG], vec![0.0, 0.0]);
        let est = refine_pose(&d, &j, &opts, &start).unwrap();
        assert!((est.length_excess + 0.01).abs() < 1e-9, "ends on the lower side: {}", est.length_excess);
        assert!(est.rms < start.rms, "{} from {}", est.rms, start.rms);
        assert!(est.weights[1] > 0.02, "toward the truth: {:?}", est.weights);
    }

    #[test]
    fn a_start_outside_the_length_bound_is_projected_and_the_bound_kept() {
        // With κ = 0.02 the true weights lengthen the bones beyond the bound: the best pose
        // lies on it (g = κ Σl²), the start (the true weights, camera off) is outside.
        let d = fixture();
        let j = observe(&d, &[(ARM, W_ARM), (LEG, W_LEG)], 0.0);
        let opts = PoseOptions { refine: true, equal_scales: false, kappa: 0.02, ..options() };
        let prob = Problem::new(&d, &j, 0.0).unwrap();
        let mut cam = true_camera();
        cam.sx = 240.0;
        cam.r = Rotation3::new(Vector3::new(0.0, 0.1, 0.0)).into_inner();
        let start = finish(&prob, cam, vec![ARM, LEG], vec![W_ARM, W_LEG]);
        assert!(start.length_excess > 0.04, "{}", start.length_excess);
        // The exact truth outside the bound fits better than anything within it: only the
        // projection of the start brings it inside.
        let exact = finish(&prob, true_camera(), vec![ARM, LEG], vec![W_ARM, W_LEG]);
        let inside = refine_pose(&d, &j, &opts, &exact).unwrap();
        assert!((inside.length_excess - 0.02).abs() < 1e-9, "{}", inside.length_excess);
        let est = refine_pose(&d, &j, &opts, &start).unwrap();
        assert_eq!(est.bases, [ARM, LEG]);
        assert!(
            est.length_excess <= 0.02 + 1e-12 && est.length_excess > 0.02 - 1e-9,
            "the bound is active and kept: {}",
            est.length_excess
        );
        assert!(est.rms > 0.01, "the bound costs some fit: {}", est.rms);
        // Better than the start moved onto the bound with its own camera (the weights re-solved
        // under the constraint).
        let con = prob.constraint(&est.bases);
        let (a, r0) = prob.linear_system(&cam, &est.bases);
        let projected = qcls::solve(&a, &r0, &con, -0.02 * con.sum_sq, 0.02 * con.sum_sq);
        assert!(projected.feasible);
        let f_proj = prob.total_objective(&cam, &est.bases, projected.w.as_slice());
        let f = prob.total_objective(&est.camera, &est.bases, &est.weights);
        assert!(f < 0.5 * f_proj, "{f} vs {f_proj}");
        // A constrained minimum: no move along the bound (weights moved in its tangent and
        // retracted onto it) nor of the camera lowers the objective.
        let w = DVector::from_column_slice(&est.weights);
        let n = con.gradient(&w);
        let t = tangent_basis(&n);
        for s in [1e-4, -1e-4, 1e-3, -1e-3] {
            let nw = con.retract(&(&w + t.column(0) * s), &n, 0.02 * con.sum_sq).unwrap();
            assert!(prob.total_objective(&est.camera, &est.bases, nw.as_slice()) >= f * (1.0 - 1e-9), "tangent {s}");
            for k in 0..7 {
                let mut d7 = [0.0; 7];
                d7[k] = s * if k < 3 { 0.1 } else { 10.0 };
                let c = apply(&est.camera, &d7, false).unwrap();
                assert!(prob.total_objective(&c, &est.bases, &est.weights) >= f * (1.0 - 1e-9), "camera {k} {s}");
            }
        }
    }

    #[test]
    fn one_weight_on_the_bound_takes_camera_only_steps() {
        // One basis, whose true weight is outside the bound: the weight sits on the bound (the
        // tangent space is empty) and the camera is still refined.
        let d = fixture();
        let j = observe(&d, &[(ARM, W_ARM)], 0.0);
        let opts = PoseOptions { refine: true, equal_scales: false, kappa: 0.02, ..options() };
        let prob = Problem::new(&d, &j, 0.0).unwrap();
        let mut cam = true_camera();
        cam.t = [190.0, 455.0];
        let start = finish(&prob, cam, vec![ARM], vec![W_ARM]);
        let est = refine_pose(&d, &j, &opts, &start).unwrap();
        assert!((est.length_excess - 0.02).abs() < 1e-9, "{}", est.length_excess);
        assert!(est.weights[0] > 0.0 && est.weights[0] < W_ARM, "{:?}", est.weights);
        let con = prob.constraint(&est.bases);
        let (a, r0) = prob.linear_system(&cam, &est.bases);
        let projected = qcls::solve(&a, &r0, &con, -0.02 * con.sum_sq, 0.02 * con.sum_sq);
        let f_proj = prob.total_objective(&cam, &est.bases, projected.w.as_slice());
        assert!(prob.total_objective(&est.camera, &est.bases, &est.weights) < 0.5 * f_proj);
    }
}

//! The projected matching pursuit of eq. (3) ([`estimate_pose`]).
//!
//! Start from the mean pose (the paper; [`PoseOptions::starts`] = 0) or from exemplar starts
//! ([`super::exemplar`]) with the fitted camera. Each step adds the unused basis whose
//! projection (current camera, no translation) is most correlated with the reprojection residual
//! (|aᵀr| / ‖a‖), then alternates the weights Ω ([`super::qcls`], constraint
//! |g| ≤ κ Σl²) and the camera ([`super::camera_fit`], eq. 4 with α) until the RMS changes by
//! less than 1e-6 relative (at most 50 rounds). Stopping rules: RMS ≤ tolerance, `max_bases`
//! reached, or a step that lowers the objective (reprojection plus the optional weight prior)
//! by less than 0.2 % (that step is undone) — except that
//! steps are always kept while the current state violates the constraint. Then, if enabled, the
//! joint refinement [`super::refine::refine_pose`], and last the free-joint refinement
//! [`super::joint_fit`] (off when [`PoseOptions::joint_noise`] = 0).

use nalgebra::{DVector, Vector3};

use super::camera_fit::{fit_camera, CameraPrior};
use super::dictionary::Dictionary;
use super::figure::{estimate_factors, BodyFactors, FACTOR_MAX, FACTOR_MIN};
use super::options::PoseOptions;
use super::problem::Problem;
use super::qcls;
use crate::camera::WeakPerspective;
use crate::error::Result;
use crate::skeleton::{Joints2, Joints3, NUM_JOINTS};

/// Result of the 3-D pose step.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseEstimate {
    /// 3-D joints, metres of a 1.75 m person, model frame (+Y up, facing +Z when R = I).
    pub joints: Joints3,
    /// Weak-perspective camera (eq. 1).
    pub camera: WeakPerspective,
    /// Chosen basis columns of the dictionary, in the order chosen.
    pub bases: Vec<usize>,
    /// Weight of each chosen basis, metres.
    pub weights: Vec<f64>,
    /// RMS reprojection error per visible joint, pixels.
    pub rms: f64,
    /// g / Σl²: relative excess of the summed squared bone lengths (|·| ≤ κ when feasible).
    pub length_excess: f64,
    /// The pose the bases are added to, metres: μ (eq. 2) or an exemplar start.
    pub base: Joints3,
    /// For an exemplar start: the exemplar columns of its torso and of its limbs (right arm,
    /// left arm, right leg, left leg; all equal unless recomposed); `None` for μ.
    pub base_parts: Option<[usize; 5]>,
    /// The drawn proportions: per-group bone-length factors relative to the dictionary's
    /// skeleton ([`super::figure`]; all 1 unless [`PoseOptions::proportions`]). `joints` is the
    /// dictionary pose (`base` + Σ B w, after the free-joint step) with these factors applied.
    pub factors: BodyFactors,
    /// `false` when no plausible body explains the 2-D joints: the reprojection RMS exceeds
    /// [`IMPLAUSIBLE_RMS`] of the visible joints' extent, or a factor sits at its range's end.
    /// The estimate is still the best found.
    pub plausible: bool,
}

/// Reprojection RMS, as a fraction of the visible joints' bounding-box diagonal, above which an
/// estimate is flagged implausible (5%: 25 px on a 500-px figure; exact mocap joints stay below
/// 2%).
pub const IMPLAUSIBLE_RMS: f64 = 0.05;

/// How many of the most correlated bases each pursuit step tries.
const CANDIDATES: usize = 1;
/// Most Ω/camera alternation rounds after adding a basis.
const ALTERNATIONS: usize = 20;

pub(crate) fn to_joints(x: &[Vector3<f64>; NUM_JOINTS]) -> Joints3 {
    std::array::from_fn(|j| [x[j].x, x[j].y, x[j].z])
}

/// Builds the estimate for a state.
pub(crate) fn finish(prob: &Problem, cam: WeakPerspective, bases: Vec<usize>, weights: Vec<f64>) -> PoseEstimate {
    let x = prob.pose(&bases, &weights);
    let con = prob.constraint(&bases);
    let excess = con.value(&DVector::from_column_slice(&weights)) / con.sum_sq;
    PoseEstimate {
        joints: to_joints(&x),
        rms: prob.rms(&cam, &x),
        camera: cam,
        bases,
        weights,
        length_excess: excess,
        base: crate::pose::dictionary::vec_to_pose(prob.base.as_slice()),
        base_parts: None,
        factors: BodyFactors::default(),
        plausible: true,
    }
}

/// Estimates the 3-D pose and camera from 2-D joints (see the module doc). Invisible joints
/// (`visible[j] == false`) drop their residuals; see [`Problem::new`] for the input checks.
/// With [`PoseOptions::starts`] > 0 and a dictionary with exemplars, the pursuit and refinement
/// run from each of the `starts` best exemplar starts ([`super::exemplar`]; recomposed limb by
/// limb when [`PoseOptions::limb_candidates`] > 0) instead of from μ; the results are blended
/// by their objectives (reprojection plus weight prior; [`super::blend`], temperature
/// [`PoseOptions::blend`]; 0 = the one with the lowest objective) and, if refinement is on, a
/// blend of several is refined once more from its own base pose. Last, with
/// [`PoseOptions::joint_noise`] > 0, the free-joint refinement ([`super::joint_fit`]).
///
/// With [`PoseOptions::proportions`], the drawn proportions are unknowns too: the factors are
/// estimated from that first estimate ([`super::figure::estimate_factors`]), the whole solve
/// runs again on the 2-D joints unstylised by them, and the factors are applied to its joints
/// (the first estimate is kept when that second solve fails or fits the image worse). Every
/// estimate is flagged for plausibility ([`PoseEstimate::plausible`]).
pub fn estimate_pose(dict: &Dictionary, joints: &Joints2, opts: &PoseOptions) -> Result<PoseEstimate> {
    opts.validate()?;
    let first = estimate_fixed(dict, joints, opts)?;
    let est = if opts.proportions { with_proportions(dict, joints, opts, first) } else { first };
    Ok(flag_plausibility(joints, est))
}

/// The second solve of [`estimate_pose`] with estimated factors (see there).
fn with_proportions(dict: &Dictionary, joints: &Joints2, opts: &PoseOptions, first: PoseEstimate) -> PoseEstimate {
    let c = &first.camera;
    let f = estimate_factors(joints, &dict.bone_lengths, &first.joints, &c.r, c.sx, c.sy);
    if f.k.iter().all(|k| (k - 1.0).abs() < 1e-3) {
        return first;
    }
    let Ok(second) = estimate_fixed(dict, &f.unstylise_2d(joints), opts) else { return first };
    let x = f.apply(&second.joints);
    let xs: [Vector3<f64>; NUM_JOINTS] = std::array::from_fn(|j| Vector3::from(x[j]));
    let Ok(prob) = Problem::new(dict, joints, 0.0) else { return first };
    let rms = prob.rms(&second.camera, &xs);
    if !(rms <= first.rms) && rms > opts.tolerance {
        return first;
    }
    PoseEstimate { joints: x, rms, factors: f, ..second }
}

/// Sets [`PoseEstimate::plausible`].
fn flag_plausibility(joints: &Joints2, est: PoseEstimate) -> PoseEstimate {
    let vis: Vec<&[f64; 2]> = joints.xy.iter().zip(&joints.visible).filter(|(_, v)| **v).map(|(p, _)| p).collect();
    let span = |a: usize| {
        let (lo, hi) = vis.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[a]), h.max(p[a])));
        hi - lo
    };
    let extent = span(0).hypot(span(1));
    let at_bound = est.factors.k.iter().any(|&k| k <= FACTOR_MIN + 1e-9 || k >= FACTOR_MAX - 1e-9);
    let plausible = est.rms.is_finite() && est.rms <= IMPLAUSIBLE_RMS * extent && !at_bound;
    PoseEstimate { plausible, ..est }
}

/// [`estimate_pose`] with the dictionary's proportions (no factors, no plausibility flag).
fn estimate_fixed(dict: &Dictionary, joints: &Joints2, opts: &PoseOptions) -> Result<PoseEstimate> {
    let prob = Problem::new(dict, joints, opts.prior)?;
    if opts.starts == 0 || dict.exemplars.ncols() == 0 {
        let cam = fit_camera(&prob.pose(&[], &[]), &prob.uv, &prob.vis, &CameraPrior::of(opts))?;
        return Ok(with_joint_fit(&prob, opts, pursue(&prob, opts, cam, None)?));
    }
    let ranking =
        super::exemplar::affine_ranking(&prob, super::exemplar::shortlist_len(opts.starts).max(opts.limb_candidates));
    let candidates: Vec<usize> = ranking.iter().take(opts.limb_candidates).map(|r| r.0).collect();
    let mut hyps: Vec<(f64, PoseEstimate)> = Vec::new();
    let mut last_err = None;
    for s in super::exemplar::nearest(&prob, &ranking, opts.starts, &CameraPrior::of(opts))? {
        let (p, cam, parts) = if candidates.is_empty() {
            (prob.with_base(dict.exemplars.column(s.index).into_owned()), s.camera, [s.index; 5])
        } else {
            let (base, parts) = super::exemplar::compose(&prob, &s, &candidates);
            let p = prob.with_base(base);
            match fit_camera(&p.pose(&[], &[]), &p.uv, &p.vis, &CameraPrior::of(opts)) {
                Ok(cam) => (p, cam, parts),
                Err(e) => {
                    last_err = Some(e);
                    continue;
                }
            }
        };
        match pursue(&p, opts, cam, Some(parts)) {
            Ok(est) => {
                hyps.push((p.total_objective(&est.camera, &est.bases, &est.weights), est));
            }
            Err(e) => last_err = Some(e),
        }
    }
    let est = match (super::blend::blend(&prob, &hyps, opts.blend), last_err) {
        // A blend of several results is refined once more from its own base pose (the average
        // fits the 2-D joints less well than each result; the 3-D error is unchanged).
        (Some(est), _) if opts.refine && hyps.len() > 1 && opts.blend > 0.0 && !est.bases.is_empty() => {
            super::refine::refine_problem(&prob.with_base(super::dictionary::pose_to_vec(&est.base)), opts, &est)?
        }
        (Some(est), _) => est,
        (None, Some(e)) => return Err(e),
        (None, None) => return Err(crate::error::Error::Degenerate("no exemplar start admitted a camera".into())),
    };
    Ok(with_joint_fit(&prob, opts, est))
}

/// The free-joint refinement of `est` when [`PoseOptions::joint_noise`] > 0.
fn with_joint_fit(prob: &Problem, opts: &PoseOptions, est: PoseEstimate) -> PoseEstimate {
    if opts.joint_noise > 0.0 {
        let priors = super::joint_fit::Priors { standing: opts.standing_prior, knee_limits: opts.knee_limits };
        super::joint_fit::fit_joints(prob, &est, opts.joint_noise, &priors)
    } else {
        est
    }
}

/// The pursuit (and refinement, if enabled) from the base pose of `prob` with camera `cam`.
fn pursue(
    prob: &Problem,
    opts: &PoseOptions,
    mut cam: WeakPerspective,
    parts: Option<[usize; 5]>,
) -> Result<PoseEstimate> {
    let dict = prob.dict;
    let bound = opts.kappa * dict.sum_sq_lengths();
    let mean = prob.pose(&[], &[]);
    let mut bases: Vec<usize> = Vec::new();
    let mut w: Vec<f64> = Vec::new();
    let mut rms = prob.rms(&cam, &mean);
    let mut obj = prob.objective(&cam, &mean);
    let mut feasible = prob.constraint(&[]).value(&DVector::zeros(0)).abs() <= bound;
    let max_bases = opts.max_bases.min(dict.num_bases()).min(2 * prob.vis.len() - 7);
    while bases.len() < max_bases && (rms > opts.tolerance || !feasible) {
        let x = prob.pose(&bases, &w);
        let r = prob.residuals(&cam, &x);
        // With the camera's image rows pu, pv (no translation), basis b's projection a has
        // aᵀr = B_bᵀ z, z_p = pu r_u,p + pv r_v,p, and ‖a‖² = ⟨pu puᵀ + pv pvᵀ, C_b⟩.
        let (pu, pv) = (cam.r.row(0).transpose() * cam.sx, cam.r.row(1).transpose() * -cam.sy);
        let mut z = [0.0; 3 * NUM_JOINTS];
        for (i, &p) in prob.vis.iter().enumerate() {
            let zp = pu * r[2 * i] + pv * r[2 * i + 1];
            z[3 * p..3 * p + 3].copy_from_slice(zp.as_slice());
        }
        let m = pu * pu.transpose() + pv * pv.transpose();
        let mw = [m[(0, 0)], 2.0 * m[(0, 1)], 2.0 * m[(0, 2)], m[(1, 1)], 2.0 * m[(1, 2)], m[(2, 2)]];
        let mut scored: Vec<(usize, f64)> = Vec::with_capacity(dict.num_bases());
        for (b, (col, c)) in dict.bases.column_iter().zip(prob.basis_gram.iter()).enumerate() {
            if bases.contains(&b) {
                continue;
            }
            let dot: f64 = col.as_slice().iter().zip(&z).map(|(x, y)| x * y).sum();
            let norm2: f64 = mw.iter().zip(c).map(|(x, y)| x * y).sum();
            if norm2 > 0.0 {
                scored.push((b, dot.abs() / norm2.sqrt()));
            }
        }
        // The CANDIDATES most correlated with the residual are tried with the constrained weight
        // solve for the current camera; the one leaving the smallest objective is added (ties
        // by column, so the choice does not depend on the selection algorithm).
        let order = |a: &(usize, f64), b: &(usize, f64)| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0));
        if CANDIDATES < scored.len() {
            scored.select_nth_unstable_by(CANDIDATES, order);
            scored.truncate(CANDIDATES);
        }
        scored.sort_unstable_by(order);
        let mut best: Option<(usize, f64)> = None;
        for &(b, _) in scored.iter().take(CANDIDATES) {
            let mut nb = bases.clone();
            nb.push(b);
            let (a, r0) = prob.linear_system(&cam, &nb);
            let sol = qcls::solve(&a, &r0, &prob.constraint(&nb), -bound, bound);
            let f = (&a * &sol.w - &r0).norm_squared() + if sol.feasible { 0.0 } else { f64::MAX / 4.0 };
            if best.is_none_or(|(_, s)| f < s) {
                best = Some((b, f));
            }
        }
        let Some((b, _)) = best else { break };
        let mut nb = bases.clone();
        nb.push(b);
        let con = prob.constraint(&nb);
        let mut ncam = cam;
        let mut nw = DVector::zeros(nb.len());
        let mut nrms = f64::INFINITY;
        let mut nobj = f64::INFINITY;
        let mut nfeasible = false;
        for _ in 0..ALTERNATIONS {
            let (a, r0) = prob.linear_system(&ncam, &nb);
            let sol = qcls::solve(&a, &r0, &con, -bound, bound);
            nw = sol.w;
            nfeasible = sol.feasible;
            let x = prob.pose(&nb, nw.as_slice());
            ncam = match fit_camera(&x, &prob.uv, &prob.vis, &CameraPrior::of(opts)) {
                Ok(c) => c,
                Err(_) => break,
            };
            let new = prob.total_objective(&ncam, &nb, nw.as_slice());
            let done = (nobj - new).abs() <= 1e-6 * nobj;
            nobj = new;
            nrms = prob.rms(&ncam, &x);
            if done {
                break;
            }
        }
        if feasible && !(nobj < obj * (1.0 - 2e-3)) {
            break;
        }
        bases = nb;
        w = nw.iter().copied().collect();
        cam = ncam;
        rms = nrms;
        obj = nobj;
        feasible = nfeasible;
    }
    let est = PoseEstimate { base_parts: parts, ..finish(prob, cam, bases, w) };
    if opts.refine && !est.bases.is_empty() {
        return super::refine::refine_problem(prob, opts, &est);
    }
    Ok(est)
}

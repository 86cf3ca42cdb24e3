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

use super::alternatives::{Alternative, DepthCosts};
use super::bend_prior::BendPrior;
use super::camera_fit::{fit_camera, CameraPrior};
use super::depth_hint::{hint_cost, DepthHint};
use super::dictionary::Dictionary;
use super::factor_prior::FactorPrior;
use super::figure::{estimate_factors_with_prior, BodyFactors, FACTOR_MAX, FACTOR_MIN, NUM_GROUPS};
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
    /// The ranked depth readings ([`super::alternatives`]): `[0]` is this estimate itself, the
    /// others flip limbs in depth, best first; at most [`super::alternatives::MAX_ALTERNATIVES`].
    /// Empty for an estimate not made by [`estimate_pose`] (e.g. [`super::refine_pose`]'s).
    pub alternatives: Vec<Alternative>,
    /// The scores of every reading ([`super::alternatives::DepthCosts`]), kept so that
    /// [`super::alternatives::flip_limb`] re-ranks without the dictionary; `None` with no alternatives.
    pub depth_costs: Option<DepthCosts>,
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
        alternatives: Vec::new(),
        depth_costs: None,
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
/// (the first estimate is kept when that second solve fails or fits the image worse). With
/// [`PoseOptions::factor_prior`] the factors' prior is the learned one
/// ([`super::factor_prior`]); when the solve with those factors fits the image worse than the
/// first estimate, the fixed prior's factors are tried (from half the exemplar starts) before
/// falling back to the first estimate. With [`PoseOptions::depth_prior`] > 0 the learned
/// joints' depths ([`FactorPrior::depth_hint`]) weigh the solver's choices as an image cue's
/// would ([`estimate_pose_hinted`]), predicted from the 2-D joints each solve sees, except for a
/// figure the standing prior takes as standing ([`super::plausibility::standing_in_image`]).
/// Every estimate is flagged for plausibility ([`PoseEstimate::plausible`]).
pub fn estimate_pose(dict: &Dictionary, joints: &Joints2, opts: &PoseOptions) -> Result<PoseEstimate> {
    estimate_pose_hinted(dict, joints, opts, None)
}

/// [`estimate_pose`] with relative joint depths from an image cue ([`DepthHint`]): its cost is
/// added where the solver chooses between readings (the exemplar starts, each recomposed limb,
/// the blend of the hypotheses; see [`super::depth_hint`]); it replaces the learned depths of
/// [`PoseOptions::depth_prior`]. `None`, or a hint of weight 0, is [`estimate_pose`]. Errors:
/// those of [`estimate_pose`], the hint's ([`DepthHint::validate`]), and `CorruptData` when
/// [`PoseOptions::factor_prior`] or [`PoseOptions::depth_prior`] is on and the embedded prior
/// does not parse (a build fault).
pub fn estimate_pose_hinted(
    dict: &Dictionary,
    joints: &Joints2,
    opts: &PoseOptions,
    hint: Option<&DepthHint>,
) -> Result<PoseEstimate> {
    let prior = if opts.factor_prior || opts.depth_prior > 0.0 || opts.bend_prior > 0.0 {
        Some(FactorPrior::embedded()?)
    } else {
        None
    };
    estimate_pose_with_factor_prior(dict, joints, opts, hint, prior)
}

/// [`estimate_pose_hinted`] with the learned priors `prior` instead of the embedded ones (e.g.
/// ones trained without a validation split): its factors when [`PoseOptions::factor_prior`] is
/// on, its depths when [`PoseOptions::depth_prior`] > 0; `None` = neither (the fixed prior of
/// [`super::figure::estimate_factors`], no learned depths). Errors: those of
/// [`estimate_pose_hinted`].
pub fn estimate_pose_with_factor_prior(
    dict: &Dictionary,
    joints: &Joints2,
    opts: &PoseOptions,
    hint: Option<&DepthHint>,
    prior: Option<&FactorPrior>,
) -> Result<PoseEstimate> {
    opts.validate()?;
    if let Some(h) = hint {
        h.validate()?;
    }
    // An image cue's depths decide the limbs' depths and bends: the free-joint step then holds
    // the limb joints as the others and has no bend prior (as it has no learned depths).
    let cued;
    let opts = if hint.is_some_and(|h| h.weight > 0.0) {
        cued = PoseOptions { limb_depth_sd: 0.0, bend_prior: 0.0, ..*opts };
        &cued
    } else {
        opts
    };
    // A figure the image shows standing takes the standing prior's depths instead of the
    // learned ones, which read the bundled example's short drawn legs as a lean with the feet
    // behind (docs/benchmarks-history.md, "Held-out real motion, drawn proportions,
    // plausibility priors").
    let standing = opts.standing_prior
        && opts.joint_noise > 0.0
        && super::plausibility::standing_in_image(&joints.xy, &joints.visible);
    let hints = Hints {
        given: hint,
        prior: prior.filter(|_| opts.depth_prior > 0.0 && !standing),
        weight: opts.depth_prior,
        bend: prior.and_then(|p| p.bend.as_ref()).filter(|_| opts.bend_prior > 0.0),
    };
    let factor_prior = prior.filter(|_| opts.factor_prior);
    let first =
        estimate_fixed(dict, joints, opts, hints.of(joints).as_ref(), hints.learned(joints).as_ref(), hints.bend)?;
    let est = if opts.proportions { with_proportions(dict, joints, opts, first, &hints, factor_prior) } else { first };
    let est = with_straight_limbs(dict, joints, opts, est);
    let est = with_alternatives(dict, joints, opts, hints.of(joints).as_ref(), est);
    finite_estimate(flag_plausibility(joints, est))
}

/// `est` with its ranked depth readings ([`super::alternatives`]): the limb candidates are the
/// solver's (the first [`PoseOptions::limb_candidates`] exemplars of the affine ranking of
/// `joints`) and the exemplars `est` started from; none without exemplar starts.
fn with_alternatives(
    dict: &Dictionary,
    joints: &Joints2,
    opts: &PoseOptions,
    hint: Option<&DepthHint>,
    est: PoseEstimate,
) -> PoseEstimate {
    let Ok(prob) = Problem::new(dict, joints, 0.0) else { return est };
    let ex = &dict.exemplars;
    let mut cols: Vec<usize> = est.base_parts.map(|p| p.to_vec()).unwrap_or_default();
    if opts.starts > 0 && opts.limb_candidates > 0 && ex.ncols() > 0 {
        cols.extend(super::exemplar::affine_ranking(&prob, opts.limb_candidates).into_iter().map(|r| r.0));
    }
    cols.sort_unstable();
    cols.dedup();
    let n = ex.nrows();
    let candidates: Vec<&[f64]> =
        cols.iter().filter(|&&k| k < ex.ncols()).map(|&k| &ex.as_slice()[k * n..(k + 1) * n]).collect();
    let x: [Vector3<f64>; NUM_JOINTS] = std::array::from_fn(|j| Vector3::from(est.joints[j]));
    let costs =
        super::alternatives::depth_costs(&est.joints, &est.camera, prob.objective(&est.camera, &x), &candidates, hint);
    super::alternatives::with_alternatives(est, costs)
}

/// `e`, or [`Error::NonFinite`] naming its first NaN or infinite joint, camera value, RMS,
/// length excess or basis weight (a dictionary of extreme values overflows; never reported OK).
fn finite_estimate(e: PoseEstimate) -> Result<PoseEstimate> {
    let c = &e.camera;
    let named = (e.joints.iter().flatten().map(|&v| ("pose joint", v)))
        .chain([("camera sx", c.sx), ("camera sy", c.sy), ("camera t", c.t[0]), ("camera t", c.t[1])])
        .chain(c.r.iter().map(|&v| ("camera rotation", v)))
        .chain([("pose RMS", e.rms), ("length excess", e.length_excess)])
        .chain(e.weights.iter().map(|&v| ("basis weight", v)))
        .chain(e.alternatives.iter().flat_map(|a| a.joints.iter().flatten().map(|&v| ("alternative joint", v))))
        .chain(e.alternatives.iter().map(|a| ("alternative score", a.score)));
    for (name, v) in named {
        crate::error::ensure_finite(name, v)?;
    }
    Ok(e)
}

/// Where a solve's depth hint comes from: the caller's image cue, else the learned depths of
/// the 2-D joints that solve sees; and the learned bend prior of the free-joint step.
struct Hints<'a> {
    given: Option<&'a DepthHint>,
    prior: Option<&'a FactorPrior>,
    weight: f64,
    bend: Option<&'a BendPrior>,
}

impl Hints<'_> {
    /// The hint for a solve on the 2-D joints `joints` (a given hint of weight 0 counts as none).
    fn of(&self, joints: &Joints2) -> Option<DepthHint> {
        match self.given {
            Some(h) if h.weight > 0.0 => Some(*h),
            _ => self.prior.and_then(|p| p.depth_hint(joints, self.weight)),
        }
    }

    /// The learned depths of the 2-D joints `joints` for the free-joint step's pull: none when an
    /// image cue is given (the image's depths decide where it has them, not the learned prior).
    fn learned(&self, joints: &Joints2) -> Option<DepthHint> {
        match self.given {
            Some(h) if h.weight > 0.0 => None,
            _ => self.prior.and_then(|p| p.depth_hint(joints, self.weight)),
        }
    }
}

/// The second solve of [`estimate_pose`] with estimated factors (see there).
fn with_proportions(
    dict: &Dictionary,
    joints: &Joints2,
    opts: &PoseOptions,
    first: PoseEstimate,
    hints: &Hints,
    prior: Option<&FactorPrior>,
) -> PoseEstimate {
    let c = &first.camera;
    // The learned prior's image scales, relative to the first solve's camera scale (the
    // convention of the factor estimate).
    let learned: Option<[(f64, f64); NUM_GROUPS]> =
        prior.and_then(|p| p.predict(joints, &dict.bone_lengths)).map(|p| {
            let ls = 0.5 * (c.sx * c.sy).ln();
            std::array::from_fn(|g| (p.log_scale[g] - ls, p.sd[g]))
        });
    let fixed = || estimate_factors_with_prior(joints, &dict.bone_lengths, &first.joints, &c.r, c.sx, c.sy, None);
    let Some(l) = learned else { return second_solve(dict, joints, opts, &first, hints, fixed()).unwrap_or(first) };
    // The factors under the learned prior; when that solve fits the image worse than the first
    // estimate, the fixed prior's factors are tried (docs/benchmarks-history.md, "Held-out
    // real motion, drawn proportions, plausibility priors").
    let f = estimate_factors_with_prior(joints, &dict.bone_lengths, &first.joints, &c.r, c.sx, c.sy, Some(&l));
    match second_solve(dict, joints, opts, &first, hints, f) {
        Some(e) => e,
        None => {
            // From half the exemplar starts: as accurate on the validation split, less CPU on
            // standard figures, where this fallback runs most (docs/benchmarks-history.md,
            // "Held-out real motion, drawn proportions, plausibility priors").
            let half = PoseOptions { starts: opts.starts.div_ceil(2), ..*opts };
            second_solve(dict, joints, &half, &first, hints, fixed()).unwrap_or(first)
        }
    }
}

/// The solve on the 2-D joints unstylised by the factors `f`, with the factors applied to its
/// joints; `None` when the factors are all 1, the solve fails, or it fits the 2-D joints worse
/// than the first estimate (and above the tolerance).
fn second_solve(
    dict: &Dictionary,
    joints: &Joints2,
    opts: &PoseOptions,
    first: &PoseEstimate,
    hints: &Hints,
    f: BodyFactors,
) -> Option<PoseEstimate> {
    if f.k.iter().all(|k| (k - 1.0).abs() < 1e-3) {
        return None;
    }
    let plain = f.unstylise_2d(joints);
    let second =
        estimate_fixed(dict, &plain, opts, hints.of(&plain).as_ref(), hints.learned(&plain).as_ref(), hints.bend)
            .ok()?;
    let x = f.apply(&second.joints);
    let xs: [Vector3<f64>; NUM_JOINTS] = std::array::from_fn(|j| Vector3::from(x[j]));
    let prob = Problem::new(dict, joints, 0.0).ok()?;
    let rms = prob.rms(&second.camera, &xs);
    if !(rms <= first.rms) && rms > opts.tolerance {
        return None;
    }
    Some(PoseEstimate { joints: x, rms, factors: f, ..second })
}

/// `est` with its limbs drawn straight straightened ([`super::straighten`]) when
/// [`PoseOptions::straight_limbs`] is on; the base pose is redefined so that the joints are still
/// the factors applied to base + Σ B w, and the RMS is that of the new joints.
fn with_straight_limbs(dict: &Dictionary, joints: &Joints2, opts: &PoseOptions, est: PoseEstimate) -> PoseEstimate {
    if !opts.straight_limbs {
        return est;
    }
    let (x, n) = super::straighten::straighten_limbs(&est.joints, &est.camera, joints);
    if n == 0 {
        return est;
    }
    let Ok(prob) = Problem::new(dict, joints, 0.0) else { return est };
    let inverse = BodyFactors { k: est.factors.k.map(|k| 1.0 / k) };
    let (old, new) = (inverse.apply(&est.joints), inverse.apply(&x));
    let base = std::array::from_fn(|j| std::array::from_fn(|a| est.base[j][a] + new[j][a] - old[j][a]));
    let xs: [Vector3<f64>; NUM_JOINTS] = std::array::from_fn(|j| Vector3::from(x[j]));
    PoseEstimate { joints: x, rms: prob.rms(&est.camera, &xs), base, ..est }
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

/// [`estimate_pose`] with the dictionary's proportions (no factors, no plausibility flag);
/// `hint` weighs the solver's choices, `learned` (the learned depths) pulls the free-joint step,
/// `bend` is its learned bend prior.
fn estimate_fixed(
    dict: &Dictionary,
    joints: &Joints2,
    opts: &PoseOptions,
    hint: Option<&DepthHint>,
    learned: Option<&DepthHint>,
    bend: Option<&BendPrior>,
) -> Result<PoseEstimate> {
    let prob = Problem::new(dict, joints, opts.prior)?;
    if opts.starts == 0 || dict.exemplars.ncols() == 0 {
        let cam = fit_camera(&prob.pose(&[], &[]), &prob.uv, &prob.vis, &CameraPrior::of(opts))?;
        return Ok(with_joint_fit(&prob, opts, pursue(&prob, opts, cam, None)?, learned, bend));
    }
    let ranking =
        super::exemplar::affine_ranking(&prob, super::exemplar::shortlist_len(opts.starts).max(opts.limb_candidates));
    let candidates: Vec<usize> = ranking.iter().take(opts.limb_candidates).map(|r| r.0).collect();
    let mut hyps: Vec<(f64, PoseEstimate)> = Vec::new();
    let mut last_err = None;
    for s in super::exemplar::nearest(&prob, &ranking, opts.starts, &CameraPrior::of(opts), hint)? {
        let (p, cam, parts) = if candidates.is_empty() {
            (prob.with_base(dict.exemplars.column(s.index).into_owned()), s.camera, [s.index; 5])
        } else {
            let (base, parts) = super::exemplar::compose(&prob, &s, &candidates, hint);
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
                let x: [Vector3<f64>; NUM_JOINTS] = std::array::from_fn(|j| Vector3::from(est.joints[j]));
                let f = p.total_objective(&est.camera, &est.bases, &est.weights) + hint_cost(hint, &est.camera, &x);
                hyps.push((f, est));
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
    Ok(with_joint_fit(&prob, opts, est, learned, bend))
}

/// The free-joint refinement of `est` when [`PoseOptions::joint_noise`] > 0, pulled toward the
/// learned depths `learned` at [`PoseOptions::learned_depth_sd`], its bone lengths uncertain at
/// [`PoseOptions::bone_length_sd`] and its bends under the learned bend prior `bend` at
/// [`PoseOptions::bend_prior`].
fn with_joint_fit(
    prob: &Problem,
    opts: &PoseOptions,
    est: PoseEstimate,
    learned: Option<&DepthHint>,
    bend: Option<&BendPrior>,
) -> PoseEstimate {
    if opts.joint_noise > 0.0 {
        let depths = learned.filter(|h| opts.learned_depth_sd > 0.0 && h.known.iter().all(|k| *k)).map(|h| h.depth);
        let priors = super::joint_fit::Priors {
            standing: opts.standing_prior,
            knee_limits: opts.knee_limits,
            depths,
            depth_sd: opts.learned_depth_sd,
            length_sd: opts.bone_length_sd,
            limb_depth_sd: opts.limb_depth_sd,
            bend,
            bend_weight: opts.bend_prior,
        };
        super::joint_fit::fit_joints(prob, &est, opts.joint_noise, &priors)
    } else {
        est
    }
}

/// `B_bᵀ z` for every basis b, each summed in joint-coordinate order. Eight columns at a time
/// with their own sums: the additions of one column form a chain, and interleaving eight
/// chains keeps the adder busy (the sums are those of a plain loop, bit for bit).
fn basis_dots(dict: &Dictionary, z: &[f64; 3 * NUM_JOINTS]) -> Vec<f64> {
    const LANES: usize = 8;
    let n = 3 * NUM_JOINTS;
    let data = dict.bases.as_slice();
    let mut out = Vec::with_capacity(dict.num_bases());
    let mut blocks = data.chunks_exact(LANES * n);
    for block in blocks.by_ref() {
        let mut acc = [0.0; LANES];
        for (i, zi) in z.iter().enumerate() {
            for (l, a) in acc.iter_mut().enumerate() {
                *a += block[l * n + i] * zi;
            }
        }
        out.extend_from_slice(&acc);
    }
    for col in blocks.remainder().chunks_exact(n) {
        out.push(col.iter().zip(z).map(|(x, y)| x * y).sum());
    }
    out
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
        // The CANDIDATES most correlated with the residual are tried with the constrained weight
        // solve for the current camera; the one leaving the smallest objective is added (ties
        // by column, so the choice does not depend on the selection algorithm).
        let order = |a: &(usize, f64), b: &(usize, f64)| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0));
        let mut scored: Vec<(usize, f64)> = Vec::with_capacity(CANDIDATES + 1);
        for (b, (dot, c)) in basis_dots(dict, &z).iter().zip(prob.basis_gram.iter()).enumerate() {
            if bases.contains(&b) {
                continue;
            }
            let norm2: f64 = mw.iter().zip(c).map(|(x, y)| x * y).sum();
            if norm2 > 0.0 {
                let s = (b, dot.abs() / norm2.sqrt());
                if scored.len() < CANDIDATES || scored.last().is_some_and(|l| order(&s, l).is_lt()) {
                    let at = scored.partition_point(|x| order(x, &s).is_lt());
                    scored.insert(at, s);
                    scored.truncate(CANDIDATES);
                }
            }
        }
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

#[cfg(test)]
pub(crate) mod tests {
    //! A fixed problem whose right answer is known: a hand-made dictionary of four bases over a
    //! 3-D mean pose, 2-D joints projected from the mean plus known weights of two of them.
    use super::*;
    use crate::pose::dictionary::{pose_to_vec, Action, POSE_DIM};
    use crate::pose::options::RotationTarget;
    use crate::skeleton::BONES;
    use nalgebra::{DMatrix, Matrix3};

    /// 0.6 of ARM's sideways part and 0.8 of LEG (its image correlates with both true bases).
    pub(crate) const DECOY: usize = 0;
    /// Right wrist out and elbow in, right wrist down and left wrist up, right wrist toward the
    /// viewer (its image is 0.6 of its length).
    pub(crate) const ARM: usize = 1;
    /// Left ankle out, left hip in.
    pub(crate) const LEG: usize = 2;
    /// Head toward the viewer: invisible to a camera with R = I.
    pub(crate) const DEPTH: usize = 3;
    /// Right wrist down, left wrist up: an image along v only.
    pub(crate) const SHRUG: usize = 4;

    /// The true weights of the observations, metres.
    pub(crate) const W_ARM: f64 = 0.15;
    pub(crate) const W_LEG: f64 = 0.05;

    /// A standing figure with depth (so the camera's rotation is observable). The joints each
    /// basis moves in pairs share the coordinate they move along (right wrist and elbow x,
    /// both wrists y, left ankle and hip x), and each pair moves by opposite amounts: no basis
    /// moves the figure's centroid or changes its spread, so the camera fitted to the mean pose
    /// is already the true one and the pursuit's weights are exact.
    pub(crate) fn mean_pose() -> Joints3 {
        [
            [0.0, 1.6, 0.05],
            [0.0, 1.45, 0.0],
            [-0.18, 1.45, 0.06],
            [-0.24, 1.17, -0.08],
            [-0.24, 0.92, 0.1],
            [0.18, 1.45, -0.06],
            [0.21, 1.17, 0.07],
            [0.23, 0.92, -0.09],
            [0.0, 0.95, 0.0],
            [-0.1, 0.9, -0.05],
            [-0.11, 0.5, 0.08],
            [-0.1, 0.08, -0.03],
            [0.1, 0.9, 0.05],
            [0.11, 0.5, -0.06],
            [0.1, 0.08, 0.04],
        ]
    }

    /// The dictionary: the mean above (meeting the length constraint exactly) and five bases.
    pub(crate) fn fixture() -> Dictionary {
        let unit = |entries: &[(usize, usize, f64)]| {
            let mut v = DVector::zeros(POSE_DIM);
            for &(j, a, x) in entries {
                v[3 * j + a] = x;
            }
            v.normalize()
        };
        // Orthonormal pair moves: right wrist out / elbow in, right wrist down / left wrist up,
        // left ankle out / hip in.
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let (wrist_out, wrists_y, ankle_out) =
            ([(4, 0, -h), (3, 0, h)], [(4, 1, -h), (7, 1, h)], [(14, 0, h), (12, 0, -h)]);
        // (joint, axis, amount) entries of a move, and moves with their factors.
        type Move<'a> = &'a [(usize, usize, f64)];
        let scaled = |parts: &[(Move, f64)]| -> Vec<(usize, usize, f64)> {
            parts.iter().flat_map(|(p, s)| p.iter().map(move |&(j, a, x)| (j, a, x * s))).collect()
        };
        let cols = [
            unit(&scaled(&[(&wrist_out, 0.6), (&ankle_out, 0.8)])),
            unit(&scaled(&[(&wrist_out, 0.48), (&wrists_y, 0.36), (&[(4, 2, 1.0)], 0.8)])),
            unit(&ankle_out),
            unit(&[(0, 2, 1.0)]),
            unit(&wrists_y),
        ];
        let x = mean_pose();
        let bone_lengths = std::array::from_fn(|b| {
            let (p, c) = BONES[b];
            (Vector3::from(x[c]) - Vector3::from(x[p])).norm()
        });
        Dictionary {
            mean: pose_to_vec(&x),
            bases: DMatrix::from_columns(&cols),
            sigma: DVector::from_element(5, 0.1),
            bone_lengths,
            actions: vec![Action { name: "fixture".into(), first: 0, count: 5 }],
            exemplars: DMatrix::zeros(POSE_DIM, 0),
            provenance: "test fixture".into(),
            frame_cache: Default::default(),
        }
    }

    /// The camera of the observations: R = I, 250 px/m.
    pub(crate) fn true_camera() -> WeakPerspective {
        WeakPerspective { sx: 250.0, sy: 250.0, r: Matrix3::identity(), t: [200.0, 450.0] }
    }

    /// 2-D joints of the mean plus `w` (basis, weight) under [`true_camera`], with the head moved
    /// `noise` px right and the neck as much left: a residual no basis and no camera explains
    /// (zero mean, and head and neck share their x, so no scale absorbs it).
    pub(crate) fn observe(d: &Dictionary, w: &[(usize, f64)], noise: f64) -> Joints2 {
        let cam = true_camera();
        let mut v = d.mean.clone();
        for &(b, wb) in w {
            v.axpy(wb, &d.bases.column(b), 1.0);
        }
        let mut j = Joints2 {
            xy: std::array::from_fn(|p| cam.project(&Vector3::new(v[3 * p], v[3 * p + 1], v[3 * p + 2]))),
            visible: [true; NUM_JOINTS],
        };
        j.xy[0][0] += noise;
        j.xy[1][0] -= noise;
        j
    }

    /// The paper's pursuit alone from μ, the camera rotation held at I (α = 1 toward identity),
    /// κ loose enough for the true weights.
    pub(crate) fn options() -> PoseOptions {
        PoseOptions {
            kappa: 0.5,
            alpha: 1.0,
            alpha_target: RotationTarget::Identity,
            equal_scales: true,
            max_bases: 4,
            tolerance: 0.0,
            refine: false,
            prior: 0.0,
            starts: 0,
            limb_candidates: 0,
            blend: 0.0,
            joint_noise: 0.0,
            proportions: false,
            standing_prior: false,
            knee_limits: false,
            factor_prior: false,
            depth_prior: 0.0,
            learned_depth_sd: 0.0,
            bone_length_sd: 0.0,
            limb_depth_sd: 0.0,
            bend_prior: 0.0,
            straight_limbs: false,
        }
    }

    fn truth() -> [(usize, f64); 2] {
        [(ARM, W_ARM), (LEG, W_LEG)]
    }

    #[test]
    fn picks_the_most_correlated_basis_and_recovers_the_weights() {
        let d = fixture();
        d.validate().unwrap();
        let j = observe(&d, &truth(), 1.0);
        let est = estimate_pose(&d, &j, &options()).unwrap();
        // ARM first: its correlation |aᵀr| / ‖a‖ (22.5 px) beats the decoy's (20.8 px), SHRUG's
        // (13.5 px) and LEG's (12.5 px), although the decoy's |aᵀr| is larger (its image is
        // longer); then LEG. Nothing lowers the objective further (the head/neck residual is
        // orthogonal to every basis) and DEPTH has no image, so the pursuit stops with two.
        assert_eq!(est.bases, [ARM, LEG], "{est:?}");
        assert!((est.weights[0] - W_ARM).abs() < 1e-6 && (est.weights[1] - W_LEG).abs() < 1e-6, "{:?}", est.weights);
        // What is left is the head/neck residual: 2 px² over 15 joints.
        let floor = (2.0f64 / 15.0).sqrt();
        assert!((est.rms - floor).abs() < 1e-6, "rms {} vs {floor}", est.rms);
        assert!(est.length_excess.abs() <= 0.5, "{}", est.length_excess);
        let cam = true_camera();
        assert!((est.camera.r - cam.r).norm() < 1e-12 && (est.camera.sx - 250.0).abs() < 1e-6, "{:?}", est.camera);
        assert!((est.camera.t[0] - cam.t[0]).abs() < 1e-6 && (est.camera.t[1] - cam.t[1]).abs() < 1e-6);
        // The joints are the mean plus the chosen bases.
        let x = fixture().mean.clone() + d.bases.column(ARM) * est.weights[0] + d.bases.column(LEG) * est.weights[1];
        for p in 0..NUM_JOINTS {
            for a in 0..3 {
                assert!((est.joints[p][a] - x[3 * p + a]).abs() < 1e-12, "joint {p} axis {a}");
            }
        }
        // Without noise the fit is exact (the tolerance keeps a third basis from fitting
        // rounding errors).
        let exact =
            estimate_pose(&d, &observe(&d, &truth(), 0.0), &PoseOptions { tolerance: 1e-6, ..options() }).unwrap();
        assert_eq!(exact.bases, [ARM, LEG]);
        assert!(exact.rms < 1e-6, "{}", exact.rms);
        // A motion along v only is found as such (its image norm counts v as much as u).
        let shrug = estimate_pose(&d, &observe(&d, &[(SHRUG, 0.1)], 1.0), &options()).unwrap();
        assert_eq!(shrug.bases, [SHRUG]);
        assert!((shrug.weights[0] - 0.1).abs() < 1e-9 && (shrug.rms - floor).abs() < 1e-9, "{shrug:?}");
        // DEPTH is invisible at R = I: never chosen, even when it is the truth.
        let depth = estimate_pose(&d, &observe(&d, &[(DEPTH, 0.1)], 1.0), &options()).unwrap();
        assert!(!depth.bases.contains(&DEPTH), "{depth:?}");
    }

    #[test]
    fn weights_stay_within_the_length_bound() {
        // With κ = 0.02 the true weights lengthen the bones too much (g/Σl² = 0.043): the
        // pursuit's weights stay within the bound, using most of it (more bases are taken to
        // fit the image within it).
        let d = fixture();
        let j = observe(&d, &truth(), 0.0);
        let est = estimate_pose(&d, &j, &PoseOptions { kappa: 0.02, ..options() }).unwrap();
        assert_eq!(est.bases[0], ARM, "{est:?}");
        assert!(est.length_excess <= 0.02 + 1e-12 && est.length_excess > 0.018, "{}", est.length_excess);
        let loose = estimate_pose(&d, &j, &options()).unwrap();
        assert!(loose.length_excess > 0.04 && loose.length_excess < 0.5, "{}", loose.length_excess);
    }

    #[test]
    fn drawn_proportions_are_estimated_applied_and_reported() {
        // Legs drawn 30 % long: the factors find longer legs, the joints carry them, and the
        // reported RMS is that of the reported joints on the drawn 2-D joints.
        let d = fixture();
        let drawn = BodyFactors { k: [1.0, 1.0, 1.0, 1.0, 1.0, 1.3] }.apply(&mean_pose());
        let cam = true_camera();
        let mut j =
            Joints2 { xy: std::array::from_fn(|p| cam.project(&Vector3::from(drawn[p]))), visible: [true; NUM_JOINTS] };
        j.xy[0][0] += 1.0;
        j.xy[1][0] -= 1.0;
        let plain = estimate_pose(&d, &j, &options()).unwrap();
        let est = estimate_pose(&d, &j, &PoseOptions { proportions: true, ..options() }).unwrap();
        // Relative to the arms (the figure's scale takes up a common factor).
        assert!(est.factors.k[5] > 1.2 * est.factors.k[3], "{:?}", est.factors);
        assert!(est.rms < plain.rms, "{} vs {}", est.rms, plain.rms);
        let x: [Vector3<f64>; NUM_JOINTS] = std::array::from_fn(|p| Vector3::from(est.joints[p]));
        let prob = Problem::new(&d, &j, 0.0).unwrap();
        assert!((prob.rms(&est.camera, &x) - est.rms).abs() < 1e-9, "{} vs {}", prob.rms(&est.camera, &x), est.rms);
        let bone = |x: &Joints3, a: usize, b: usize| (Vector3::from(x[a]) - Vector3::from(x[b])).norm();
        let shin_to_forearm = |x: &Joints3| bone(x, 13, 14) / bone(x, 3, 4);
        assert!(
            shin_to_forearm(&est.joints) > 1.2 * shin_to_forearm(&mean_pose()),
            "{} vs {}",
            shin_to_forearm(&est.joints),
            shin_to_forearm(&mean_pose())
        );
    }

    #[test]
    fn an_exemplar_start_is_reported() {
        // One exemplar (the mean itself): a start from it names it as every part.
        let mut d = fixture();
        d.exemplars = d.mean.clone().reshape_generic(nalgebra::Dyn(POSE_DIM), nalgebra::Dyn(1));
        let j = observe(&d, &truth(), 1.0);
        let est = estimate_pose(&d, &j, &PoseOptions { starts: 1, ..options() }).unwrap();
        assert_eq!(est.base_parts, Some([0; 5]));
        assert_eq!(est.bases, [ARM, LEG]);
    }

    #[test]
    fn an_estimate_far_from_the_joints_is_flagged_implausible() {
        // The RMS limit is 5 % of the visible joints' diagonal (about 19 px here): 1 px of
        // head/neck residual is plausible, 60 px is not.
        let d = fixture();
        let ok = estimate_pose(&d, &observe(&d, &truth(), 1.0), &options()).unwrap();
        assert!(ok.plausible, "{ok:?}");
        let far = estimate_pose(&d, &observe(&d, &truth(), 60.0), &options()).unwrap();
        assert!(far.rms > 20.0 && !far.plausible, "{far:?}");
    }

    /// A group factor at either end of its range means the evidence wanted more than the prior
    /// allows: flagged implausible, however well the joints fit; just inside the range it is not.
    #[test]
    fn a_factor_at_its_bound_is_flagged_implausible() {
        let d = fixture();
        let j = observe(&d, &truth(), 1.0);
        let est = estimate_pose(&d, &j, &options()).unwrap();
        assert!(est.plausible, "{est:?}");
        let with_factor = |k: f64| {
            let mut factors = est.factors;
            factors.k[2] = k;
            flag_plausibility(&j, PoseEstimate { factors, ..est.clone() }).plausible
        };
        assert!(!with_factor(FACTOR_MIN) && !with_factor(FACTOR_MAX));
        assert!(with_factor(FACTOR_MIN + 1e-6) && with_factor(FACTOR_MAX - 1e-6) && with_factor(1.0));
    }

    #[test]
    fn refinement_runs_after_the_pursuit_when_enabled() {
        // The pursuit holds R = I (α = 1); the refinement frees it and uses it on the head/neck
        // residual (the head has depth), from the pursuit's own result.
        let d = fixture();
        let j = observe(&d, &truth(), 1.0);
        let plain = estimate_pose(&d, &j, &options()).unwrap();
        let refined = estimate_pose(&d, &j, &PoseOptions { refine: true, ..options() }).unwrap();
        // (refine_pose lists no depth readings; estimate_pose adds them after the refinement.)
        assert_eq!(
            PoseEstimate { alternatives: Vec::new(), depth_costs: None, ..refined.clone() },
            crate::pose::refine_pose(&d, &j, &PoseOptions { refine: true, ..options() }, &plain).unwrap()
        );
        assert!(refined.rms < plain.rms - 1e-4, "{} vs {}", refined.rms, plain.rms);
        // Nothing to refine without bases.
        let mean = estimate_pose(&d, &j, &PoseOptions { refine: true, max_bases: 0, ..options() }).unwrap();
        assert!(mean.bases.is_empty());
        assert_eq!(mean.camera.r, Matrix3::identity());
    }

    #[test]
    fn stops_at_max_bases_and_at_the_tolerance() {
        let d = fixture();
        let j = observe(&d, &truth(), 1.0);
        let one = estimate_pose(&d, &j, &PoseOptions { max_bases: 1, ..options() }).unwrap();
        assert_eq!(one.bases, [ARM]);
        assert!(one.rms > 1.0, "LEG's 12.5 px are left: {}", one.rms);
        let none = estimate_pose(&d, &j, &PoseOptions { max_bases: 0, ..options() }).unwrap();
        assert!(none.bases.is_empty() && none.weights.is_empty());
        assert!(none.rms > one.rms);
        // RMS ≤ tolerance stops: at exactly the RMS reached with one basis the pursuit stops
        // there; a hair below it, it goes on to LEG.
        let at = estimate_pose(&d, &j, &PoseOptions { tolerance: one.rms, ..options() }).unwrap();
        assert_eq!(at.bases, [ARM]);
        assert_eq!(at.rms, one.rms);
        let below = estimate_pose(&d, &j, &PoseOptions { tolerance: one.rms * (1.0 - 1e-9), ..options() }).unwrap();
        assert_eq!(below.bases, [ARM, LEG]);
        // Already within tolerance at the mean: no basis at all.
        let mean_only = estimate_pose(&d, &j, &PoseOptions { tolerance: none.rms, ..options() }).unwrap();
        assert!(mean_only.bases.is_empty());
    }

    #[test]
    fn a_step_gaining_less_than_the_threshold_is_undone() {
        // A little of the decoy in the observations: the part of its image outside ARM's and
        // LEG's (0.36 of it, 90 px per metre of weight) is all a third basis can still explain,
        // out of the 2 px² head/neck residual. About 0.03 % of the objective is below the
        // 0.2 % threshold (two bases); about 2 % is above it (a third basis is added).
        let d = fixture();
        let gain = |eps: f64| {
            let x = (90.0 * eps).powi(2);
            x / (2.0 + x)
        };
        let (small, large) = (2.5e-4, 2.3e-3);
        assert!(gain(small) < 1e-3 && gain(large) > 4e-3, "{} {}", gain(small), gain(large));
        let with = |eps: f64| {
            let mut w = truth().to_vec();
            w.push((DECOY, eps));
            estimate_pose(&d, &observe(&d, &w, 1.0), &options()).unwrap()
        };
        let kept = with(small);
        assert_eq!(kept.bases, [ARM, LEG], "{kept:?}");
        // The third basis is SHRUG, not the decoy: the decoy's leftover image is mostly along
        // v (0.8 of it), and ARM with SHRUG spans it.
        let added = with(large);
        assert_eq!(added.bases, [ARM, LEG, SHRUG], "{added:?}");
        let floor = (2.0f64 / 15.0).sqrt();
        assert!((added.rms - floor).abs() < 1e-9 && kept.rms > floor + 1e-6, "{} {}", added.rms, kept.rms);
    }
}

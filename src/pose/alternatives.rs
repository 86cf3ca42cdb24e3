//! Ranked depth readings of an estimate ([`PoseEstimate::alternatives`]) and the flip of one
//! limb's depth ([`flip_limb`]).
//!
//! Under weak perspective each limb bone (upper arm, forearm, thigh, shin) can point toward or
//! away from the camera with exactly the same image and length: reflecting the bone's offset
//! from its parent joint along the camera's viewing direction (and moving the joints below it
//! with it) keeps every 2-D joint and every bone length. One view cannot tell the two readings
//! apart; [`super::estimate_pose`] chooses one, and this module lists the others.
//!
//! **Readings.** A reading is a set of flipped limb bones relative to the estimate. A bone whose
//! depth offset is at most [`NO_DEPTH_SIN`] of its length lies in the picture plane: it has no
//! depth to flip (its reflection would be the same bone within 2·[`NO_DEPTH_SIN`] rad) and is never
//! flipped. With every bone in depth there are 2⁸ = 256 readings.
//!
//! **Score** (px², lower = better): the objective by which the solver chooses a limb among its
//! limb candidates ([`super::exemplar::compose`]: the candidate limb's reprojection plus the
//! depth hint's cost), taken in 3-D so that it sees depth:
//!
//! `score = Σ_visible ‖π(X_j) − u_j‖² + Σ_limbs min_k s̄² (‖X_mid − M_k‖² + ‖X_end − E_k‖²) + hint`
//!
//! with π the estimate's camera (s̄ its mean scale, px per metre), `M_k`, `E_k` the middle and end
//! joints of limb candidate k (an exemplar among the solver's limb candidates and the
//! estimate's own start exemplars) hung from the reading's root joint with its bone directions
//! and the reading's bone lengths, and `hint` the depth hint's cost
//! ([`super::depth_hint::DepthHint::cost`], when the solve used one). The first term is the
//! same for every reading (a flip keeps the image); the second is how far, in pixels as if seen
//! side-on, the limb is from the nearest limb of training motion that explains the figure.
//! Each term after the first is a sum over limbs of a cost that depends on that limb's two flips
//! alone, so [`DepthCosts`] keeps 4 × 4 numbers and a flip re-scores every reading without the
//! dictionary.
//!
//! **Ranking.** [`PoseEstimate::alternatives`]`[0]` is always the estimate itself (nothing
//! flipped, its own score); the other readings follow by score, lowest first (ties: fewer flips,
//! then the limb order of [`Limb::ALL`]), at most [`MAX_ALTERNATIVES`] in all.

use nalgebra::{Matrix3, Vector3};

use super::pursuit::PoseEstimate;
use crate::camera::WeakPerspective;
use crate::skeleton::{joint, Joints3, BONES, NUM_JOINTS, PARENT};

/// Most alternatives of an estimate (the estimate itself included).
pub const MAX_ALTERNATIVES: usize = 8;

/// A limb bone lies in the picture plane, with no depth to flip, when its offset along the
/// camera's viewing direction is at most this fraction of its length (sin 2.9°; a flip would
/// turn it by at most 5.7°).
pub const NO_DEPTH_SIN: f64 = 0.05;

/// A limb bone whose depth can be flipped: upper arm, forearm, thigh or shin of either side.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Limb {
    /// Right shoulder → right elbow.
    RUpperArm,
    /// Right elbow → right wrist.
    RForearm,
    /// Left shoulder → left elbow.
    LUpperArm,
    /// Left elbow → left wrist.
    LForearm,
    /// Right hip → right knee.
    RThigh,
    /// Right knee → right ankle.
    RShin,
    /// Left hip → left knee.
    LThigh,
    /// Left knee → left ankle.
    LShin,
}

impl Limb {
    /// Every limb bone, in the order of [`crate::skeleton::LIMB_BONES`] (also the C API's index).
    pub const ALL: [Limb; 8] = [
        Limb::RUpperArm,
        Limb::RForearm,
        Limb::LUpperArm,
        Limb::LForearm,
        Limb::RThigh,
        Limb::RShin,
        Limb::LThigh,
        Limb::LShin,
    ];

    /// The name used in files and the C API: `r_upper_arm`, `r_forearm`, `l_upper_arm`,
    /// `l_forearm`, `r_thigh`, `r_shin`, `l_thigh`, `l_shin`.
    pub fn name(self) -> &'static str {
        match self {
            Limb::RUpperArm => "r_upper_arm",
            Limb::RForearm => "r_forearm",
            Limb::LUpperArm => "l_upper_arm",
            Limb::LForearm => "l_forearm",
            Limb::RThigh => "r_thigh",
            Limb::RShin => "r_shin",
            Limb::LThigh => "l_thigh",
            Limb::LShin => "l_shin",
        }
    }

    /// The limb of [`Limb::name`].
    pub fn parse(name: &str) -> Option<Limb> {
        Limb::ALL.into_iter().find(|l| l.name() == name)
    }

    /// Position in [`Limb::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The limb at `index` of [`Limb::ALL`].
    pub fn from_index(index: usize) -> Option<Limb> {
        Limb::ALL.get(index).copied()
    }

    /// The bone (index into [`BONES`]).
    pub fn bone(self) -> usize {
        crate::skeleton::LIMB_BONES[self.index()]
    }
}

/// The four limbs as (root, middle, end) joints, in [`Limb::ALL`] order by pairs (upper, lower).
const LIMBS: [(usize, usize, usize); 4] = [
    (joint::R_SHOULDER, joint::R_ELBOW, joint::R_WRIST),
    (joint::L_SHOULDER, joint::L_ELBOW, joint::L_WRIST),
    (joint::R_HIP, joint::R_KNEE, joint::R_ANKLE),
    (joint::L_HIP, joint::L_KNEE, joint::L_ANKLE),
];

/// One reading of an estimate: its joints, its score and what it flips.
#[derive(Clone, Debug, PartialEq)]
pub struct Alternative {
    /// The 15 joints, same frame and units as [`PoseEstimate::joints`].
    pub joints: Joints3,
    /// Score, px², lower = better (module doc).
    pub score: f64,
    /// The limbs whose depth is flipped relative to [`PoseEstimate::joints`], in [`Limb::ALL`] order.
    pub flipped: Vec<Limb>,
}

/// The scores of every reading of an estimate (module doc): `score(reading) = common +
/// Σ_limbs limb[l][state]`, with `state` bit 0 the limb's upper bone flipped and bit 1 its lower
/// bone, relative to the estimate; `f64::INFINITY` where a flipped bone has no depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthCosts {
    /// The part of the score no flip changes, px².
    pub common: f64,
    /// Per limb (right arm, left arm, right leg, left leg) and state, px².
    pub limb: [[f64; 4]; 4],
}

/// What [`flip_limb`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlipStatus {
    /// The limb's depth was flipped.
    Flipped,
    /// The limb lies in the picture plane ([`NO_DEPTH_SIN`]): nothing to flip, the estimate is
    /// returned unchanged.
    NoDepth,
}

/// The camera's viewing direction (toward the viewer) in the model frame.
fn view_dir(r: &Matrix3<f64>) -> Vector3<f64> {
    r.row(2).transpose()
}

fn v(x: &[f64; 3]) -> Vector3<f64> {
    Vector3::from(*x)
}

/// Whether `limb` of `joints` has depth to flip for a camera of rotation `r` ([`NO_DEPTH_SIN`]).
pub fn has_depth(joints: &Joints3, r: &Matrix3<f64>, limb: Limb) -> bool {
    let (p, c) = BONES[limb.bone()];
    let d = v(&joints[c]) - v(&joints[p]);
    view_dir(r).dot(&d).abs() > NO_DEPTH_SIN * d.norm()
}

/// Whether joint `j` hangs below joint `c` (or is `c`).
fn below(mut j: usize, c: usize) -> bool {
    loop {
        if j == c {
            return true;
        }
        match PARENT[j] {
            Some(p) => j = p,
            None => return false,
        }
    }
}

/// `joints` with `limb`'s depth flipped for a camera of rotation `r` (module doc; the image and
/// every bone length are kept), whether or not it has depth.
pub fn flip_joints(joints: &Joints3, r: &Matrix3<f64>, limb: Limb) -> Joints3 {
    let (p, c) = BONES[limb.bone()];
    let z = view_dir(r);
    let shift = -2.0 * z.dot(&(v(&joints[c]) - v(&joints[p]))) * z;
    let mut out = *joints;
    for (j, x) in out.iter_mut().enumerate() {
        if below(j, c) {
            *x = (v(x) + shift).into();
        }
    }
    out
}

/// `joints` with every limb of `mask` (bit i: [`Limb::ALL`]`[i]`) flipped.
fn apply_mask(joints: &Joints3, r: &Matrix3<f64>, mask: u8) -> Joints3 {
    let mut x = *joints;
    for (i, limb) in Limb::ALL.iter().enumerate() {
        if mask & (1 << i) != 0 {
            x = flip_joints(&x, r, *limb);
        }
    }
    x
}

/// The limbs of `mask`.
fn limbs_of(mask: u8) -> Vec<Limb> {
    Limb::ALL.iter().enumerate().filter(|(i, _)| mask & (1 << i) != 0).map(|(_, l)| *l).collect()
}

/// The depth costs of `joints` (model frame, seen by `cam`) for the module doc's score:
/// `reprojection` (Σ px² of the estimate), the limb candidates `candidates` (45-vectors of
/// exemplar poses) and the optional depth hint.
pub(crate) fn depth_costs(
    joints: &Joints3,
    cam: &WeakPerspective,
    reprojection: f64,
    candidates: &[&[f64]],
    hint: Option<&super::DepthHint>,
) -> DepthCosts {
    let s = 0.5 * (cam.sx + cam.sy);
    let z = view_dir(&cam.r);
    let x: [Vector3<f64>; NUM_JOINTS] = std::array::from_fn(|j| v(&joints[j]));
    // The hint's part for joint j at position y (relative to the pelvis, as DepthHint::cost).
    let hint_part = |j: usize, y: &Vector3<f64>| -> f64 {
        match hint {
            Some(h) if h.weight > 0.0 && h.known[joint::PELVIS] && h.known[j] => {
                let d = s * z.dot(&(y - x[joint::PELVIS]));
                h.weight * (d - (h.depth[j] - h.depth[joint::PELVIS])).powi(2)
            }
            _ => 0.0,
        }
    };
    let total_hint = super::depth_hint::hint_cost(hint, cam, &x);
    let mut limb = [[0.0; 4]; 4];
    let mut limb_hint0 = 0.0;
    for (li, &(a, b, c)) in LIMBS.iter().enumerate() {
        let (du, dl) = (x[b] - x[a], x[c] - x[b]);
        let (lu, ll) = (du.norm(), dl.norm());
        let (flat_u, flat_l) = (z.dot(&du).abs() <= NO_DEPTH_SIN * lu, z.dot(&dl).abs() <= NO_DEPTH_SIN * ll);
        let (su, sl) = (-2.0 * z.dot(&du) * z, -2.0 * z.dot(&dl) * z);
        // Unit bone directions of each candidate's limb.
        let dirs: Vec<(Vector3<f64>, Vector3<f64>)> = candidates
            .iter()
            .filter_map(|e| {
                let at = |j: usize| Vector3::new(e[3 * j], e[3 * j + 1], e[3 * j + 2]);
                Some(((at(b) - at(a)).try_normalize(1e-9)?, (at(c) - at(b)).try_normalize(1e-9)?))
            })
            .collect();
        for state in 0..4 {
            if (state & 1 != 0 && flat_u) || (state & 2 != 0 && flat_l) {
                limb[li][state] = f64::INFINITY;
                continue;
            }
            let mut mid = x[b];
            let mut end = x[c];
            if state & 1 != 0 {
                mid += su;
                end += su;
            }
            if state & 2 != 0 {
                end += sl;
            }
            let nearest = dirs
                .iter()
                .map(|(eu, el)| {
                    let m = x[a] + lu * eu;
                    let e = m + ll * el;
                    (mid - m).norm_squared() + (end - e).norm_squared()
                })
                .fold(f64::INFINITY, f64::min);
            let nearest = if nearest.is_finite() { s * s * nearest } else { 0.0 };
            let h = hint_part(b, &mid) + hint_part(c, &end);
            if state == 0 {
                limb_hint0 += h;
            }
            limb[li][state] = nearest + h;
        }
    }
    DepthCosts { common: reprojection + total_hint - limb_hint0, limb }
}

/// The state of limb `li` (0..4) in `mask`.
fn state_of(mask: u8, li: usize) -> usize {
    ((mask >> (2 * li)) & 3) as usize
}

/// Score of the reading `mask` (module doc).
fn score_of(c: &DepthCosts, mask: u8) -> f64 {
    c.common + (0..4).map(|li| c.limb[li][state_of(mask, li)]).sum::<f64>()
}

/// The ranked alternatives of `joints` with depth costs `c` (module doc, "Ranking").
pub fn rank(joints: &Joints3, r: &Matrix3<f64>, c: &DepthCosts) -> Vec<Alternative> {
    let mut readings: Vec<(f64, u8)> =
        (1..=255u8).map(|m| (score_of(c, m), m)).filter(|(s, _)| s.is_finite()).collect();
    readings.sort_by(|p, q| p.0.total_cmp(&q.0).then(p.1.count_ones().cmp(&q.1.count_ones())).then(p.1.cmp(&q.1)));
    let mut out = vec![Alternative { joints: *joints, score: score_of(c, 0), flipped: Vec::new() }];
    for &(score, mask) in readings.iter().take(MAX_ALTERNATIVES - 1) {
        out.push(Alternative { joints: apply_mask(joints, r, mask), score, flipped: limbs_of(mask) });
    }
    out
}

/// `est` with its depth costs `c` and its alternatives set.
pub(crate) fn with_alternatives(est: PoseEstimate, c: DepthCosts) -> PoseEstimate {
    let alternatives = rank(&est.joints, &est.camera.r, &c);
    PoseEstimate { alternatives, depth_costs: Some(c), ..est }
}

/// Flips the depth of `limb` of `est` and re-solves: under weak perspective the flip keeps every
/// 2-D joint and bone length, so the re-solve moves only the joints below the bone (reflected
/// along the viewing direction), keeps the camera, bases, weights, factors, RMS and
/// plausibility, redefines the base pose so that `joints` are still the factors applied to
/// base + Σ B w, and re-ranks the alternatives relative to the new answer (their scores are
/// those of the same readings). Microseconds. A limb lying in the picture plane
/// ([`NO_DEPTH_SIN`]) returns `est` unchanged with [`FlipStatus::NoDepth`]. Flipping the same
/// limb twice returns the original estimate (joints within rounding, the rest exactly).
pub fn flip_limb(est: &PoseEstimate, limb: Limb) -> (PoseEstimate, FlipStatus) {
    let r = est.camera.r;
    if !has_depth(&est.joints, &r, limb) {
        return (est.clone(), FlipStatus::NoDepth);
    }
    let x = flip_joints(&est.joints, &r, limb);
    let inverse = super::figure::BodyFactors { k: est.factors.k.map(|k| 1.0 / k) };
    let (old, new) = (inverse.apply(&est.joints), inverse.apply(&x));
    let base = std::array::from_fn(|j| std::array::from_fn(|a| est.base[j][a] + new[j][a] - old[j][a]));
    let depth_costs = est.depth_costs.map(|c| {
        // The flipped limb's states swap their bit: state s of the new answer is s ^ bit.
        let (li, bit) = (limb.index() / 2, 1 << (limb.index() % 2));
        let mut limb_costs = c.limb;
        limb_costs[li] = std::array::from_fn(|s| c.limb[li][s ^ bit]);
        DepthCosts { common: c.common, limb: limb_costs }
    });
    let alternatives = match &depth_costs {
        Some(c) => rank(&x, &r, c),
        None => Vec::new(),
    };
    (PoseEstimate { joints: x, base, alternatives, depth_costs, ..est.clone() }, FlipStatus::Flipped)
}

/// `est` re-answered with its alternative `index` (0 = itself): every limb of that alternative
/// flipped ([`flip_limb`] in [`Limb::ALL`] order). `None` when `index` is out of range.
pub fn pick_alternative(est: &PoseEstimate, index: usize) -> Option<PoseEstimate> {
    let alt = est.alternatives.get(index)?;
    let mut out = est.clone();
    for &l in &alt.flipped {
        out = flip_limb(&out, l).0;
    }
    Some(out)
}

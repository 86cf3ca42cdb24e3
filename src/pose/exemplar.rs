//! Nearest-neighbour starts ([`super::PoseOptions::starts`] and
//! [`super::PoseOptions::limb_candidates`]): start poses built from the dictionary's exemplars
//! (training poses) that best explain the 2-D joints, instead of the mean pose μ.
//!
//! 1. Every exemplar is scored with the best affine camera (2 × 3 matrix plus translation, a
//!    relaxation of eq. (1) with a closed form): with X the visible 3-D joints and W the
//!    centred visible 2-D joints, the residual is `‖W‖² − tr(Wᵀ X̄ (X̄ᵀX̄)⁻¹ X̄ᵀ W)` px² (X̄ = X
//!    centred) — [`affine_ranking`], best first, ties by index.
//! 2. The first max([`SHORTLIST_FACTOR`] × count, [`MIN_SHORTLIST`]) are refitted with the
//!    weak-perspective camera step ([`super::camera_fit::fit_camera`]) and ranked by that
//!    reprojection objective — [`nearest`].
//! 3. Optionally a start is recomposed limb by limb — [`compose`]: it keeps the torso (head,
//!    neck, pelvis, shoulders, hips) of the start's exemplar and takes each limb's shape (the
//!    offsets elbow − shoulder and wrist − elbow, or knee − hip and ankle − knee) from the one
//!    of the first `limb_candidates` exemplars of the affine ranking whose limb, hung from the
//!    torso and seen by the start's camera, lands nearest the visible 2-D joints. Restricting
//!    the candidates to exemplars that explain the whole figure keeps the limb depths
//!    plausible (every limb's 2-D projection also fits its depth mirror).

use std::sync::OnceLock;

use nalgebra::{DVector, Matrix3, Matrix3x2, SMatrix, Vector3};

use super::camera_fit::{fit_camera, CameraPrior};
use super::depth_hint::{hint_cost, DepthHint};
use super::problem::Problem;
use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::skeleton::NUM_JOINTS;

/// Shortlist size per requested start.
pub const SHORTLIST_FACTOR: usize = 4;
/// Smallest shortlist.
pub const MIN_SHORTLIST: usize = 16;
/// The four limbs (root, middle, end joint): right arm, left arm, right leg, left leg.
pub const LIMBS: [[usize; 3]; 4] = [[2, 3, 4], [5, 6, 7], [9, 10, 11], [12, 13, 14]];

/// A ranked start: exemplar column, its fitted camera and reprojection objective (px²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Start {
    /// Exemplar column of the dictionary.
    pub index: usize,
    /// Weak-perspective camera fitted to the exemplar (with the camera prior).
    pub camera: WeakPerspective,
    /// Σ squared reprojection error of the exemplar under `camera`, px².
    pub objective: f64,
}

/// Affine-camera residual of exemplar column `e` (45 values), px²; `None` when its visible
/// joints are degenerate. `w` are the centred 2-D joints of `vis` (Σ w = 0), `ww` = ‖w‖².
fn affine_residual(e: &[f64], vis: &[usize], w: &[[f64; 2]], ww: f64) -> Option<f64> {
    let (mut s, mut g, mut xw) = (Vector3::zeros(), Matrix3::zeros(), Matrix3x2::zeros());
    for (i, &p) in vis.iter().enumerate() {
        let x = Vector3::new(e[3 * p], e[3 * p + 1], e[3 * p + 2]);
        s += x;
        g += x * x.transpose();
        for a in 0..3 {
            xw[(a, 0)] += x[a] * w[i][0];
            xw[(a, 1)] += x[a] * w[i][1];
        }
    }
    // Centring X changes neither Xᵀw (Σ w = 0) nor needs a second pass for XᵀX.
    g -= s * s.transpose() / vis.len() as f64;
    let chol = g.cholesky()?;
    Some((ww - (xw.transpose() * chol.solve(&xw)).trace()).max(0.0))
}

/// An orthonormal basis Q (15 × 3, row-major per joint) of the centred exemplar's column
/// space with all joints visible: X̄ (X̄ᵀX̄)⁻¹ X̄ᵀ = Q Qᵀ, so the affine residual is
/// `‖W‖² − ‖QᵀW‖²`. `None` when the exemplar is degenerate.
type Frame = Option<[f64; 3 * NUM_JOINTS]>;

fn frame(e: &[f64]) -> Frame {
    let mut xt = SMatrix::<f64, 3, NUM_JOINTS>::zeros();
    for a in 0..3 {
        let m = (0..NUM_JOINTS).map(|p| e[3 * p + a]).sum::<f64>() / NUM_JOINTS as f64;
        for p in 0..NUM_JOINTS {
            xt[(a, p)] = e[3 * p + a] - m;
        }
    }
    let chol = (xt * xt.transpose()).cholesky()?;
    let qt = chol.l().solve_lower_triangular(&xt)?;
    Some(std::array::from_fn(|i| qt[(i % 3, i / 3)]))
}

/// Exemplars per block of [`Frames`].
const LANES: usize = 4;

/// The exemplar frames ([`frame`]) in blocks of [`LANES`] exemplars, coordinate-major within
/// a block (`q[i][l]`: coordinate i of the l-th exemplar), so that the ranking computes several
/// exemplars side by side; `usable[k]` is false for a degenerate exemplar (its entries are 0).
struct Frames {
    blocks: Vec<[[f64; LANES]; 3 * NUM_JOINTS]>,
    usable: Vec<bool>,
}

/// The dictionary's exemplar frames ([`Frames`]), computed on first use. A clone starts empty
/// (so a dictionary rebuilt from another with `..d.clone()` never sees stale frames) and
/// equality ignores it: it is derived from [`super::Dictionary::exemplars`] alone.
#[derive(Default)]
pub struct FrameCache(OnceLock<Frames>);

impl Clone for FrameCache {
    fn clone(&self) -> Self {
        FrameCache::default()
    }
}

impl PartialEq for FrameCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for FrameCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("FrameCache")
    }
}

fn frames<'a>(prob: &Problem<'a>) -> &'a Frames {
    let ex = &prob.dict.exemplars;
    prob.dict.frame_cache.0.get_or_init(|| {
        let n = ex.ncols();
        let mut blocks = vec![[[0.0; LANES]; 3 * NUM_JOINTS]; n.div_ceil(LANES)];
        let mut usable = vec![false; n];
        for (k, ok) in usable.iter_mut().enumerate() {
            if let Some(q) = frame(ex.column(k).as_slice()) {
                for (i, v) in q.iter().enumerate() {
                    blocks[k / LANES][i][k % LANES] = *v;
                }
                *ok = true;
            }
        }
        Frames { blocks, usable }
    })
}

/// An exemplar and its residual, ordered by residual, then index (the ranking's order).
#[derive(Clone, Copy, PartialEq)]
struct Ranked(f64, usize);

impl Eq for Ranked {}

impl PartialOrd for Ranked {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ranked {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

/// The `keep` best usable exemplars of `prob.dict` with their affine-camera residuals (px²),
/// best first (ties by index); all of them when `keep` is larger. Empty when the dictionary
/// has no exemplars.
pub fn affine_ranking(prob: &Problem, keep: usize) -> Vec<(usize, f64)> {
    let ex = &prob.dict.exemplars;
    let n = prob.vis.len() as f64;
    let cu = prob.vis.iter().map(|&p| prob.uv[p][0]).sum::<f64>() / n;
    let cv = prob.vis.iter().map(|&p| prob.uv[p][1]).sum::<f64>() / n;
    let w: Vec<[f64; 2]> = prob.vis.iter().map(|&p| [prob.uv[p][0] - cu, prob.uv[p][1] - cv]).collect();
    let ww: f64 = w.iter().map(|q| q[0] * q[0] + q[1] * q[1]).sum();
    // The `keep` best so far, the worst on top.
    let mut best = std::collections::BinaryHeap::with_capacity(keep.min(ex.ncols()) + 1);
    let mut offer = |r: Ranked| {
        if best.len() < keep {
            best.push(r);
        } else if let Some(mut worst) = best.peek_mut() {
            if r < *worst {
                *worst = r;
            }
        }
    };
    if prob.vis.len() == NUM_JOINTS {
        let f = frames(prob);
        for (b, q) in f.blocks.iter().enumerate() {
            // The six sums QᵀW of each exemplar, in joint order, for LANES exemplars at once.
            let (mut pu, mut pv) = ([[0.0; LANES]; 3], [[0.0; LANES]; 3]);
            for (qp, wp) in q.chunks_exact(3).zip(&w) {
                for a in 0..3 {
                    for l in 0..LANES {
                        pu[a][l] += qp[a][l] * wp[0];
                        pv[a][l] += qp[a][l] * wp[1];
                    }
                }
            }
            for l in 0..LANES {
                let k = b * LANES + l;
                if !f.usable.get(k).copied().unwrap_or(false) {
                    continue;
                }
                let mut proj = 0.0;
                for a in 0..3 {
                    proj += pu[a][l] * pu[a][l] + pv[a][l] * pv[a][l];
                }
                offer(Ranked((ww - proj).max(0.0), k));
            }
        }
    } else {
        for k in 0..ex.ncols() {
            if let Some(r) = affine_residual(ex.column(k).as_slice(), &prob.vis, &w, ww) {
                offer(Ranked(r, k));
            }
        }
    }
    best.into_sorted_vec().into_iter().map(|Ranked(r, k)| (k, r)).collect()
}

/// How many exemplars of the [`affine_ranking`] [`nearest`] refits for `count` starts.
pub fn shortlist_len(count: usize) -> usize {
    (SHORTLIST_FACTOR * count).max(MIN_SHORTLIST)
}

/// The `count` best starts from an [`affine_ranking`] (see the module doc, step 2), best first;
/// fewer when fewer exemplars admit a camera. Errors: `OutOfRange` when the ranking is empty
/// (no exemplars), `Degenerate` when no shortlisted exemplar admits a camera.
/// With a depth `hint`, its cost ([`DepthHint::cost`]) is added to each start's objective.
pub fn nearest(
    prob: &Problem,
    ranking: &[(usize, f64)],
    count: usize,
    prior: &CameraPrior,
    hint: Option<&DepthHint>,
) -> Result<Vec<Start>> {
    if ranking.is_empty() {
        return Err(Error::OutOfRange {
            name: "starts",
            detail: "the dictionary has no exemplars (rebuild it with --exemplar-spacing > 0)".into(),
        });
    }
    let ex = &prob.dict.exemplars;
    let mut starts: Vec<Start> = Vec::new();
    for &(k, _) in ranking.iter().take(shortlist_len(count)) {
        let e = ex.column(k);
        let x: [Vector3<f64>; NUM_JOINTS] = std::array::from_fn(|p| Vector3::new(e[3 * p], e[3 * p + 1], e[3 * p + 2]));
        if let Ok(camera) = fit_camera(&x, &prob.uv, &prob.vis, prior) {
            let objective = prob.objective(&camera, &x) + hint_cost(hint, &camera, &x);
            starts.push(Start { index: k, camera, objective });
        }
    }
    if starts.is_empty() {
        return Err(Error::Degenerate("no exemplar admits a camera for these joints".into()));
    }
    starts.sort_by(|a, b| a.objective.total_cmp(&b.objective).then(a.index.cmp(&b.index)));
    starts.truncate(count);
    Ok(starts)
}

/// Recomposes `start` limb by limb from `candidates` (exemplar columns; see the module doc,
/// step 3). Returns the 45-vector and the exemplar of each part: torso, then the limbs in
/// [`LIMBS`] order (a limb keeps the torso's exemplar when no candidate does better). With a
/// depth `hint`, a candidate limb's cost also holds the hint's cost of its two joints about the
/// limb's root ([`DepthHint::cost_about`]).
pub fn compose(
    prob: &Problem,
    start: &Start,
    candidates: &[usize],
    hint: Option<&DepthHint>,
) -> (DVector<f64>, [usize; 5]) {
    let ex = &prob.dict.exemplars;
    let mut out = ex.column(start.index).into_owned();
    let mut parts = [start.index; 5];
    for (li, limb) in LIMBS.iter().enumerate() {
        let at = |e: &[f64], j: usize| Vector3::new(e[3 * j], e[3 * j + 1], e[3 * j + 2]);
        let root = at(out.as_slice(), limb[0]);
        let cost = |k: usize| -> f64 {
            let e = ex.column(k);
            let mid = root + at(e.as_slice(), limb[1]) - at(e.as_slice(), limb[0]);
            let end = mid + at(e.as_slice(), limb[2]) - at(e.as_slice(), limb[1]);
            let ends = [(limb[1], mid), (limb[2], end)];
            let reprojection: f64 = ends
                .iter()
                .filter(|(j, _)| prob.vis.contains(j))
                .map(|(j, x)| {
                    let q = start.camera.project(x);
                    (q[0] - prob.uv[*j][0]).powi(2) + (q[1] - prob.uv[*j][1]).powi(2)
                })
                .sum();
            reprojection + hint.map_or(0.0, |h| h.cost_about(&start.camera, limb[0], &root, &ends))
        };
        let mut best = (cost(start.index), start.index);
        for &k in candidates {
            let f = cost(k);
            if f < best.0 {
                best = (f, k);
            }
        }
        parts[1 + li] = best.1;
        let e = ex.column(best.1);
        for a in 0..3 {
            let mid = out[3 * limb[0] + a] + e[3 * limb[1] + a] - e[3 * limb[0] + a];
            out[3 * limb[1] + a] = mid;
            out[3 * limb[2] + a] = mid + e[3 * limb[2] + a] - e[3 * limb[1] + a];
        }
    }
    (out, parts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::dictionary::{tests::synthetic_clips, Dictionary, LearnParams};
    use crate::skeleton::Joints2;
    use nalgebra::Rotation3;

    fn view(e: &[f64], cam: &WeakPerspective) -> Joints2 {
        let mut j = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
        for p in 0..NUM_JOINTS {
            j.xy[p] = cam.project(&Vector3::new(e[3 * p], e[3 * p + 1], e[3 * p + 2]));
        }
        j
    }

    const NO_PRIOR: CameraPrior =
        CameraPrior { alpha: 0.0, target: crate::pose::options::RotationTarget::Identity, equal_scales: false };

    #[test]
    fn finds_the_exemplar_a_view_was_made_from_and_composes_limbs() {
        let d = Dictionary::learn(
            &synthetic_clips(),
            &LearnParams { exemplar_spacing: 0.002, ..LearnParams::default() },
            "t".into(),
        )
        .unwrap();
        let r = *Rotation3::from_euler_angles(0.05, 0.4, 0.0).matrix();
        let cam = WeakPerspective { sx: 250.0, sy: 250.0, r, t: [200.0, 300.0] };
        let k = 7;
        let j = view(d.exemplars.column(k).as_slice(), &cam);
        let prob = Problem::new(&d, &j, 0.0).unwrap();
        let ranking = affine_ranking(&prob, usize::MAX);
        assert_eq!(ranking.len(), d.exemplars.ncols());
        assert!(ranking[0].1 < 1e-9, "{}", ranking[0].1);
        let s = nearest(&prob, &ranking, 3, &NO_PRIOR, None).unwrap();
        assert_eq!(s.len(), 3);
        assert!(s[0].objective < 1e-12, "{}", s[0].objective);
        assert!(s[1].objective >= s[0].objective && s[2].objective >= s[1].objective);
        // The best start reproduces the view, so composing keeps every limb of it.
        let (pose, parts) = compose(&prob, &s[0], &(0..d.exemplars.ncols()).collect::<Vec<_>>(), None);
        let x: [Vector3<f64>; NUM_JOINTS] =
            std::array::from_fn(|p| Vector3::new(pose[3 * p], pose[3 * p + 1], pose[3 * p + 2]));
        assert!(prob.objective(&s[0].camera, &x) < 1e-12);
        assert_eq!(parts[0], s[0].index);
        // A figure whose right arm comes from another exemplar: composition takes that arm.
        let (a, b) = (2, 40);
        let mut mixed = d.exemplars.column(a).into_owned();
        let eb = d.exemplars.column(b);
        for jn in [3, 4] {
            for ax in 0..3 {
                mixed[3 * jn + ax] = mixed[3 * 2 + ax] + eb[3 * jn + ax] - eb[3 * 2 + ax];
            }
        }
        let start = Start { index: a, camera: cam, objective: 0.0 };
        let prob = Problem::new(&d, &view(mixed.as_slice(), &cam), 0.0).unwrap();
        let (pose, parts) = compose(&prob, &start, &[b], None);
        assert_eq!(parts, [a, b, a, a, a]);
        assert!((pose - mixed).norm() < 1e-12);
        let empty = Dictionary { exemplars: nalgebra::DMatrix::zeros(45, 0), ..d.clone() };
        let prob = Problem::new(&empty, &j, 0.0).unwrap();
        assert!(matches!(
            nearest(&prob, &affine_ranking(&prob, usize::MAX), 1, &NO_PRIOR, None),
            Err(Error::OutOfRange { name: "starts", .. })
        ));
    }
}

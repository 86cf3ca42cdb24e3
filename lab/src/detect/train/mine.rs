//! Negative examples: random configurations (the first round) and hard negatives mined with the
//! current model through the engine (`tree::detect_level`: the highest-scoring configurations of
//! every pyramid level, back-tracked to part placements, whose φ gives exactly their score).

use std::hash::{Hash, Hasher};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use sketchbody::detect::hog::Planes;
use sketchbody::detect::model::Model;
use sketchbody::detect::pyramid::{build, Level};
use sketchbody::detect::tree::{detect_level, Candidate};
use sketchbody::error::Result;

use super::features::{Placement, SparseVec, Structure};
use super::layout::{NUM_PARTS, PARENT};

/// Which pyramid levels are searched for negatives: cells from `min_cell_px` to `max_cell_px`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchRange {
    /// Smallest cell, px.
    pub min_cell_px: f64,
    /// Largest cell, px.
    pub max_cell_px: f64,
}

/// The levels of `im` in `range` for `st`'s model geometry.
pub fn levels(im: &Planes, st: &Structure, range: SearchRange) -> Result<Vec<Level>> {
    let p = st.side.saturating_sub(2);
    Ok(build(im, st.sbin, st.interval, p, p, range.min_cell_px, range.max_cell_px)?.levels)
}

/// A mined negative: its features, its engine score and its identity.
#[derive(Clone, Debug)]
pub struct Mined {
    /// φ.
    pub x: SparseVec,
    /// The engine's score of the configuration.
    pub score: f64,
    /// Hash of (image, level, placement).
    pub key: u64,
}

fn key(image: usize, level: usize, p: &Placement) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (image, level, p).hash(&mut h);
    h.finish()
}

/// The placement (cells on the level's map) of a back-tracked candidate.
pub fn placement_of(c: &Candidate, pad: usize) -> Placement {
    c.parts
        .iter()
        .map(|b| {
            (
                ((b.x1 / c.cell_px).round() as i64 + pad as i64).max(0) as usize,
                ((b.y1 / c.cell_px).round() as i64 + pad as i64).max(0) as usize,
                b.mixture,
            )
        })
        .collect()
}

/// Hard negatives of one image: on every level, the best configurations scoring at least
/// `thresh` (at most `per_level`), then the best `per_image` of them.
pub fn mine_image(
    im: &Planes,
    image: usize,
    model: &Model,
    st: &Structure,
    range: SearchRange,
    thresh: f64,
    per_level: usize,
    per_image: usize,
) -> Result<Vec<Mined>> {
    let lv = levels(im, st, range)?;
    let pad = st.side.saturating_sub(2);
    let mut out: Vec<Mined> = lv
        .iter()
        .enumerate()
        .flat_map(|(li, l)| {
            detect_level(model, l, pad, pad, thresh, per_level, &|_| true).into_iter().map(move |c| {
                let p = placement_of(&c, pad);
                Mined { x: st.features(&l.feat, &p), score: c.score, key: key(image, li, &p) }
            })
        })
        .collect();
    out.sort_by(|a, b| b.score.total_cmp(&a.score).then(a.key.cmp(&b.key)));
    out.truncate(per_image);
    Ok(out)
}

/// Hard negatives of every image (in parallel, order-preserving).
pub fn mine(
    images: &[Planes],
    model: &Model,
    st: &Structure,
    range: SearchRange,
    thresh: f64,
    per_level: usize,
    per_image: usize,
) -> Result<Vec<Mined>> {
    let per: Vec<Vec<Mined>> = images
        .par_iter()
        .enumerate()
        .map(|(i, im)| mine_image(im, i, model, st, range, thresh, per_level, per_image))
        .collect::<Result<_>>()?;
    Ok(per.into_iter().flatten().collect())
}

/// `count` random configurations per image: a random level in range, root position and
/// mixtures, every part at its anchor, clamped to the map. Deterministic from `seed`.
pub fn random_negatives(
    images: &[Planes],
    st: &Structure,
    range: SearchRange,
    count: usize,
    seed: u64,
) -> Result<Vec<(SparseVec, u64)>> {
    let per: Vec<Vec<(SparseVec, u64)>> = images
        .par_iter()
        .enumerate()
        .map(|(i, im)| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            let lv = levels(im, st, range)?;
            let mut out = Vec::new();
            if lv.is_empty() {
                return Ok(out);
            }
            for _ in 0..count {
                let li = rng.random_range(0..lv.len());
                let f = &lv[li].feat;
                if f.cols < st.side || f.rows < st.side {
                    continue;
                }
                let (mx, my) = ((f.cols - st.side) as i64, (f.rows - st.side) as i64);
                let mut p: Placement = Vec::with_capacity(NUM_PARTS);
                p.push((
                    rng.random_range(0..=mx) as usize,
                    rng.random_range(0..=my) as usize,
                    rng.random_range(0..st.k),
                ));
                for i in 1..NUM_PARTS {
                    let (px, py, _) = p[PARENT[i].unwrap_or(0)];
                    let m = rng.random_range(0..st.k);
                    let a = st.anchors[i][m];
                    let x = (px as i64 + a[0] as i64 - 1).clamp(0, mx) as usize;
                    let y = (py as i64 + a[1] as i64 - 1).clamp(0, my) as usize;
                    p.push((x, y, m));
                }
                out.push((st.features(f, &p), key(i, li, &p)));
            }
            Ok(out)
        })
        .collect::<Result<_>>()?;
    Ok(per.into_iter().flatten().collect())
}

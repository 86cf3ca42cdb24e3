//! Tree dynamic programming over one pyramid level (Yang & Ramanan's `detect.m` / `passmsg`):
//! leaves to root, each child's per-mixture score is distance-transformed onto its parent's grid
//! (shifted by the anchor), the best child mixture is chosen per parent mixture with the
//! co-occurrence bias added, and the message is added to the parent's score. Root positions
//! scoring at least the threshold are back-tracked to part boxes.

use super::conv::{responses, responses_reference, ScoreMap};
use super::dt::{distance_transform, distance_transform_reference};
use super::dtwin::max_step;
use super::model::Model;
use super::pyramid::Level;
use rayon::prelude::*;

/// One part's placement in a detection, in input-image pixels (continuous coordinates: the
/// top-left corner of pixel (i, j) is (i, j)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PartBox {
    /// Left edge, px.
    pub x1: f64,
    /// Top edge, px.
    pub y1: f64,
    /// Right edge (exclusive), px.
    pub x2: f64,
    /// Bottom edge (exclusive), px.
    pub y2: f64,
    /// The part's mixture (0-based).
    pub mixture: usize,
    /// The part filter's response at this placement (appearance evidence, unitless).
    pub local: f32,
}

impl PartBox {
    /// Box centre (x, y), px.
    pub fn centre(&self) -> [f64; 2] {
        [0.5 * (self.x1 + self.x2), 0.5 * (self.y1 + self.y2)]
    }
}

/// A back-tracked detection candidate: total score and one box per part.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    /// Total score (filters + deformations + biases).
    pub score: f64,
    /// Cell size of its pyramid level, in input pixels.
    pub cell_px: f64,
    /// One box per model part, in model part order.
    pub parts: Vec<PartBox>,
}

impl Candidate {
    /// Bounding box (x1, y1, x2, y2) of all part boxes, px.
    pub fn bbox(&self) -> [f64; 4] {
        let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
        for p in &self.parts {
            b = [b[0].min(p.x1), b[1].min(p.y1), b[2].max(p.x2), b[3].max(p.y2)];
        }
        b
    }
}

/// Back-tracking data of one non-root part.
struct Trace {
    /// Per own mixture: child position (x, y) chosen for each parent-grid position.
    ix: Vec<Vec<u16>>,
    iy: Vec<Vec<u16>>,
    /// Per parent mixture: own mixture chosen for each parent-grid position.
    ik: Vec<Vec<u8>>,
    /// Parent grid width.
    pcols: usize,
}

/// Runs the DP on one level and returns the best candidates with score ≥ `thresh` that `accept`
/// admits, at most `max_candidates` of them, best first. Empty when a filter does not fit.
/// Uses the optimised kernels (matrix-product filter responses, fast distance transform).
pub fn detect_level(
    model: &Model,
    level: &Level,
    padx: usize,
    pady: usize,
    thresh: f64,
    max_candidates: usize,
    accept: &(dyn Fn(&Candidate) -> bool + Sync),
) -> Vec<Candidate> {
    detect_level_with(model, level, (padx, pady), thresh, max_candidates, accept, Kernels::Optimised)
}

/// Which kernels [`detect_level_with`] runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernels {
    /// Matrix-product filter responses and the fast distance transform (what [`detect_level`] uses).
    Optimised,
    /// The plain reference kernels ([`responses_reference`], [`distance_transform_reference`]):
    /// slower, for checking the optimised path.
    Reference,
}

/// [`detect_level`] with a choice of kernels; `pad` = (padx, pady).
pub fn detect_level_with(
    model: &Model,
    level: &Level,
    (padx, pady): (usize, usize),
    thresh: f64,
    max_candidates: usize,
    accept: &(dyn Fn(&Candidate) -> bool + Sync),
    kernels: Kernels,
) -> Vec<Candidate> {
    let reference = kernels == Kernels::Reference;
    let resp = if reference {
        responses_reference(&level.feat, &model.filters)
    } else {
        responses(&level.feat, &model.filters)
    };
    let dt = if reference { distance_transform_reference } else { distance_transform };
    let np = model.parts.len();
    // Per part, per mixture: score maps (start as the filter responses).
    let mut scores: Vec<Vec<ScoreMap>> = Vec::with_capacity(np);
    for p in &model.parts {
        let mut v = Vec::with_capacity(p.filter.len());
        for &f in &p.filter {
            match &resp[f] {
                Some(r) => v.push(r.clone()),
                None => return Vec::new(),
            }
        }
        scores.push(v);
    }
    let mut traces: Vec<Option<Trace>> = (0..np).map(|_| None).collect();
    for i in (1..np).rev() {
        let part = &model.parts[i];
        let Some(par) = part.parent else { continue };
        let (prows, pcols) = (scores[par][0].rows, scores[par][0].cols);
        let own = std::mem::take(&mut scores[i]);
        // The mixtures' transforms, and below the parent mixtures' maxima, are independent: they
        // run in parallel, so that the finest level (most of the work) keeps both threads busy.
        let dts: Vec<_> = own
            .par_iter()
            .zip(part.def.par_iter())
            .map(|(s, &d)| {
                let def = &model.defs[d];
                dt(s, def.w, def.anchor[0] as i64 - 1, def.anchor[1] as i64 - 1, prows, pcols)
            })
            .collect();
        let maxima: Vec<(Vec<f32>, Vec<u8>)> = part
            .bias
            .par_iter()
            .map(|brow| {
                let mut best = vec![f32::NEG_INFINITY; prows * pcols];
                let mut arg32 = vec![0i32; prows * pcols];
                for (m, t) in dts.iter().enumerate() {
                    // best = max(best, s + bias) as vector selects (s − (−b) is exactly s + b); the
                    // first mixture attaining the maximum wins.
                    max_step(&mut best, &mut arg32, &t.score.data, -(model.bias[brow[m]] as f32), m as i32);
                }
                (best, arg32.iter().map(|&m| m as u8).collect())
            })
            .collect();
        let mut ik = Vec::with_capacity(maxima.len());
        for (l, (best, arg)) in maxima.into_iter().enumerate() {
            for (ps, v) in scores[par][l].data.iter_mut().zip(&best) {
                *ps += v;
            }
            ik.push(arg);
        }
        let (ix, iy) = dts.into_iter().map(|t| (t.ix, t.iy)).unzip();
        traces[i] = Some(Trace { ix, iy, ik, pcols });
    }
    // Root: best mixture per position, with its bias.
    let root = &model.parts[0];
    let (rows, cols) = (scores[0][0].rows, scores[0][0].cols);
    let mut found: Vec<(f32, usize, u8)> = Vec::new();
    for pos in 0..rows * cols {
        let mut best = (f32::NEG_INFINITY, 0u8);
        for (l, s) in scores[0].iter().enumerate() {
            let b = model.bias[root.bias[0][if root.bias[0].len() == 1 { 0 } else { l }]] as f32;
            let v = s.data[pos] + b;
            if v > best.0 {
                best = (v, l as u8);
            }
        }
        if best.0 as f64 >= thresh {
            found.push((best.0, pos, best.1));
        }
    }
    found.sort_by(|a, b| b.0.total_cmp(&a.0));
    let s = level.cell_px;
    found
        .into_iter()
        .map(|(score, pos, l)| {
            // Positions (x, y, mixture) per part, parents first.
            let mut at = vec![(0usize, 0usize, 0usize); np];
            at[0] = (pos % cols, pos / cols, l as usize);
            for i in 1..np {
                let (Some(par), Some(t)) = (model.parts[i].parent, traces[i].as_ref()) else { continue };
                let (px, py, pl) = at[par];
                let q = py * t.pcols + px;
                let m = t.ik[pl][q] as usize;
                at[i] = (t.ix[m][q] as usize, t.iy[m][q] as usize, m);
            }
            let parts = at
                .iter()
                .zip(&model.parts)
                .map(|(&(x, y, m), p)| {
                    let f = &model.filters[p.filter[m]];
                    let x1 = (x as f64 - padx as f64) * s;
                    let y1 = (y as f64 - pady as f64) * s;
                    let local = resp[p.filter[m]].as_ref().map_or(0.0, |r| r.at(x, y));
                    PartBox { x1, y1, x2: x1 + f.cols as f64 * s, y2: y1 + f.rows as f64 * s, mixture: m, local }
                })
                .collect();
            Candidate { score: score as f64, cell_px: s, parts }
        })
        .filter(|c| accept(c))
        .take(max_candidates)
        .collect()
}

/// Greedy non-maximum suppression (the DPM code's `nms.m`): candidates sorted by score; one is
/// dropped when its bounding box overlaps a kept one by more than `overlap` of its own area.
pub fn nms(mut cands: Vec<Candidate>, overlap: f64, max_keep: usize) -> Vec<Candidate> {
    cands.sort_by(|a, b| b.score.total_cmp(&a.score));
    let mut kept: Vec<(Candidate, [f64; 4])> = Vec::new();
    for c in cands {
        if kept.len() >= max_keep {
            break;
        }
        let b = c.bbox();
        let area = (b[2] - b[0]).max(0.0) * (b[3] - b[1]).max(0.0);
        let suppressed = kept.iter().any(|(_, k)| {
            let w = (b[2].min(k[2]) - b[0].max(k[0])).max(0.0);
            let h = (b[3].min(k[3]) - b[1].max(k[1])).max(0.0);
            area <= 0.0 || w * h / area > overlap
        });
        if !suppressed {
            kept.push((c, b));
        }
    }
    kept.into_iter().map(|(c, _)| c).collect()
}

#[cfg(test)]
mod tests {
    use super::super::hog::FeatureMap;
    use super::super::model::{tests::tiny_model, FEAT_DIM};
    use super::*;

    /// Brute force over every placement of the two parts of the tiny model.
    #[test]
    fn dp_equals_exhaustive_search_and_backtrack_is_consistent() {
        let model = tiny_model();
        let (rows, cols) = (9, 10);
        let feat = FeatureMap {
            rows,
            cols,
            data: (0..rows * cols * FEAT_DIM).map(|i| ((i * 31 % 53) as f32 - 26.0) / 13.0).collect(),
        };
        let level = Level { feat: feat.clone(), cell_px: 4.0 };
        let c = detect_level(&model, &level, 0, 0, f64::NEG_INFINITY, 1, &|_| true);
        assert_eq!(c.len(), 1);
        let r: Vec<ScoreMap> = model.filters.iter().map(|f| super::super::conv::response(&feat, f).unwrap()).collect();
        let (rr, rc) = (r[0].rows, r[0].cols);
        let mut best = f64::NEG_INFINITY;
        for l in 0..2 {
            for y in 0..rr {
                for x in 0..rc {
                    for m in 0..2 {
                        let d = &model.defs[m];
                        for cy in 0..rr {
                            for cx in 0..rc {
                                let dx = (x as f64 + d.anchor[0] as f64 - 1.0) - cx as f64;
                                let dy = (y as f64 + d.anchor[1] as f64 - 1.0) - cy as f64;
                                let s = r[l].at(x, y) as f64
                                    + model.bias[0]
                                    + r[2 + m].at(cx, cy) as f64
                                    + model.bias[model.parts[1].bias[l][m]]
                                    - (d.w[0] * dx * dx + d.w[1] * dx + d.w[2] * dy * dy + d.w[3] * dy);
                                best = best.max(s);
                            }
                        }
                    }
                }
            }
        }
        assert!((c[0].score - best).abs() < 1e-3, "{} vs {best}", c[0].score);
        // Recompute the score from the back-tracked placement.
        let p0 = c[0].parts[0];
        let p1 = c[0].parts[1];
        let (x, y) = ((p0.x1 / 4.0) as usize, (p0.y1 / 4.0) as usize);
        let (cx, cy) = ((p1.x1 / 4.0) as usize, (p1.y1 / 4.0) as usize);
        let d = &model.defs[model.parts[1].def[p1.mixture]];
        let dx = (x as f64 + d.anchor[0] as f64 - 1.0) - cx as f64;
        let dy = (y as f64 + d.anchor[1] as f64 - 1.0) - cy as f64;
        let s = r[p0.mixture].at(x, y) as f64
            + model.bias[0]
            + r[2 + p1.mixture].at(cx, cy) as f64
            + model.bias[model.parts[1].bias[p0.mixture][p1.mixture]]
            - (d.w[0] * dx * dx + d.w[1] * dx + d.w[2] * dy * dy + d.w[3] * dy);
        assert!((s - best).abs() < 1e-3, "back-tracked score {s} vs {best}");
        assert_eq!(p1.local, r[2 + p1.mixture].at(cx, cy));
    }

    /// A seeded random model of the PARSE family's shape (5x5 filters, 6 mixtures, a chain and a
    /// branch), big enough for the matrix-product path.
    fn random_model(seed: u64) -> Model {
        use super::super::model::{Deformation, Filter, Part};
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let (np, k) = (4, 6);
        let filters = (0..np * k)
            .map(|_| Filter { rows: 5, cols: 5, w: (0..25 * FEAT_DIM).map(|_| rng.random_range(-0.3..0.3)).collect() })
            .collect();
        let defs = (0..np * k)
            .map(|_| Deformation {
                w: [
                    rng.random_range(0.01..0.1),
                    rng.random_range(-0.05..0.05),
                    rng.random_range(0.01..0.1),
                    rng.random_range(-0.05..0.05),
                ],
                anchor: [rng.random_range(-3..5), rng.random_range(-3..5)],
            })
            .collect();
        let bias: Vec<f64> = (0..1 + np * k * k).map(|_| rng.random_range(-0.5..0.5)).collect();
        let parents = [None, Some(0), Some(1), Some(0)];
        let parts = (0..np)
            .map(|i| Part {
                parent: parents[i],
                filter: (0..k).map(|m| i * k + m).collect(),
                def: if i == 0 { vec![] } else { (0..k).map(|m| i * k + m).collect() },
                bias: if i == 0 {
                    vec![vec![0]]
                } else {
                    (0..k).map(|l| (0..k).map(|m| 1 + (i * k + l) * k + m).collect()).collect()
                },
            })
            .collect();
        Model::new(4, 5, -1.0, filters, defs, bias, parts, [0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1]).unwrap()
    }

    /// End to end on a small image: every level of its pyramid gives the same candidates with the
    /// optimised kernels as with the reference ones (scores within 1e-4 relative, same boxes).
    #[test]
    fn optimised_kernels_give_the_reference_detections() {
        let model = random_model(3);
        let (w, h) = (120, 104);
        let data: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                let ring = ((x - 60.0).hypot(y - 40.0) - 18.0).abs() < 2.0;
                let bar = (x - 60.0).abs() < 2.0 && y > 58.0 && y < 100.0;
                if ring || bar {
                    20.0
                } else {
                    230.0 + ((i * 7919) % 13) as f32
                }
            })
            .collect();
        let im = super::super::hog::Planes { width: w, height: h, channels: 1, data };
        let (padx, pady) = model.padding();
        let pyr =
            super::super::pyramid::build(&im, model.sbin, model.interval, padx, pady, 0.0, f64::INFINITY).unwrap();
        assert!(pyr.levels.len() >= 8);
        let mut compared = 0;
        for level in &pyr.levels {
            let fast = detect_level(&model, level, padx, pady, f64::NEG_INFINITY, 5, &|_| true);
            let slow =
                detect_level_with(&model, level, (padx, pady), f64::NEG_INFINITY, 5, &|_| true, Kernels::Reference);
            assert_eq!(fast.len(), slow.len(), "level {}", level.cell_px);
            for (a, b) in fast.iter().zip(&slow) {
                assert!(
                    (a.score - b.score).abs() <= 1e-4 * b.score.abs().max(1.0),
                    "level {}: {} vs {}",
                    level.cell_px,
                    a.score,
                    b.score
                );
                for (p, q) in a.parts.iter().zip(&b.parts) {
                    assert_eq!((p.x1, p.y1, p.mixture), (q.x1, q.y1, q.mixture), "level {}", level.cell_px);
                }
                compared += 1;
            }
        }
        assert!(compared >= 20, "{compared} candidates compared");
    }

    #[test]
    fn nms_keeps_the_best_of_overlapping_candidates() {
        let mk = |score: f64, x: f64| Candidate {
            score,
            cell_px: 1.0,
            parts: vec![PartBox { x1: x, y1: 0.0, x2: x + 10.0, y2: 10.0, mixture: 0, local: 0.0 }],
        };
        let kept = nms(vec![mk(1.0, 0.0), mk(2.0, 1.0), mk(0.5, 50.0)], 0.3, 10);
        assert_eq!(kept.iter().map(|c| c.score).collect::<Vec<_>>(), vec![2.0, 0.5]);
        assert_eq!(nms(vec![mk(1.0, 0.0), mk(0.5, 50.0)], 0.3, 1).len(), 1);
    }
}

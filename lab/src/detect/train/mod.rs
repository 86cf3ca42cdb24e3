//! Training a flexible-mixture-of-parts detector on synthetic concept sketches (Yang & Ramanan's
//! method, written fresh): fully supervised positives from the sketch renderer with 26 part
//! boxes derived from the 15 joints ([`layout`]), mixture labels by k-means on each part's offset
//! from its parent ([`cluster`]), mirrored copies, negatives from pages without a figure
//! ([`examples`]), and a structured SVM over φ ([`features`]) solved by dual coordinate descent
//! with a cache ([`qp`]) over several rounds of hard-negative mining with the engine ([`mine`]).
//! Deterministic from [`TrainOptions::seed`] on any number of threads.

pub mod cluster;
pub mod examples;
pub mod features;
pub mod layout;
pub mod mine;
pub mod parse_positives;
pub mod qp;

use sketchbody::detect::model::Model;
use sketchbody::error::{Error, Result};
use sketchbody::render::sketch::{Hair, SketchRenderer};

use examples::{gray_planes, render_negatives, render_positives, Drawing, Geometry, Positive};
use features::{Structure, DEF_LOWER_BOUND};
use layout::{NUM_PARTS, PARENT};
use mine::SearchRange;
use parse_positives::{parse_positives, ParseSource};
use qp::{Example, Qp};

/// Training options. `Default` is the shipped run's geometry with small counts.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainOptions {
    /// Seed of every random choice (positives, negatives, clustering, solver order).
    pub seed: u64,
    /// Sketches rendered for positives (each also mirrored; held-out hair styles are skipped).
    pub positives: usize,
    /// Negative pages.
    pub negatives: usize,
    /// Mixtures per part (1..=8).
    pub mixtures: usize,
    /// Hard-negative mining rounds after the first (random-negative) solve.
    pub rounds: usize,
    /// Side of the rendered images, px (≥ 64).
    pub image_size: usize,
    /// Hair style never used in training (held out for evaluation); `None` uses all.
    pub held_out_hair: Option<Hair>,
    /// Fraction of the positives, in [0, 1], drawn as capsule mannequins around the same 2-D
    /// joints instead of the body's contours ([`crate::render::mannequin`]).
    pub mannequins: f64,
    /// Fraction of the positives, in [0, 1] with `mannequins + art_styles ≤ 1`, rendered in a
    /// random art style ([`sketchbody::render::sketch::art`]).
    pub art_styles: f64,
    /// PARSE training photos through the training filters as extra positives
    /// ([`parse_positives`]); `None` for none.
    pub parse: Option<ParseSource>,
    /// SVM C.
    pub c: f64,
    /// HOG cell, px.
    pub sbin: usize,
    /// Filter side, cells.
    pub filter_side: usize,
    /// Canonical standing-figure height, px.
    pub figure_px: f64,
    /// Pyramid levels per octave.
    pub interval: usize,
    /// Cell sizes searched when mining, px.
    pub search: SearchRange,
    /// Random configurations per negative page in the first round.
    pub random_per_image: usize,
    /// Hard negatives kept per page per round.
    pub mined_per_image: usize,
    /// Largest number of cached negatives.
    pub cache_negatives: usize,
    /// Coordinate-descent passes per solve (at most).
    pub max_passes: usize,
}

impl Default for TrainOptions {
    fn default() -> Self {
        TrainOptions {
            seed: 1,
            positives: 100,
            negatives: 50,
            mixtures: 4,
            rounds: 3,
            image_size: 512,
            held_out_hair: Some(Hair::Ponytail),
            mannequins: 0.0,
            art_styles: 0.0,
            parse: None,
            c: 0.01,
            sbin: 4,
            filter_side: 5,
            figure_px: 160.0,
            interval: 10,
            search: SearchRange { min_cell_px: 4.0, max_cell_px: 20.0 },
            random_per_image: 20,
            mined_per_image: 30,
            cache_negatives: 30_000,
            max_passes: 60,
        }
    }
}

impl TrainOptions {
    fn validate(&self) -> Result<()> {
        let bad = |name, detail: String| Err(Error::OutOfRange { name, detail });
        if self.positives == 0 || self.negatives == 0 {
            return bad("positives/negatives", format!("{} / {}: both must be ≥ 1", self.positives, self.negatives));
        }
        if !(1..=8).contains(&self.mixtures) {
            return bad("mixtures", format!("{} not in 1..=8", self.mixtures));
        }
        if !(64..=4096).contains(&self.image_size) {
            return bad("image_size", format!("{} not in 64..=4096", self.image_size));
        }
        if !(0.0..=1.0).contains(&self.mannequins) {
            return bad("mannequins", format!("{} not in [0, 1]", self.mannequins));
        }
        if !((0.0..=1.0).contains(&self.art_styles) && self.art_styles + self.mannequins <= 1.0) {
            return bad(
                "art_styles",
                format!("{} not in [0, 1 - mannequins] (mannequins {})", self.art_styles, self.mannequins),
            );
        }
        if !(1..=100_000).contains(&self.max_passes) {
            return bad("max_passes", format!("{} not in 1..=100000", self.max_passes));
        }
        if !(self.c.is_finite() && self.c > 0.0) {
            return bad("c", format!("{} must be finite and > 0", self.c));
        }
        let geometry_ok = self.figure_px >= 16.0
            && self.figure_px.is_finite()
            && self.sbin >= 2
            && self.sbin.is_multiple_of(2)
            && (3..=16).contains(&self.filter_side);
        if !geometry_ok {
            return bad(
                "geometry",
                format!("figure {} px, sbin {}, filter {}", self.figure_px, self.sbin, self.filter_side),
            );
        }
        if !(self.search.min_cell_px >= 0.0 && self.search.max_cell_px > self.search.min_cell_px) {
            return bad("search", format!("{:?}", self.search));
        }
        Ok(())
    }
}

/// The result of [`train`].
#[derive(Clone, Debug)]
pub struct Trained {
    /// The model (threshold: see [`train`]).
    pub model: Model,
    /// Its structure (for [`features::Structure::features`]).
    pub structure: Structure,
    /// Scores w·φ of the training positives.
    pub positive_scores: Vec<f64>,
    /// Mixture label of every part of every positive.
    pub labels: Vec<[usize; NUM_PARTS]>,
    /// Positives used (mirrors included) and sketches skipped (held-out style or too small).
    pub counts: (usize, usize),
}

/// Mixture labels per part and positive, and the anchors (1-based mean cell offset from the
/// parent per mixture). The root takes the labels of its child (part 1).
fn mixtures(pos: &[Positive], k: usize, seed: u64) -> (Vec<[usize; NUM_PARTS]>, Vec<Vec<[i32; 2]>>) {
    let mut labels = vec![[0usize; NUM_PARTS]; pos.len()];
    let mut anchors = vec![vec![[0i32; 2]; k]; NUM_PARTS];
    for i in 1..NUM_PARTS {
        let par = PARENT[i].unwrap_or(0);
        let off: Vec<[f64; 2]> =
            pos.iter().map(|p| [p.points[i][0] - p.points[par][0], p.points[i][1] - p.points[par][1]]).collect();
        let l = cluster::kmeans(&off, k, seed ^ (i as u64) << 8);
        for m in 0..k {
            let mut s = [0.0; 2];
            let mut n = 0usize;
            for (p, _) in pos.iter().zip(&l).filter(|(_, &lm)| lm == m) {
                s[0] += p.cells[i].0 as f64 - p.cells[par].0 as f64;
                s[1] += p.cells[i].1 as f64 - p.cells[par].1 as f64;
                n += 1;
            }
            let n = n.max(1) as f64;
            anchors[i][m] = [(s[0] / n).round() as i32 + 1, (s[1] / n).round() as i32 + 1];
        }
        for (lab, &m) in labels.iter_mut().zip(&l) {
            lab[i] = m;
        }
    }
    for lab in &mut labels {
        lab[0] = lab[1];
    }
    (labels, anchors)
}

/// Trains a model. `progress` receives one line per stage. The model's threshold is the lower
/// of −0.5 and the 2nd-percentile training-positive score. Errors: bad options
/// (`OutOfRange`), the renderer's, and `Degenerate` when no positive is usable.
pub fn train(renderer: &SketchRenderer, o: &TrainOptions, progress: &mut dyn FnMut(&str)) -> Result<Trained> {
    o.validate()?;
    let t0 = std::time::Instant::now();
    let el = || t0.elapsed().as_secs_f64();
    let geo = Geometry { sbin: o.sbin, side: o.filter_side, figure_px: o.figure_px };
    let drawing = Drawing { mannequins: o.mannequins, art: o.art_styles };
    let (mut pos, skipped) =
        render_positives(renderer, &geo, o.seed, o.positives, o.image_size, o.held_out_hair, drawing)?;
    if let Some(src) = &o.parse {
        let (extra, photos) = parse_positives(src, &geo, o.seed)?;
        progress(&format!(
            "[{:7.1} s] PARSE photos 1-{}: {photos} photos, {} positives (mirrors included)",
            el(),
            src.last,
            extra.len()
        ));
        pos.extend(extra);
    }
    if pos.is_empty() {
        return Err(Error::Degenerate("no usable training positive".into()));
    }
    progress(&format!(
        "[{:7.1} s] positives: {} examples (mirrors included), {skipped} sketches skipped",
        el(),
        pos.len()
    ));
    let (labels, anchors) = mixtures(&pos, o.mixtures, o.seed);
    let st = Structure { sbin: o.sbin, interval: o.interval, k: o.mixtures, side: o.filter_side, anchors };
    let mut qp = Qp::new(st.dim(), &st.bounded(), DEF_LOWER_BOUND, o.c);
    for (n, (p, lab)) in pos.iter().zip(&labels).enumerate() {
        let place: Vec<(usize, usize, usize)> = (0..NUM_PARTS).map(|i| (p.cells[i].0, p.cells[i].1, lab[i])).collect();
        qp.examples.push(Example::new(st.features(&p.feat, &place), 1.0, n as u64));
    }
    let pos_x: Vec<_> = qp.examples.iter().map(|e| e.x.clone()).collect();
    drop(pos);
    let neg_px = render_negatives(o.seed, o.negatives, o.image_size)?;
    let negs: Vec<_> = neg_px.iter().map(|px| gray_planes(px, o.image_size, o.image_size)).collect();
    drop(neg_px);
    let rand = mine::random_negatives(&negs, &st, o.search, o.random_per_image, o.seed)?;
    for (x, key) in rand {
        qp.examples.push(Example::new(x, -1.0, key | 1 << 63));
    }
    progress(&format!(
        "[{:7.1} s] {} negative pages, {} random negatives; dim {}",
        el(),
        negs.len(),
        qp.examples.len() - pos_x.len(),
        st.dim()
    ));
    let s = qp.solve(o.max_passes, 1e-3, o.seed);
    progress(&format!(
        "[{:7.1} s] round 0: {} passes, violation {:.2e}, objective {:.4}, {} support vectors",
        el(),
        s.passes,
        s.violation,
        s.primal,
        s.support
    ));
    for round in 1..=o.rounds {
        let model = st.to_model(&qp.w, -1.0)?;
        let mined = mine::mine(&negs, &model, &st, o.search, -1.0, 5, o.mined_per_image)?;
        let found = mined.len();
        let worst = mined.iter().map(|m| m.score).fold(f64::NEG_INFINITY, f64::max);
        let mut added = 0;
        for m in mined {
            if !qp.has_key(m.key) {
                qp.examples.push(Example::new(m.x, -1.0, m.key));
                added += 1;
            }
        }
        let s = qp.solve(o.max_passes, 1e-3, o.seed.wrapping_add(round as u64));
        qp.prune(0.5, o.cache_negatives);
        let ps: Vec<f64> = pos_x.iter().map(|x| x.dot(&qp.w)).collect();
        let below = ps.iter().filter(|&&v| v < 1.0).count();
        progress(&format!(
            "[{:7.1} s] round {round}: {found} hard negatives (best {worst:.3}), {added} new, cache {}; {} passes, violation {:.2e}, objective {:.4}, {} SV; positives under margin {below}/{}",
            el(),
            qp.examples.len(),
            s.passes,
            s.violation,
            s.primal,
            s.support,
            ps.len()
        ));
        if found == 0 {
            break;
        }
    }
    let w = st.effective(&qp.w);
    let mut positive_scores: Vec<f64> = pos_x.iter().map(|x| x.dot(&w)).collect();
    let mut sorted = positive_scores.clone();
    sorted.sort_by(f64::total_cmp);
    let p2 = sorted[(sorted.len() as f64 * 0.02) as usize];
    let model = st.to_model(&w, p2.min(-0.5))?;
    progress(&format!("[{:7.1} s] done: threshold {:.3}", el(), model.thresh));
    positive_scores.shrink_to_fit();
    Ok(Trained { model, structure: st, positive_scores, labels, counts: (pos_x.len(), skipped) })
}

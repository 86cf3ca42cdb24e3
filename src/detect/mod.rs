//! 2-D pose detection with a flexible mixture of parts (Yang & Ramanan; paper §II-A): HOG
//! feature pyramid ([`hog`], [`pyramid`]), part filter responses ([`conv`]), quadratic
//! deformations by the generalised distance transform ([`dt`]), tree dynamic programming with
//! mixture co-occurrence biases and back-tracking ([`tree`]), joints ([`joints`]), model I/O
//! ([`model`] for the PARSE JSON, [`format`] for the project's binary format);
//! its evaluation and training are in the `sketchbody-lab` crate.

pub mod calibration;
pub mod conv;
pub mod dt;
pub mod dtwin;
pub mod embedded;
pub mod facing;
pub mod figure;
pub mod fastconv;
pub mod format;
pub mod hog;
pub mod joints;
pub mod landmark;
pub mod model;
pub mod normalise;
pub mod pyramid;
pub mod tone;
pub mod tree;

use rayon::prelude::*;

pub use model::{Deformation, Filter, Model, Part, FEAT_DIM, NUM_PARSE_JOINTS, PARSE_JOINT_NAMES};
pub use tree::{Candidate, PartBox};

use crate::error::{Error, Result};
use crate::image::ImageView;
use crate::skeleton::{Joints2, NUM_JOINTS};
use hog::Planes;

/// Smallest accepted image side for detection, px (smaller images give [`Error::ImageTooSmall`]).
pub const MIN_DETECT_SIDE: usize = 32;
/// Default cap on the longer image side, px: larger images are downscaled (area averaging)
/// before detection and the joints mapped back to the input's pixels.
pub const DEFAULT_MAX_DETECT_SIDE: usize = 1024;

/// Which figure sizes [`detect`] searches (which pyramid levels it scores).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SearchScales {
    /// Every pyramid level: figures from about 5 cells (the ×2 octave) up to the image size; the
    /// PARSE protocol and photos with small people.
    All,
    /// Figures whose height is between `min` × the image's shorter side and `max` × its longer
    /// side (fractions, 0 < min < max). A figure F px tall is found at pyramid cells of about F /
    /// H px, H = [`Model::rest_height_cells`]; the deformations let a figure span 0.75 H to
    /// 1.25 H cells, so levels with cells in [min · short / (1.25 H), max · long / (0.75 H)] are
    /// scored.
    FigureFraction {
        /// Smallest figure height as a fraction of the shorter image side.
        min: f64,
        /// Largest figure height as a fraction of the longer image side.
        max: f64,
    },
}

/// The smallest figure the sketch default searches, as a fraction of the shorter image side.
/// Concept sketches draw one figure large on the page (the renderer's figures are 0.72–0.92 of
/// the shorter side tall; docs/benchmarks-history.md, "Detector (issue 7)"). Smaller figures need
/// [`SearchScales::FigureFraction`] with a smaller `min` or [`SearchScales::All`].
pub const SKETCH_MIN_FIGURE: f64 = 0.5;

/// The documented default search range for concept sketches: one figure filling much of the
/// canvas, at least [`SKETCH_MIN_FIGURE`] of the shorter side tall and at most the longer side.
pub const SKETCH_SEARCH: SearchScales = SearchScales::FigureFraction { min: SKETCH_MIN_FIGURE, max: 1.0 };

impl SearchScales {
    /// Pyramid cell range (px of the image searched, `width` x `height`) for `model`.
    pub fn cell_range(&self, model: &Model, width: usize, height: usize) -> (f64, f64) {
        match *self {
            SearchScales::All => (0.0, f64::INFINITY),
            SearchScales::FigureFraction { min, max } => {
                let h = model.rest_height_cells();
                let (short, long) = (width.min(height) as f64, width.max(height) as f64);
                (min * short / (1.25 * h), max * long / (0.75 * h))
            }
        }
    }
}

/// Detection options. `Default` gives the model's threshold, the sketch search range
/// [`SKETCH_SEARCH`] at [`SKETCH_LEVELS_PER_OCTAVE`] levels per octave, NMS at 0.3 and up to 10
/// detections.
#[derive(Clone, Debug, PartialEq)]
pub struct DetectOptions {
    /// Score threshold; `None` uses the model's own.
    pub threshold: Option<f64>,
    /// Longer-side cap in px (≥ [`MIN_DETECT_SIDE`]); larger inputs are downscaled first.
    pub max_side: usize,
    /// Smallest pyramid cell, in (possibly downscaled) image px: finer levels (which find small
    /// figures) are skipped. 0 searches all levels; `sbin` skips the ×2 octave.
    pub min_cell_px: f64,
    /// Largest figure searched, as the longest cell side in px: coarser levels are skipped.
    pub max_cell_px: f64,
    /// NMS overlap (fraction of the weaker box's area) above which a detection is suppressed.
    pub nms_overlap: f64,
    /// Most detections returned (≥ 1).
    pub max_detections: usize,
    /// Figure sizes searched; combined with `min_cell_px` / `max_cell_px` (a level is scored
    /// when it passes both).
    pub search: SearchScales,
    /// Pyramid levels per octave (scale step 2^(−1/n)); `None` uses the model's own
    /// (`Model::interval`, 10 for the PARSE family). Fewer levels are proportionally faster and
    /// coarser in scale; 5 gives every other level of 10 exactly. Range 1..=100. Default
    /// [`SKETCH_LEVELS_PER_OCTAVE`].
    pub levels_per_octave: Option<usize>,
    /// Ink-box normalisation: when the square around the drawing's ink (its longer side at 0.8
    /// of the square) is larger than this many px, that square is cropped and downscaled to it
    /// before the search, so a large scan is seen at the size the model was trained on
    /// ([`normalise::normalise`]). `None` searches the whole image (downscaled to `max_side`), as
    /// does [`SearchScales::All`] (photos with small people keep their resolution).
    /// Default [`DEFAULT_NORMALISE_SIDE`]; at least [`MIN_DETECT_SIDE`]; capped by `max_side`.
    pub normalise: Option<usize>,
}

/// The default working side of ink-box normalisation, px: the training sketches' canvas.
pub const DEFAULT_NORMALISE_SIDE: usize = 512;

/// The documented default levels per octave for concept sketches ([`DetectOptions::default`]):
/// 7 instead of the models' 10, 0.7 of the levels and of the work at the same held-out PCK
/// (docs/benchmarks-history.md, "Detector (issue 7)").
pub const SKETCH_LEVELS_PER_OCTAVE: usize = 7;

impl Default for DetectOptions {
    fn default() -> Self {
        Self {
            threshold: None,
            max_side: DEFAULT_MAX_DETECT_SIDE,
            min_cell_px: 0.0,
            max_cell_px: f64::INFINITY,
            nms_overlap: 0.3,
            max_detections: 10,
            search: SKETCH_SEARCH,
            levels_per_octave: Some(SKETCH_LEVELS_PER_OCTAVE),
            normalise: Some(DEFAULT_NORMALISE_SIDE),
        }
    }
}

impl DetectOptions {
    fn validate(&self) -> Result<()> {
        if let Some(t) = self.threshold {
            crate::error::ensure_finite("threshold", t)?;
        }
        let range = |name, detail: String| Err(Error::OutOfRange { name, detail });
        if self.max_side < MIN_DETECT_SIDE {
            return range("max_side", format!("{} < {MIN_DETECT_SIDE}", self.max_side));
        }
        if !(self.min_cell_px >= 0.0) || self.min_cell_px.is_infinite() {
            return range("min_cell_px", format!("{} must be finite and ≥ 0", self.min_cell_px));
        }
        if !(self.max_cell_px > self.min_cell_px) {
            return range("max_cell_px", format!("{} must exceed min_cell_px {}", self.max_cell_px, self.min_cell_px));
        }
        if !(0.0..=1.0).contains(&self.nms_overlap) {
            return range("nms_overlap", format!("{} not in [0, 1]", self.nms_overlap));
        }
        if self.max_detections == 0 {
            return range("max_detections", "must be ≥ 1".into());
        }
        if let Some(n) = self.levels_per_octave {
            if !(1..=100).contains(&n) {
                return range("levels_per_octave", format!("{n} not in 1..=100"));
            }
        }
        if let Some(n) = self.normalise {
            if n < MIN_DETECT_SIDE {
                return range("normalise", format!("{n} < {MIN_DETECT_SIDE}"));
            }
        }
        if let SearchScales::FigureFraction { min, max } = self.search {
            if !(min > 0.0 && min < max && max.is_finite()) {
                return range("search", format!("figure fractions {min}..{max}: need 0 < min < max, finite"));
            }
        }
        Ok(())
    }
}

/// One detected figure, in input-image pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct Detection {
    /// Total model score (higher is more confident; compare with the threshold).
    pub score: f64,
    /// The canonical 15 joints (all marked visible), px.
    pub joints: Joints2,
    /// Per canonical joint confidence in (0, 1) (logistic of the part's filter response).
    pub confidence: [f64; NUM_JOINTS],
    /// The 14 PARSE joints (data-set order, [`PARSE_JOINT_NAMES`]), px.
    pub parse_joints: [[f64; 2]; NUM_PARSE_JOINTS],
    /// One box per model part, px.
    pub parts: Vec<PartBox>,
    /// Bounding box of the part boxes (x1, y1, x2, y2), px.
    pub bbox: [f64; 4],
    /// Cell size of the pyramid level it was found at, input px (the figure is about
    /// `Model::rest_height_cells` of these tall).
    pub cell_px: f64,
}

/// The result of [`detect`]: the best figure first, then the others after NMS, by score.
#[derive(Clone, Debug, PartialEq)]
pub struct Detections {
    /// Detections, best first (never empty).
    pub all: Vec<Detection>,
}

impl Detections {
    /// The best-scoring figure.
    pub fn best(&self) -> &Detection {
        &self.all[0]
    }
}

/// Planes of `image`, downscaled so that its longer side is at most `max_side`; returns the
/// factor from working pixels to input pixels. Errors: [`Error::ImageTooSmall`].
pub fn prepare_image(image: &ImageView<'_>, max_side: usize) -> Result<(Planes, f64)> {
    let (w, h) = (image.width(), image.height());
    if w.min(h) < MIN_DETECT_SIDE {
        return Err(Error::ImageTooSmall { width: w, height: h, min: MIN_DETECT_SIDE });
    }
    let planes = pyramid::planes_from_view(image);
    let long = w.max(h);
    if long <= max_side {
        return Ok((planes, 1.0));
    }
    let f = max_side as f64 / long as f64;
    let small = pyramid::resize(&planes, f);
    if small.width.min(small.height) < MIN_DETECT_SIDE {
        return Err(Error::ImageTooSmall { width: w, height: h, min: MIN_DETECT_SIDE });
    }
    Ok((small, long as f64 / max_side as f64))
}

/// Candidates scoring at least `thresh` on `im` (working pixels) that `accept` admits, at most
/// `per_level` per pyramid level, best first, over a pyramid of `interval` levels per octave;
/// levels with cells outside [min_cell_px, max_cell_px] are neither built nor scored. Errors:
/// the pyramid's ([`pyramid::build`]).
#[allow(clippy::too_many_arguments)]
pub fn candidates(
    im: &Planes,
    model: &Model,
    interval: usize,
    thresh: f64,
    min_cell_px: f64,
    max_cell_px: f64,
    per_level: usize,
    accept: &(dyn Fn(&Candidate) -> bool + Sync),
) -> Result<Vec<Candidate>> {
    let search = Search { interval, min_cell_px, max_cell_px, per_level };
    candidates_with_progress(im, model, thresh, &search, accept, &mut |_| true)
}

/// Which pyramid levels [`candidates_with_progress`] scores and how many candidates it keeps.
#[derive(Clone, Copy, Debug)]
pub struct Search {
    /// Pyramid levels per octave.
    pub interval: usize,
    /// Smallest cell scored, working px.
    pub min_cell_px: f64,
    /// Largest cell scored, working px.
    pub max_cell_px: f64,
    /// Most candidates kept per level.
    pub per_level: usize,
}

/// [`candidates`] reporting progress: `progress(fraction)` (0..=1, non-decreasing) is called on
/// the calling thread after the pyramid is built and after each group of levels (as many as
/// rayon has threads) is scored; returning `false` stops with [`Error::Cancelled`] there.
pub fn candidates_with_progress(
    im: &Planes,
    model: &Model,
    thresh: f64,
    search: &Search,
    accept: &(dyn Fn(&Candidate) -> bool + Sync),
    progress: &mut dyn FnMut(f32) -> bool,
) -> Result<Vec<Candidate>> {
    let (padx, pady) = model.padding();
    let pyr = pyramid::build(im, model.sbin, search.interval, padx, pady, search.min_cell_px, search.max_cell_px)?;
    // The pyramid is about a tenth of the work; the levels' scoring the rest.
    let share = |done: usize| 0.1 + 0.9 * done as f32 / pyr.levels.len().max(1) as f32;
    if !progress(share(0)) {
        return Err(Error::Cancelled);
    }
    let mut all: Vec<Candidate> = Vec::new();
    let group = rayon::current_num_threads().max(1);
    for (g, levels) in pyr.levels.chunks(group).enumerate() {
        let found: Vec<Candidate> = levels
            .par_iter()
            .flat_map_iter(|l| tree::detect_level(model, l, padx, pady, thresh, search.per_level, accept))
            .collect();
        all.extend(found);
        if !progress(share((g * group + levels.len()).min(pyr.levels.len()))) {
            return Err(Error::Cancelled);
        }
    }
    all.sort_by(|a, b| b.score.total_cmp(&a.score));
    Ok(all)
}

/// Converts a candidate (working pixels) to a detection in input pixels (`scale` = input px per
/// working px).
pub fn to_detection(c: &Candidate, model: &Model, scale: f64) -> Detection {
    let parts: Vec<PartBox> = c
        .parts
        .iter()
        .map(|p| PartBox { x1: p.x1 * scale, y1: p.y1 * scale, x2: p.x2 * scale, y2: p.y2 * scale, ..*p })
        .collect();
    let scaled = Candidate { score: c.score, cell_px: c.cell_px * scale, parts };
    let (pxy, pconf) = joints::parse_joints(&scaled, &model.part_to_joint);
    let (j2, conf) = joints::parse_to_canonical(&pxy, &pconf);
    Detection {
        score: c.score,
        joints: j2,
        confidence: conf,
        parse_joints: pxy,
        bbox: scaled.bbox(),
        cell_px: scaled.cell_px,
        parts: scaled.parts,
    }
}

/// Detects human figures in `image` (1, 3 or 4 channels; colour is used by the HOG) at the
/// scales `options.search` names. Returns the best figure and the other non-overlapping ones
/// scoring above the threshold. When no pyramid level lies in the searched range the result is
/// [`Error::NoFigure`] with score −∞.
/// Errors: [`Error::ImageTooSmall`] (side < [`MIN_DETECT_SIDE`]), [`Error::OutOfRange`] /
/// [`Error::NonFinite`] for bad options or a search beyond [`pyramid::MAX_PYRAMID_BYTES`],
/// [`Error::NonFinite`] when a score or a joint is not finite (never reported as a detection),
/// [`Error::NoFigure`] (with the best score found) when nothing reaches the threshold.
pub fn detect(image: &ImageView<'_>, model: &Model, options: &DetectOptions) -> Result<Detections> {
    detect_with_progress(image, model, options, &mut |_| true)
}

/// [`detect`] reporting progress: `progress(fraction)` (0..=1, non-decreasing) is called on the
/// calling thread between steps (see [`candidates_with_progress`]); returning `false` stops with
/// [`Error::Cancelled`] within one group of pyramid levels.
pub fn detect_with_progress(
    image: &ImageView<'_>,
    model: &Model,
    options: &DetectOptions,
    progress: &mut dyn FnMut(f32) -> bool,
) -> Result<Detections> {
    options.validate()?;
    let normalise_side = if options.search == SearchScales::All { None } else { options.normalise };
    let (planes, scale, offset) =
        match normalise_side.and_then(|n| normalise::normalise(image, n.min(options.max_side))) {
            Some(n) => (n.planes, n.scale, n.offset),
            None => {
                let (planes, scale) = prepare_image(image, options.max_side)?;
                (planes, scale, [0.0, 0.0])
            }
        };
    let thresh = options.threshold.unwrap_or(model.thresh);
    let (lo, hi) = options.search.cell_range(model, planes.width, planes.height);
    let (min_cell_px, max_cell_px) = (lo.max(options.min_cell_px), hi.min(options.max_cell_px));
    let interval = options.levels_per_octave.unwrap_or(model.interval);
    let search = Search { interval, min_cell_px, max_cell_px, per_level: 64 };
    let cands = candidates_with_progress(&planes, model, f64::NEG_INFINITY, &search, &|_| true, progress)?;
    let best_score = cands.first().map_or(f64::NEG_INFINITY, |c| c.score);
    let above: Vec<Candidate> = cands.into_iter().filter(|c| c.score >= thresh).collect();
    if above.is_empty() {
        return Err(Error::NoFigure { score: best_score, threshold: thresh });
    }
    let kept = tree::nms(above, options.nms_overlap, options.max_detections);
    let all: Vec<Detection> = kept.iter().map(|c| shifted(to_detection(c, model, scale), offset)).collect();
    for d in &all {
        crate::error::ensure_finite("detection score", d.score)?;
        for v in d.joints.xy.iter().flatten().chain(d.confidence.iter()) {
            crate::error::ensure_finite("detected joint", *v)?;
        }
    }
    Ok(Detections { all })
}

/// `d` moved by `offset` (input px): from a normalised crop's frame to the input image's.
fn shifted(mut d: Detection, [dx, dy]: [f64; 2]) -> Detection {
    if dx == 0.0 && dy == 0.0 {
        return d;
    }
    for p in d.joints.xy.iter_mut().chain(d.parse_joints.iter_mut()) {
        p[0] += dx;
        p[1] += dy;
    }
    for b in &mut d.parts {
        (b.x1, b.x2, b.y1, b.y2) = (b.x1 + dx, b.x2 + dx, b.y1 + dy, b.y2 + dy);
    }
    d.bbox = [d.bbox[0] + dx, d.bbox[1] + dy, d.bbox[2] + dx, d.bbox[3] + dy];
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiny_images_and_bad_options_are_rejected() {
        let m = model::tests::tiny_model();
        let data = vec![0u8; 31 * 100];
        let v = ImageView::gray(&data, 100, 31).unwrap();
        assert!(matches!(
            detect(&v, &m, &DetectOptions::default()),
            Err(Error::ImageTooSmall { width: 100, height: 31, .. })
        ));
        let data = vec![0u8; 64 * 64];
        let v = ImageView::gray(&data, 64, 64).unwrap();
        let o = DetectOptions { nms_overlap: 2.0, ..Default::default() };
        assert!(matches!(detect(&v, &m, &o), Err(Error::OutOfRange { name: "nms_overlap", .. })));
        let o = DetectOptions { threshold: Some(f64::NAN), ..Default::default() };
        assert!(matches!(detect(&v, &m, &o), Err(Error::NonFinite { .. })));
    }

    /// Issue 52 finding 10: detection reports progress on the calling thread, non-decreasing
    /// to 1, gives what `detect` gives, and stops with `Cancelled` at the first `false` (at
    /// every progress point) without calling again.
    #[test]
    fn detection_reports_progress_and_can_be_cancelled() {
        let m = model::tests::tiny_model();
        let data: Vec<u8> = (0..96 * 80).map(|i| if (i % 96) / 8 % 3 == 0 { 30 } else { 220 }).collect();
        let v = ImageView::gray(&data, 96, 80).unwrap();
        let o = DetectOptions { threshold: Some(-1e6), search: SearchScales::All, ..Default::default() };
        let mut seen = Vec::new();
        let whole = detect_with_progress(&v, &m, &o, &mut |f| {
            seen.push(f);
            true
        })
        .unwrap();
        assert_eq!(whole, detect(&v, &m, &o).unwrap());
        assert!(seen.len() >= 2, "{seen:?}");
        assert!(seen.windows(2).all(|w| w[0] <= w[1]) && (seen[seen.len() - 1] - 1.0).abs() < 1e-6, "{seen:?}");
        for stop_at in 0..seen.len() {
            let mut calls = 0;
            let r = detect_with_progress(&v, &m, &o, &mut |_| {
                calls += 1;
                calls <= stop_at
            });
            assert!(matches!(r, Err(Error::Cancelled)), "stop at {stop_at}: {r:?}");
            assert_eq!(calls, stop_at + 1, "called after it asked to stop");
        }
    }

    #[test]
    fn search_scales_select_the_documented_cell_range() {
        let m = model::tests::tiny_model(); // rest height 4 cells
        let (lo, hi) = SKETCH_SEARCH.cell_range(&m, 200, 100);
        assert_eq!(SKETCH_SEARCH, SearchScales::FigureFraction { min: 0.5, max: 1.0 });
        assert!((lo - 0.5 * 100.0 / 5.0).abs() < 1e-12, "{lo}");
        assert!((hi - 200.0 / 3.0).abs() < 1e-12, "{hi}");
        assert_eq!(SearchScales::All.cell_range(&m, 200, 100), (0.0, f64::INFINITY));
        let data = vec![0u8; 64 * 64];
        let v = ImageView::gray(&data, 64, 64).unwrap();
        for (min, max) in [(0.0, 1.0), (0.5, 0.5), (0.2, f64::INFINITY), (f64::NAN, 1.0)] {
            let o = DetectOptions { search: SearchScales::FigureFraction { min, max }, ..Default::default() };
            assert!(matches!(detect(&v, &m, &o), Err(Error::OutOfRange { name: "search", .. })), "{min}..{max}");
        }
        // A range holding no pyramid level finds nothing, with score −∞.
        let o = DetectOptions {
            search: SearchScales::FigureFraction { min: 50.0, max: 60.0 },
            threshold: Some(-1e6),
            ..Default::default()
        };
        assert!(matches!(detect(&v, &m, &o), Err(Error::NoFigure { score, .. }) if score == f64::NEG_INFINITY));
    }

    /// The sketch range scores a subset of the levels: its best detection is the best of
    /// exactly those levels of the full search.
    #[test]
    fn sketch_range_equals_the_full_search_restricted_to_its_levels() {
        let m = model::tests::tiny_model();
        let data: Vec<u8> = (0..96 * 80).map(|i| if (i % 96) / 8 % 3 == 0 { 30 } else { 220 }).collect();
        let v = ImageView::gray(&data, 96, 80).unwrap();
        let o = DetectOptions { threshold: Some(-1e6), ..Default::default() };
        let sketch = detect(&v, &m, &o).unwrap();
        let (lo, hi) = SKETCH_SEARCH.cell_range(&m, 96, 80);
        let (planes, _) = prepare_image(&v, o.max_side).unwrap();
        let all =
            candidates(&planes, &m, SKETCH_LEVELS_PER_OCTAVE, f64::NEG_INFINITY, 0.0, f64::INFINITY, 64, &|_| true)
                .unwrap();
        let best_in = all.iter().find(|c| c.cell_px >= lo && c.cell_px <= hi).unwrap();
        assert_eq!(sketch.best().score, best_in.score);
        assert!(all.iter().any(|c| c.cell_px < lo), "the full search has finer levels");
    }

    /// Five levels per octave score exactly every other level of ten: the same best candidate
    /// per level, and the overall best is the best of those levels.
    #[test]
    fn five_levels_per_octave_are_every_other_level_of_ten() {
        let m = model::tests::tiny_model();
        let data: Vec<u8> =
            (0..120 * 96).map(|i| if (i % 120) / 6 % 4 == 0 || (i / 120) / 9 % 5 == 0 { 20 } else { 230 }).collect();
        let v = ImageView::gray(&data, 120, 96).unwrap();
        let (planes, _) = prepare_image(&v, DEFAULT_MAX_DETECT_SIDE).unwrap();
        let ten = candidates(&planes, &m, 10, f64::NEG_INFINITY, 0.0, f64::INFINITY, 1, &|_| true).unwrap();
        let five = candidates(&planes, &m, 5, f64::NEG_INFINITY, 0.0, f64::INFINITY, 1, &|_| true).unwrap();
        assert!(five.len() >= 10 && ten.len() >= 2 * five.len() - 1, "{} vs {}", five.len(), ten.len());
        let mut cells: Vec<f64> = ten.iter().map(|c| c.cell_px).collect();
        cells.sort_by(f64::total_cmp);
        for c in &five {
            let k = cells.iter().position(|&x| (x - c.cell_px).abs() < 1e-9).expect("a level of ten");
            assert_eq!(k % 2, 0, "cell {} is level {k} of ten", c.cell_px);
            let t = ten.iter().find(|t| (t.cell_px - c.cell_px).abs() < 1e-9).unwrap();
            assert_eq!(t.score, c.score);
            for (p, q) in t.parts.iter().zip(&c.parts) {
                // Cell sizes agree to rounding (2^(2k/10) vs 2^(k/5)).
                assert!(
                    (p.x1 - q.x1).abs() < 1e-9 && (p.y2 - q.y2).abs() < 1e-9 && p.mixture == q.mixture,
                    "{p:?} vs {q:?}"
                );
            }
        }
        let o = |n| DetectOptions {
            threshold: Some(-1e6),
            search: SearchScales::All,
            levels_per_octave: Some(n),
            ..Default::default()
        };
        assert_eq!(detect(&v, &m, &o(5)).unwrap().best().score, five[0].score);
        assert_eq!(detect(&v, &m, &o(10)).unwrap().best().score, ten[0].score);
        assert_eq!(detect(&v, &m, &o(10)).unwrap().best().cell_px, ten[0].cell_px);
        for bad in [0, 101] {
            assert!(
                matches!(detect(&v, &m, &o(bad)), Err(Error::OutOfRange { name: "levels_per_octave", .. })),
                "{bad}"
            );
        }
    }

    #[test]
    fn no_figure_reports_the_best_score() {
        let m = model::tests::tiny_model();
        let data = vec![128u8; 64 * 64];
        let v = ImageView::gray(&data, 64, 64).unwrap();
        let o = DetectOptions { threshold: Some(1e6), ..Default::default() };
        match detect(&v, &m, &o) {
            Err(Error::NoFigure { score, threshold }) => {
                assert!(score.is_finite() && score < 1e6, "{score}");
                assert_eq!(threshold, 1e6);
            }
            other => panic!("expected NoFigure, got {other:?}"),
        }
        let o = DetectOptions { threshold: Some(-1e6), max_detections: 3, ..Default::default() };
        let d = detect(&v, &m, &o).unwrap();
        assert!(!d.all.is_empty() && d.all.len() <= 3);
        assert!(d.all.windows(2).all(|w| w[0].score >= w[1].score));
    }

    #[test]
    fn huge_images_are_downscaled_and_mapped_back() {
        let m = model::tests::tiny_model();
        let data: Vec<u8> = (0..300 * 200).map(|i| ((i * 7) % 251) as u8).collect();
        let v = ImageView::gray(&data, 300, 200).unwrap();
        let (p, s) = prepare_image(&v, 150).unwrap();
        assert_eq!((p.width, p.height), (150, 100));
        assert_eq!(s, 2.0);
        let o = DetectOptions { threshold: Some(-1e6), max_side: 150, ..Default::default() };
        let d = detect(&v, &m, &o).unwrap();
        // Boxes are in input pixels: 2 cells of at least sbin/2 = 2 working px, times 2.
        let b = d.best().parts[0];
        assert!(b.x2 - b.x1 >= 8.0 - 1e-9, "box width {}", b.x2 - b.x1);
    }
}

//! Training images: positives (synthetic sketches rescaled so the figure is at the model's
//! canonical height, plus their mirror images with left/right swapped) with every part's cell
//! position, and negative pages without a figure.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::render::mannequin::render_mannequin;
use sketchbody::detect::hog::{hog, FeatureMap, Planes};
use sketchbody::detect::pyramid::{pad, resize};
use sketchbody::error::Result;
use sketchbody::render::sketch::background::render_background;
use sketchbody::render::sketch::truth::sample_seed;
use sketchbody::render::sketch::{ArtStyle, Hair, SketchRenderer, SketchRequest};
use sketchbody::skeleton::NUM_JOINTS;

use super::layout::{mirror_joints, part_points, NUM_PARTS};

/// One positive: the padded HOG map at the canonical scale and each part's filter position.
#[derive(Clone, Debug)]
pub struct Positive {
    /// Padded feature map (the engine's layout: cell x ↔ pixels from (x − pad)·sbin).
    pub feat: FeatureMap,
    /// Top-left cell (x, y) of each part's filter, inside the map.
    pub cells: [(usize, usize); NUM_PARTS],
    /// Part points, canonical-scale pixels (for mixture clustering).
    pub points: [[f64; 2]; NUM_PARTS],
}

/// Geometry of the examples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// HOG cell size, px.
    pub sbin: usize,
    /// Filter side, cells.
    pub side: usize,
    /// Standing figure height at the canonical scale, px.
    pub figure_px: f64,
}

impl Geometry {
    /// Engine padding (cells) for this filter side.
    pub fn pad(&self) -> usize {
        self.side.saturating_sub(2)
    }

    /// The positive of an image already at the canonical scale.
    pub fn at_scale(&self, im: &Planes, j: &[[f64; 2]; NUM_JOINTS]) -> Positive {
        let p = self.pad();
        let feat = pad(&hog(im, self.sbin), p, p);
        let points = part_points(j);
        let s = self.sbin as f64;
        let half = self.side as f64 / 2.0;
        let cell = |q: f64, n: usize| {
            ((q / s - half).round() + p as f64).clamp(0.0, n.saturating_sub(self.side) as f64) as usize
        };
        let cells = std::array::from_fn(|i| (cell(points[i][0], feat.cols), cell(points[i][1], feat.rows)));
        Positive { feat, cells, points }
    }

    /// The positive and its mirror image from a gray image (values 0..=255) whose figure has canonical joints
    /// `joints` (px) and standing height `height_px`; `None` when the figure is smaller than
    /// canonical (it would need upsampling).
    pub fn positive_pair(
        &self,
        gray: &Planes,
        joints: &[[f64; 2]; NUM_JOINTS],
        height_px: f64,
    ) -> Option<[Positive; 2]> {
        let f = self.figure_px / height_px;
        if !(f > 0.0 && f <= 1.0) {
            return None;
        }
        let small = resize(gray, f);
        let (fx, fy) = (small.width as f64 / gray.width as f64, small.height as f64 / gray.height as f64);
        let j: [[f64; 2]; NUM_JOINTS] = std::array::from_fn(|k| [joints[k][0] * fx, joints[k][1] * fy]);
        let flipped = mirror_planes(&small);
        let jm = mirror_joints(&j, small.width as f64);
        Some([self.at_scale(&small, &j), self.at_scale(&flipped, &jm)])
    }
}

/// Horizontal mirror image.
pub fn mirror_planes(im: &Planes) -> Planes {
    let mut data = im.data.clone();
    for row in data.chunks_exact_mut(im.width) {
        row.reverse();
    }
    Planes { data, ..im.clone() }
}

/// Gray planes of 8-bit pixels.
pub fn gray_planes(px: &[u8], width: usize, height: usize) -> Planes {
    Planes { width, height, channels: 1, data: px.iter().map(|&v| v as f32).collect() }
}

/// Seed tag of the mannequin choice and drawing of a positive.
const MANNEQUIN_STREAM: u64 = 0x4D41_4E4E;
/// Seed tag of the art-style choice of a positive.
const ART_STREAM: u64 = 0x4152_5453;

/// How the positives are drawn: fractions of all positives (each in [0, 1], sum ≤ 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drawing {
    /// Capsule mannequins around the same 2-D joints.
    pub mannequins: f64,
    /// Art styles ([`sketchbody::render::sketch::art`]), chosen among the positives that are not
    /// mannequins.
    pub art: f64,
}

/// Uniform in [0, 1) from the top 53 bits of `v`.
fn unit_of(v: u64) -> f64 {
    (v >> 11) as f64 / (1u64 << 53) as f64
}

/// Renders positives `0..n` of `seed` at `size`² (sample seeds as `make-dataset`), skipping
/// figures with hair `held_out`; a fraction `drawing.mannequins` of them (chosen per index from
/// its own stream) is redrawn as a capsule mannequin around the same 2-D joints, and a fraction
/// `drawing.art` (from another stream, among the others) is rendered in a random art style
/// ([`SketchRenderer::render_art`]). With both fractions 0 the positives are the plain sketches.
/// Returns the positives (each with its mirror) and the number of sketches skipped. Parallel,
/// order-preserving. Errors: the renderer's.
pub fn render_positives(
    renderer: &SketchRenderer,
    geo: &Geometry,
    seed: u64,
    n: usize,
    size: usize,
    held_out: Option<Hair>,
    drawing: Drawing,
) -> Result<(Vec<Positive>, usize)> {
    let art_share = if drawing.mannequins < 1.0 { drawing.art / (1.0 - drawing.mannequins) } else { 0.0 };
    let got: Vec<Option<[Positive; 2]>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let draw = sample_seed(seed ^ MANNEQUIN_STREAM, i as u64);
            let mannequin = unit_of(draw) < drawing.mannequins;
            let art_draw = sample_seed(seed ^ ART_STREAM, i as u64);
            let req = SketchRequest::random(sample_seed(seed, i as u64), size);
            let s = if !mannequin && unit_of(art_draw) < art_share {
                let style = ArtStyle::random(&mut ChaCha8Rng::seed_from_u64(art_draw));
                renderer.render_art(&req, &style)?
            } else {
                renderer.render(&req)?
            };
            if Some(s.truth.style.hair) == held_out {
                return Ok(None);
            }
            let j: [[f64; 2]; NUM_JOINTS] = std::array::from_fn(|k| s.truth.joints2d[k]);
            let height_px = s.truth.height_m * s.truth.camera.sx;
            let pixels = if mannequin { render_mannequin(&j, height_px, size, size, draw) } else { s.pixels };
            Ok(geo.positive_pair(&gray_planes(&pixels, size, size), &j, height_px))
        })
        .collect::<Result<_>>()?;
    let skipped = got.iter().filter(|g| g.is_none()).count();
    Ok((got.into_iter().flatten().flatten().collect(), skipped))
}

/// Negative pages `0..n` of `seed` at `size`² (gray, 8-bit).
pub fn render_negatives(seed: u64, n: usize, size: usize) -> Result<Vec<Vec<u8>>> {
    (0..n).into_par_iter().map(|i| render_background(sample_seed(seed ^ 0x004E_4547, i as u64), size, size)).collect()
}

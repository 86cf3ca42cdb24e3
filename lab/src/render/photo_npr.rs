//! Non-photorealistic filters that turn *training* photos into drawing-like positives for the
//! sketch detector (issue 15, item 5: PARSE photos 1–100 as real-pose positives). They are
//! deliberately different from the proxy benchmark's stylisations ([`crate::render::stylise`]:
//! XDoG ink, pencil hatching, posterised colour), which must never be used in training:
//!
//! - [`PhotoNpr::SobelInk`]: the Sobel gradient magnitude of the blurred luminance, soft
//!   thresholded between two of its own percentiles into gray-to-black line work;
//! - [`PhotoNpr::Charcoal`]: smudged dark tones (blurred luminance in four levels with
//!   dithering noise) over a rough grain, plus darker gradient edges;
//! - [`PhotoNpr::Marker`]: two flat marker tones (the luminance below two of its percentiles
//!   filled dark and mid gray) with thin gradient lines, no colour clustering.
//!
//! Output: 8-bit gray pixels of the input's size. Every random choice comes from a
//! `ChaCha8Rng` seeded by the caller's seed and a per-filter tag, so a call always returns the same
//! bytes. Lengths scale with the short side (1 at 256 px, at least 0.6).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::render::stylise::filters::{blur, luma, rgb_planes};
use sketchbody::error::Result;
use sketchbody::image::ImageView;

/// A training filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PhotoNpr {
    /// Gradient-magnitude line work.
    SobelInk,
    /// Smudged tones and grain.
    Charcoal,
    /// Two flat marker tones and thin lines.
    Marker,
}

impl PhotoNpr {
    /// Every filter.
    pub const ALL: [PhotoNpr; 3] = [PhotoNpr::SobelInk, PhotoNpr::Charcoal, PhotoNpr::Marker];

    /// Short name: "sobel", "charcoal", "marker".
    pub fn name(self) -> &'static str {
        match self {
            PhotoNpr::SobelInk => "sobel",
            PhotoNpr::Charcoal => "charcoal",
            PhotoNpr::Marker => "marker",
        }
    }

    /// The filter named `s` (see [`PhotoNpr::name`]).
    pub fn from_name(s: &str) -> Option<PhotoNpr> {
        PhotoNpr::ALL.into_iter().find(|f| f.name() == s)
    }

    fn tag(self) -> u64 {
        match self {
            PhotoNpr::SobelInk => 0x534F_4245,
            PhotoNpr::Charcoal => 0x4348_4152,
            PhotoNpr::Marker => 0x4D41_524B,
        }
    }
}

/// Sobel gradient magnitude of a plane (borders clamped).
fn gradient(v: &[f32], w: usize, h: usize) -> Vec<f32> {
    let at = |x: isize, y: isize| v[(y.clamp(0, h as isize - 1) as usize) * w + x.clamp(0, w as isize - 1) as usize];
    let mut out = vec![0f32; w * h];
    for y in 0..h as isize {
        for x in 0..w as isize {
            let gx = at(x + 1, y - 1) + 2.0 * at(x + 1, y) + at(x + 1, y + 1)
                - at(x - 1, y - 1)
                - 2.0 * at(x - 1, y)
                - at(x - 1, y + 1);
            let gy = at(x - 1, y + 1) + 2.0 * at(x, y + 1) + at(x + 1, y + 1)
                - at(x - 1, y - 1)
                - 2.0 * at(x, y - 1)
                - at(x + 1, y - 1);
            out[y as usize * w + x as usize] = (gx * gx + gy * gy).sqrt();
        }
    }
    out
}

/// The `q`-quantile (0..=1) of `v`.
fn quantile(v: &[f32], q: f64) -> f32 {
    let mut s = v.to_vec();
    s.sort_by(f32::total_cmp);
    s[((s.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize]
}

/// Soft step from 0 at `a` to 1 at `b`.
fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a).max(1e-6)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Line coverage (0..=1) from the gradient of `lum` (blurred by `sigma` px), between the
/// `lo` and `hi` quantiles of the gradient.
fn lines(lum: &[f32], w: usize, h: usize, sigma: f64, lo: f64, hi: f64) -> Vec<f32> {
    let g = gradient(&blur(lum, w, h, sigma), w, h);
    let (a, b) = (quantile(&g, lo), quantile(&g, hi));
    g.iter().map(|&v| smoothstep(a, b, v)).collect()
}

/// Applies `filter` to `src` (1, 3 or 4 channels). Errors: none beyond the view's own checks
/// (an empty view gives an empty result).
pub fn photo_npr(src: &ImageView<'_>, filter: PhotoNpr, seed: u64) -> Result<Vec<u8>> {
    let (w, h) = (src.width(), src.height());
    if w == 0 || h == 0 {
        return Ok(Vec::new());
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ filter.tag().rotate_left(32));
    let u = (w.min(h) as f64 / 256.0).max(0.6);
    let lum: Vec<f32> = rgb_planes(src).into_iter().map(luma).collect();
    let paper = rng.random_range(0.9..1.0f32);
    let out: Vec<f32> = match filter {
        PhotoNpr::SobelInk => {
            let ink = rng.random_range(0.7..1.0f32);
            let l = lines(
                &lum,
                w,
                h,
                rng.random_range(0.7..1.3) * u,
                rng.random_range(0.7..0.8),
                rng.random_range(0.9..0.96),
            );
            l.iter().map(|&a| paper * (1.0 - ink * a)).collect()
        }
        PhotoNpr::Charcoal => {
            let smudge = blur(&lum, w, h, rng.random_range(1.5..2.5) * u);
            let edges = lines(&lum, w, h, 1.0 * u, 0.85, 0.97);
            let grain_amp = rng.random_range(0.1..0.3f32);
            let gamma = rng.random_range(0.8..1.4f32);
            smudge
                .iter()
                .zip(&edges)
                .map(|(&s, &e)| {
                    let dither: f32 = rng.random_range(-0.12..0.12);
                    let level = (((1.0 - s).powf(gamma) + dither) * 4.0).floor().clamp(0.0, 3.0) / 3.0;
                    let grain = 1.0 - grain_amp * rng.random_range(0.0..1.0f32);
                    let dark = (0.75 * level * grain).max(0.9 * e);
                    paper * (1.0 - dark)
                })
                .collect()
        }
        PhotoNpr::Marker => {
            let soft = blur(&lum, w, h, rng.random_range(1.0..2.0) * u);
            let (t1, t2) = (quantile(&soft, rng.random_range(0.2..0.35)), quantile(&soft, rng.random_range(0.45..0.6)));
            let (d1, d2) = (rng.random_range(0.1..0.3f32), rng.random_range(0.5..0.75f32));
            let l = lines(&lum, w, h, 0.8 * u, 0.8, 0.93);
            soft.iter()
                .zip(&l)
                .map(|(&s, &a)| {
                    let fill = if s < t1 {
                        d1
                    } else if s < t2 {
                        d2
                    } else {
                        paper
                    };
                    fill * (1.0 - 0.9 * a)
                })
                .collect()
        }
    };
    Ok(out.iter().map(|&v| (255.0 * v).round().clamp(0.0, 255.0) as u8).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dark figure-like block on a light textured background, RGB.
    fn photo() -> Vec<u8> {
        let (w, h) = (64, 96);
        let mut v = Vec::with_capacity(w * h * 3);
        for y in 0..h {
            for x in 0..w {
                let body = (20..44).contains(&x) && (15..85).contains(&y);
                let g = if body { 40 + (y % 7) as u8 } else { 200 + ((x * 7 + y * 3) % 20) as u8 };
                v.extend([g, g.saturating_sub(10), g / 2 + 60]);
            }
        }
        v
    }

    #[test]
    fn filters_are_deterministic_distinct_and_draw_the_edges() {
        let px = photo();
        let view = ImageView::new(&px, 64, 96, 3, 64 * 3).unwrap();
        let mut outs = Vec::new();
        for f in PhotoNpr::ALL {
            let a = photo_npr(&view, f, 3).unwrap();
            assert_eq!(a, photo_npr(&view, f, 3).unwrap(), "{f:?} deterministic");
            assert_eq!(a.len(), 64 * 96);
            assert_ne!(a, photo_npr(&view, f, 4).unwrap(), "{f:?} depends on the seed");
            // The block's left edge (x 20) is drawn darker than the background far from it.
            let edge: f64 = (30..70).map(|y| a[y * 64 + 20].min(a[y * 64 + 19]) as f64).sum::<f64>() / 40.0;
            let bg: f64 = (30..70).map(|y| a[y * 64 + 4] as f64).sum::<f64>() / 40.0;
            assert!(edge + 40.0 < bg, "{f:?}: edge {edge} vs background {bg}");
            assert_eq!(PhotoNpr::from_name(f.name()), Some(f));
            outs.push(a);
        }
        assert!(outs[0] != outs[1] && outs[1] != outs[2] && outs[0] != outs[2]);
        assert_eq!(PhotoNpr::from_name("xdog"), None);
    }
}

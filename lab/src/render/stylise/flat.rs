//! The flat-colour design: a few bilateral passes flatten shading and texture, colour k-means
//! maps every pixel to one of [`COLOURS`] colours (slightly more saturated, like cel paint), a
//! mode filter removes specks, and Canny on the smoothed image draws dark outlines.

use super::filters::{kmeans_colours, luma, mode_filter, nearest, smooth_photo, Rgb};
use super::unit;
use sketchbody::error::Result;
use sketchbody::image::{canny, CannyParams, GrayImage};

/// Number of paint colours (k of the k-means).
pub(crate) const COLOURS: usize = 8;
/// Outline colour: a dark warm gray, as an inked line.
pub(crate) const OUTLINE: Rgb = [0.12, 0.1, 0.11];
/// Bilateral passes and their range sigma (RGB distance, 0..=1 units).
const PASSES: usize = 3;
const SIGMA_R: f32 = 0.12;
/// Saturation gain applied to the paint colours.
const SATURATION: f32 = 1.25;
/// Canny thresholds (L2 magnitude, aperture 3) on the smoothed gray image.
const CANNY: CannyParams = CannyParams { threshold1: 40.0, threshold2: 100.0, aperture: 3, l2_gradient: true };

/// Flat-colour version of RGB pixels (0..=1), `w`×`h`; `seed` drives the k-means sample and
/// seeding.
pub(super) fn flat(rgb: &[Rgb], w: usize, h: usize, seed: u64) -> Result<Vec<Rgb>> {
    let u = unit(w, h);
    let smooth = smooth_photo(rgb, w, h, u, PASSES, SIGMA_R);
    let centres = kmeans_colours(&smooth, COLOURS, 12, 20_000, seed ^ 0x666C_6174);
    let mut labels: Vec<u8> = smooth.iter().map(|&p| nearest(p, &centres) as u8).collect();
    for _ in 0..2 {
        labels = mode_filter(&labels, w, h);
    }
    let paint: Vec<Rgb> = centres.iter().map(|&c| saturate(c, SATURATION)).collect();
    let gray =
        GrayImage::from_vec(w, h, smooth.iter().map(|&p| (luma(p) * 255.0).round().clamp(0.0, 255.0) as u8).collect())?;
    let edges = canny(&gray.view(), &CANNY)?;
    let thick = u >= 1.5;
    let e = edges.as_bytes();
    let edge_at = |x: usize, y: usize| {
        e[y * w + x] != 0 || (thick && ((x > 0 && e[y * w + x - 1] != 0) || (y > 0 && e[(y - 1) * w + x] != 0)))
    };
    Ok((0..w * h)
        .map(
            |i| {
                if edge_at(i % w, i / w) {
                    OUTLINE
                } else {
                    paint.get(labels[i] as usize).copied().unwrap_or([1.0; 3])
                }
            },
        )
        .collect())
}

/// `c` with its distance from its own gray scaled by `gain`, clamped to 0..=1.
fn saturate(c: Rgb, gain: f32) -> Rgb {
    let g = luma(c);
    c.map(|v| (g + (v - g) * gain).clamp(0.0, 1.0))
}

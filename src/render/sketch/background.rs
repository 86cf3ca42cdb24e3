//! Sketch pages without a figure: the negatives of detector training. The same paper, pencil
//! and clutter as [`super::SketchRenderer::render`], plus drawings that are not people (ellipses,
//! boxes, limb-like tubes, long curves, hatched patches). A separate entry point with its own
//! random stream, so the output of every existing sketch seed is unchanged.

use std::f64::consts::TAU;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::canvas::{Canvas, Pen};
use super::{paper, SketchStyle, DEFAULT_SIZE};
use crate::error::Result;
use crate::raster::check_size;

/// Stream tag mixed into the seed so that a background never repeats a figure sketch's stream.
const STREAM: u64 = 0x6E6F_2D66_6967_7572;

/// A smooth random curve of `n` points from `p`, heading `a`, segment `step` px, turning by
/// up to `bend` radians a step.
fn curve<R: Rng + ?Sized>(p: [f64; 2], a: f64, step: f64, n: usize, bend: f64, rng: &mut R) -> Vec<[f64; 2]> {
    let (mut p, mut a, mut da) = (p, a, 0.0);
    let mut out = vec![p];
    for _ in 0..n {
        da = 0.7 * da + rng.random_range(-bend..=bend);
        a += da;
        p = [p[0] + a.cos() * step, p[1] + a.sin() * step];
        out.push(p);
    }
    out
}

/// An ellipse with centre `c`, radii `r`, rotation `t`, as a closed polyline.
fn ellipse(c: [f64; 2], r: [f64; 2], t: f64) -> Vec<[f64; 2]> {
    (0..=48)
        .map(|i| {
            let u = i as f64 / 48.0 * TAU;
            let (x, y) = (r[0] * u.cos(), r[1] * u.sin());
            [c[0] + x * t.cos() - y * t.sin(), c[1] + x * t.sin() + y * t.cos()]
        })
        .collect()
}

/// Draws one random non-figure shape.
fn shape<R: Rng + ?Sized>(canvas: &mut Canvas, pen: &Pen, unit: f64, rng: &mut R) {
    let (w, h) = (canvas.width as f64, canvas.height as f64);
    let c = [rng.random_range(0.0..w), rng.random_range(0.0..h)];
    match rng.random_range(0..5) {
        0 => {
            let r = [rng.random_range(8.0..90.0) * unit, rng.random_range(8.0..90.0) * unit];
            canvas.stroke(&ellipse(c, r, rng.random_range(0.0..TAU)), pen, rng);
        }
        1 => {
            let (bw, bh) = (rng.random_range(15.0..160.0) * unit, rng.random_range(15.0..160.0) * unit);
            let corners = [[c[0], c[1]], [c[0] + bw, c[1]], [c[0] + bw, c[1] + bh], [c[0], c[1] + bh], [c[0], c[1]]];
            for s in corners.windows(2) {
                canvas.stroke(&[s[0], s[1]], pen, rng);
            }
        }
        2 => {
            // A limb-like tube: two roughly parallel curves.
            let a = rng.random_range(0.0..TAU);
            let spine = curve(c, a, 6.0 * unit, rng.random_range(6..30), 0.08, rng);
            let half = rng.random_range(5.0..22.0) * unit;
            for side in [-1.0, 1.0] {
                let pts: Vec<[f64; 2]> = spine
                    .windows(2)
                    .map(|s| {
                        let (dx, dy) = (s[1][0] - s[0][0], s[1][1] - s[0][1]);
                        let l = (dx * dx + dy * dy).sqrt().max(1e-9);
                        [s[0][0] - dy / l * half * side, s[0][1] + dx / l * half * side]
                    })
                    .collect();
                canvas.stroke(&pts, pen, rng);
            }
        }
        3 => {
            let pts = curve(c, rng.random_range(0.0..TAU), 5.0 * unit, rng.random_range(20..90), 0.12, rng);
            canvas.stroke(&pts, pen, rng);
        }
        _ => {
            // A hatched patch.
            let (pw, ph) = (rng.random_range(20.0..120.0) * unit, rng.random_range(20.0..120.0) * unit);
            let gap = rng.random_range(3.5..8.0) * unit;
            let light = Pen { ink: pen.ink * 0.6, width: pen.width * 0.6, ..*pen };
            let mut x = 0.0;
            while x < pw {
                canvas.stroke(&[[c[0] + x, c[1] + ph], [c[0] + x + 0.6 * ph, c[1]]], &light, rng);
                x += gap;
            }
        }
    }
}

/// A gray page (0 ink, 255 paper; `width` bytes a row) of paper, pencil clutter and non-figure
/// drawings, from `seed`. Errors: sizes outside 1..=4096.
pub fn render_background(seed: u64, width: usize, height: usize) -> Result<Vec<u8>> {
    check_size(width, height)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ STREAM);
    let style = SketchStyle::random(&mut rng);
    let unit = width.min(height) as f64 / DEFAULT_SIZE as f64;
    let pen = Pen {
        width: style.stroke_width * unit,
        ink: style.ink,
        wobble: style.wobble * unit,
        jitter: style.pressure_jitter,
        taper: 0.15,
    };
    let mut canvas = Canvas::new(width, height);
    for _ in 0..rng.random_range(0..9) {
        shape(&mut canvas, &pen, unit, &mut rng);
    }
    let ground = rng.random_bool(0.5).then(|| {
        let y = rng.random_range(0.5..0.95) * height as f64;
        let x0 = rng.random_range(0.0..0.5) * width as f64;
        (y, x0, x0 + rng.random_range(0.2..0.5) * width as f64)
    });
    let strays = rng.random_range(0..40);
    let scribbles = rng.random_range(0..6);
    paper::clutter(&mut canvas, &pen, unit, strays, scribbles, style.text_rows, ground, &mut rng);
    Ok(paper::compose(&canvas, style.paper_tone, style.paper_noise, 1.0, &mut rng))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backgrounds_are_deterministic_and_differ_by_seed() {
        let a = render_background(3, 96, 80).unwrap();
        assert_eq!(a.len(), 96 * 80);
        assert_eq!(a, render_background(3, 96, 80).unwrap());
        assert_ne!(a, render_background(4, 96, 80).unwrap());
        assert!(render_background(1, 0, 10).is_err());
    }
}

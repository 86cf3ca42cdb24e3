//! The pencil sketch: Canny edges of the smoothed photo traced into chains and redrawn as
//! jittered, tapered gray strokes, diagonal hatching over the darker tones, faint paper grain.
//! Pencil coverage never exceeds [`OUTLINE_INK`]'s upper end, so nothing is pure black.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::filters::{blur, luma, smooth_photo, Rgb};
use super::unit;
use sketchbody::error::Result;
use sketchbody::image::{canny, gaussian_blur, CannyParams, GrayImage};
use sketchbody::render::sketch::canvas::{smooth, Canvas, Pen};
use sketchbody::render::sketch::paper::compose;

/// Stream tag mixed into the seed (ASCII "pencil").
const STREAM: u64 = 0x7065_6E63_696C;

/// Darkness range of outline strokes (0 paper .. 1 black): gray 65–120 on white paper.
pub(crate) const OUTLINE_INK: std::ops::Range<f64> = 0.53..0.745;
/// Darkness range of hatching strokes: gray 140–170.
const HATCH_INK: std::ops::Range<f64> = 0.33..0.45;
/// Smoothed-luminance limits of the three hatching levels: below 0.5 sparse lines, below 0.36
/// dense lines, below 0.24 cross-hatching as well.
const TONE_LEVELS: [f32; 3] = [0.5, 0.36, 0.24];
/// Canny thresholds (L2 magnitude, aperture 3) on the blurred gray photo.
const CANNY: CannyParams = CannyParams { threshold1: 50.0, threshold2: 120.0, aperture: 3, l2_gradient: true };

/// Pencil sketch of RGB pixels (0..=1), `w`×`h`, from `seed`.
pub(super) fn pencil(rgb: &[Rgb], w: usize, h: usize, seed: u64) -> Result<Vec<Rgb>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ STREAM);
    let u = unit(w, h);
    let l: Vec<f32> = rgb.iter().map(|&p| luma(p)).collect();
    let soft: Vec<u8> =
        smooth_photo(rgb, w, h, u, 2, 0.1).iter().map(|&p| (luma(p) * 255.0).round().clamp(0.0, 255.0) as u8).collect();
    let smoothed = gaussian_blur(&GrayImage::from_vec(w, h, soft)?.view(), 0.7 * u)?;
    let edges = canny(&smoothed.view(), &CANNY)?;
    let mut canvas = Canvas::new(w, h);
    // Hatching first: outlines drawn later keep their darker value where they cross it.
    let tone = blur(&l, w, h, 2.0 * u);
    hatch(&mut canvas, &tone, u, &mut rng);
    for chain in chains(edges.as_bytes(), w, h) {
        outline(&mut canvas, &chain, u, &mut rng);
    }
    let paper = compose(&canvas, 0.975, 0.035, 1.0, &mut rng);
    Ok(paper
        .iter()
        .map(|&g| [g as f32 / 255.0, g as f32 / 255.0, g as f32 / 252.0])
        .map(|p| p.map(|v| v.min(1.0)))
        .collect())
}

/// Chains of 8-connected edge pixels (255 in `edges`), each a list of pixel indices, grown from
/// the first unvisited pixel in raster order and continued greedily, preferring straight on.
fn chains(edges: &[u8], w: usize, h: usize) -> Vec<Vec<(usize, usize)>> {
    const DIRS: [(isize, isize); 8] = [(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1)];
    let mut seen = vec![false; w * h];
    let mut out = Vec::new();
    for start in 0..w * h {
        if edges[start] == 0 || seen[start] {
            continue;
        }
        seen[start] = true;
        let mut chain = vec![(start % w, start / w)];
        let mut dir = 0usize;
        loop {
            let (x, y) = chain[chain.len() - 1];
            let next = (0..8)
                .map(|k| (dir + [0, 1, 7, 2, 6, 3, 5, 4][k]) % 8)
                .map(|d| (d, x as isize + DIRS[d].0, y as isize + DIRS[d].1))
                .find(|&(_, nx, ny)| {
                    nx >= 0
                        && ny >= 0
                        && (nx as usize) < w
                        && (ny as usize) < h
                        && edges[ny as usize * w + nx as usize] != 0
                        && !seen[ny as usize * w + nx as usize]
                });
            let Some((d, nx, ny)) = next else { break };
            seen[ny as usize * w + nx as usize] = true;
            chain.push((nx as usize, ny as usize));
            dir = d;
        }
        out.push(chain);
    }
    out
}

/// Redraws one edge chain as pencil strokes: pieces of 12–40 units, every other pixel kept and
/// smoothed, shifted by up to half a unit and slightly overshooting; sometimes a second, lighter
/// stroke beside it, as a sketcher searching for the line.
fn outline<R: Rng + ?Sized>(canvas: &mut Canvas, chain: &[(usize, usize)], u: f64, rng: &mut R) {
    if chain.len() < (4.0 * u) as usize + 2 {
        return;
    }
    let mut rest = chain;
    while rest.len() >= 3 {
        let take = (rng.random_range(12.0..40.0) * u) as usize;
        let cut = if rest.len() <= take + take / 3 { rest.len() } else { take.max(3) };
        let (piece, tail) = rest.split_at(cut);
        rest = tail;
        let mut pts: Vec<[f64; 2]> = piece.iter().step_by(2).map(|&(x, y)| [x as f64 + 0.5, y as f64 + 0.5]).collect();
        if let Some(&(x, y)) = piece.last() {
            pts.push([x as f64 + 0.5, y as f64 + 0.5]);
        }
        smooth(&mut pts, 2);
        let n = pts.len();
        if n < 2 {
            continue;
        }
        // Overshoot both ends a little along the end tangents.
        let over = rng.random_range(0.0..2.5) * u;
        for (a, b) in [(0, 1), (n - 1, n - 2)] {
            let (dx, dy) = (pts[a][0] - pts[b][0], pts[a][1] - pts[b][1]);
            let len = (dx * dx + dy * dy).sqrt().max(1e-9);
            pts[a] = [pts[a][0] + dx / len * over, pts[a][1] + dy / len * over];
        }
        let shift = [rng.random_range(-0.5..0.5) * u, rng.random_range(-0.5..0.5) * u];
        let shifted: Vec<[f64; 2]> = pts.iter().map(|p| [p[0] + shift[0], p[1] + shift[1]]).collect();
        let pen = Pen {
            width: (1.6 * u).max(1.5),
            ink: rng.random_range(OUTLINE_INK),
            wobble: 0.35 * u,
            jitter: 0.4,
            taper: 0.2,
        };
        canvas.stroke(&shifted, &pen, rng);
        if rng.random_bool(0.25) {
            let d = rng.random_range(0.8..1.6) * u;
            let again: Vec<[f64; 2]> = shifted.iter().map(|p| [p[0] + d * 0.6, p[1] - d * 0.8]).collect();
            canvas.stroke(&again, &Pen { ink: pen.ink * 0.6, width: pen.width * 0.8, ..pen }, rng);
        }
    }
}

/// Diagonal hatching by tone: one family of lines at about 45° (rising to the right) every
/// `2 × 3.2` units where the smoothed luminance `tone` is below the first level, the in-between
/// lines below the second, a crossing family below the third. Lines are broken into dashes of
/// 8–24 units with jittered ends.
fn hatch<R: Rng + ?Sized>(canvas: &mut Canvas, tone: &[f32], u: f64, rng: &mut R) {
    let (w, h) = (canvas.width, canvas.height);
    let base = -FRAC_PI_4 + rng.random_range(-0.12..0.12);
    let gap = 3.2 * u;
    let phase = rng.random_range(0.0..gap);
    let families = [
        (base, 2.0 * gap, phase, TONE_LEVELS[0]),
        (base, 2.0 * gap, phase + gap, TONE_LEVELS[1]),
        (base + FRAC_PI_2 + rng.random_range(-0.15..0.15), 2.2 * gap, phase, TONE_LEVELS[2]),
    ];
    let level_ok = |x: f64, y: f64, limit: f32| {
        x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h && tone[y as usize * w + x as usize] < limit
    };
    for (angle, spacing, phase, limit) in families {
        let (d, n) = ([angle.cos(), angle.sin()], [-angle.sin(), angle.cos()]);
        let corners = [[0.0, 0.0], [w as f64, 0.0], [0.0, h as f64], [w as f64, h as f64]];
        let proj = |v: [f64; 2], a: [f64; 2]| v[0] * a[0] + v[1] * a[1];
        let (tmin, tmax) =
            corners.iter().fold((f64::MAX, f64::MIN), |m, c| (m.0.min(proj(*c, n)), m.1.max(proj(*c, n))));
        let (smin, smax) =
            corners.iter().fold((f64::MAX, f64::MIN), |m, c| (m.0.min(proj(*c, d)), m.1.max(proj(*c, d))));
        let mut t = tmin + phase;
        while t <= tmax {
            let at = |s: f64| [t * n[0] + s * d[0], t * n[1] + s * d[1]];
            let mut s = smin;
            let mut run_start: Option<f64> = None;
            while s <= smax + 1.0 {
                let p = at(s);
                let inside = s <= smax && level_ok(p[0], p[1], limit);
                match (inside, run_start) {
                    (true, None) => run_start = Some(s),
                    (false, Some(s0)) => {
                        dashes(canvas, s0, s, &at, n, u, rng);
                        run_start = None;
                    }
                    _ => {}
                }
                s += 1.0;
            }
            t += spacing;
        }
    }
}

/// Draws the run `s0..s1` of a hatching line `at(s)` (normal `n`) as jittered dashes.
fn dashes<R: Rng + ?Sized>(
    canvas: &mut Canvas,
    s0: f64,
    s1: f64,
    at: &dyn Fn(f64) -> [f64; 2],
    n: [f64; 2],
    u: f64,
    rng: &mut R,
) {
    let mut a = s0 + rng.random_range(0.0..1.5) * u;
    while a < s1 - 2.0 * u {
        let b = (a + rng.random_range(8.0..24.0) * u).min(s1 - rng.random_range(0.0..1.5) * u);
        let (j0, j1) = (rng.random_range(-0.6..0.6) * u, rng.random_range(-0.6..0.6) * u);
        let (p, q) = (at(a), at(b));
        let pts = [[p[0] + n[0] * j0, p[1] + n[1] * j0], [q[0] + n[0] * j1, q[1] + n[1] * j1]];
        let pen = Pen { width: 0.9 * u, ink: rng.random_range(HATCH_INK), wobble: 0.15 * u, jitter: 0.3, taper: 0.25 };
        canvas.stroke(&pts, &pen, rng);
        a = b + rng.random_range(1.0..3.5) * u;
    }
}

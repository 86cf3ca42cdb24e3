//! Paper, shading and clutter: paper tone with low-frequency blotches and grain, hatching of the
//! shaded side of the body (normals from the depth buffer), and background clutter — stray
//! strokes, scribbles, rows of text-like marks and a ground line under the feet.

use rand::Rng;
use std::f64::consts::TAU;

use super::canvas::{Canvas, Pen};
use super::contours::DepthView;

/// Shade `1 − max(0, n·L)` of the body at pixel (x, y) for a unit light `l` (+y up, +z toward
/// the viewer): the normal comes from the depth gradient (`scale` pixels per metre). `None` off
/// the body, at the image border and across depth jumps.
pub fn shade_at(depth: &DepthView<'_>, scale: f64, x: usize, y: usize, l: [f64; 3]) -> Option<f64> {
    let w = depth.width;
    if x == 0 || y == 0 || x + 1 >= w || y + 1 >= depth.height {
        return None;
    }
    let d = |i: usize, j: usize| depth.depth[j * w + i];
    let c = d(x, y);
    if c == f32::NEG_INFINITY {
        return None;
    }
    let (l_, r_, u_, b_) = (d(x - 1, y), d(x + 1, y), d(x, y - 1), d(x, y + 1));
    if [l_, r_, u_, b_].iter().any(|&v| v == f32::NEG_INFINITY || (v - c).abs() as f64 * scale > 4.0) {
        return None;
    }
    let dzdx = (r_ - l_) as f64 * 0.5 * scale; // per metre in x
    let dzdy = -(b_ - u_) as f64 * 0.5 * scale; // per metre up
    let nl = (dzdx * dzdx + dzdy * dzdy + 1.0).sqrt();
    let n = [-dzdx / nl, -dzdy / nl, 1.0 / nl];
    Some(1.0 - (n[0] * l[0] + n[1] * l[1] + n[2] * l[2]).max(0.0))
}

/// Hatches the body where it faces away from a light at the upper left: the normal at each
/// covered pixel comes from the depth gradient (`scale` pixels per metre); pixels whose shade
/// `1 − max(0, n·L)` exceeds `1 − amount` get diagonal lines every `spacing` pixels, and the
/// darkest also cross-hatching. `amount` 0 draws nothing.
pub fn hatch<R: Rng + ?Sized>(
    canvas: &mut Canvas,
    depth: &DepthView<'_>,
    scale: f64,
    amount: f64,
    spacing: f64,
    ink: f64,
    rng: &mut R,
) {
    if amount <= 0.0 {
        return;
    }
    let (w, h) = (depth.width, depth.height);
    let l = {
        let v: [f64; 3] = [-0.45, 0.55, 0.70];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / n, v[1] / n, v[2] / n]
    };
    let phase = rng.random_range(0.0..spacing);
    let slope = rng.random_range(0.6..1.6);
    let thr = 1.0 - amount;
    for y in 1..h.saturating_sub(1) {
        for x in 1..w.saturating_sub(1) {
            let Some(shade) = shade_at(depth, scale, x, y, l) else {
                continue;
            };
            if shade <= thr {
                continue;
            }
            let k = ((shade - thr) / amount.max(1e-6)).clamp(0.0, 1.0);
            let line = |t: f64| {
                let f = (t / spacing).rem_euclid(1.0);
                (1.0 - (f - 0.5).abs() * 2.0 * spacing / 1.2).clamp(0.0, 1.0)
            };
            let mut a = line(x as f64 + slope * y as f64 + phase) * k;
            if k > 0.6 {
                a = a.max(line(x as f64 - y as f64 + phase) * (k - 0.6) / 0.4);
            }
            canvas.put(x as i64, y as i64, (a * ink * 0.55) as f32);
        }
    }
}

/// A random point in the image, pixels.
fn anywhere<R: Rng + ?Sized>(rng: &mut R, w: f64, h: f64) -> [f64; 2] {
    [rng.random_range(0.0..w), rng.random_range(0.0..h)]
}

/// Background clutter: `strays` stray strokes, `scribbles` scribble patches, `text_rows` rows of
/// text-like marks in a corner, and a ground line at image row `ground_y` between `x0` and `x1`
/// when given. `unit` is the stroke scale in pixels (1 at 512²).
#[allow(clippy::too_many_arguments)]
pub fn clutter<R: Rng + ?Sized>(
    canvas: &mut Canvas,
    pen: &Pen,
    unit: f64,
    strays: usize,
    scribbles: usize,
    text_rows: usize,
    ground: Option<(f64, f64, f64)>,
    rng: &mut R,
) {
    let (w, h) = (canvas.width as f64, canvas.height as f64);
    let light = Pen { ink: pen.ink * 0.6, width: pen.width * 0.7, ..*pen };
    for _ in 0..strays {
        let p = anywhere(rng, w, h);
        let len = rng.random_range(10.0..60.0) * unit;
        let a = rng.random_range(0.0..TAU);
        let bend = rng.random_range(-0.3..0.3);
        let pts: Vec<[f64; 2]> = (0..=8)
            .map(|i| {
                let t = i as f64 / 8.0;
                let ang = a + bend * t;
                [p[0] + ang.cos() * len * t, p[1] + ang.sin() * len * t]
            })
            .collect();
        canvas.stroke(&pts, &light, rng);
    }
    for _ in 0..scribbles {
        let c = anywhere(rng, w, h);
        let r = rng.random_range(4.0..14.0) * unit;
        let turns = rng.random_range(3..8);
        let pts: Vec<[f64; 2]> = (0..turns * 12)
            .map(|i| {
                let t = i as f64 / 12.0 * TAU;
                let rr = r * (0.6 + 0.4 * (t * 0.37).sin());
                [c[0] + rr * t.cos() + i as f64 * 0.3 * unit, c[1] + rr * 0.6 * t.sin()]
            })
            .collect();
        canvas.stroke(&pts, &light, rng);
    }
    if text_rows > 0 {
        let x0 = if rng.random_bool(0.5) { 0.04 * w } else { 0.62 * w };
        let y0 = if rng.random_bool(0.5) { 0.05 * h } else { 0.8 * h };
        let row_h = 14.0 * unit;
        let text_pen = Pen { width: pen.width * 0.55, ink: pen.ink * 0.7, wobble: 0.2, jitter: 0.3, taper: 0.05 };
        for r in 0..text_rows {
            let mut x = x0;
            let y = y0 + r as f64 * row_h;
            let end = x0 + rng.random_range(0.15..0.33) * w;
            while x < end {
                let word = rng.random_range(3..9);
                let pts: Vec<[f64; 2]> = (0..word * 6)
                    .map(|i| {
                        let t = i as f64 / 6.0;
                        [x + t * 4.5 * unit, y - (t * TAU).sin().abs() * 5.0 * unit * rng.random_range(0.5..1.2)]
                    })
                    .collect();
                canvas.stroke(&pts, &text_pen, rng);
                x += word as f64 * 4.5 * unit + rng.random_range(5.0..10.0) * unit;
            }
        }
    }
    if let Some((y, x0, x1)) = ground {
        let tilt = rng.random_range(-0.02..0.02);
        let pts: Vec<[f64; 2]> = (0..=20)
            .map(|i| {
                let x = x0 + (x1 - x0) * i as f64 / 20.0;
                [x, y + (x - x0) * tilt]
            })
            .collect();
        canvas.stroke(&pts, pen, rng);
        if rng.random_bool(0.5) {
            let pts: Vec<[f64; 2]> = pts.iter().map(|p| [p[0] + 12.0 * unit, p[1] + 4.0 * unit]).collect();
            canvas.stroke(&pts, &light, rng);
        }
    }
}

/// Paper under ink: tone `tone` (0..=1 brightness), smooth blotches and grain of strength
/// `noise`, ink darkening it by `ink_dark` (0..=1). Returns 8-bit gray pixels.
pub fn compose<R: Rng + ?Sized>(canvas: &Canvas, tone: f64, noise: f64, ink_dark: f64, rng: &mut R) -> Vec<u8> {
    let (w, h) = (canvas.width, canvas.height);
    // Low-frequency value noise on an 8×8 grid, bilinear.
    const G: usize = 8;
    let grid: Vec<f64> = (0..(G + 1) * (G + 1)).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        let gy = y as f64 / h as f64 * G as f64;
        let (j, fy) = ((gy as usize).min(G - 1), gy - (gy as usize).min(G - 1) as f64);
        for x in 0..w {
            let gx = x as f64 / w as f64 * G as f64;
            let (i, fx) = ((gx as usize).min(G - 1), gx - (gx as usize).min(G - 1) as f64);
            let g = |a: usize, b: usize| grid[b * (G + 1) + a];
            let blot = g(i, j) * (1.0 - fx) * (1.0 - fy)
                + g(i + 1, j) * fx * (1.0 - fy)
                + g(i, j + 1) * (1.0 - fx) * fy
                + g(i + 1, j + 1) * fx * fy;
            let grain: f64 = rng.random_range(-1.0..1.0);
            let paper = (tone + noise * (0.6 * blot + 0.4 * grain)).clamp(0.0, 1.0);
            let ink = canvas.ink[y * w + x] as f64 * ink_dark;
            out.push((255.0 * paper * (1.0 - ink)).round().clamp(0.0, 255.0) as u8);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn compose_darkens_ink_and_hatching_follows_slopes() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut c = Canvas::new(16, 16);
        c.ink[5 * 16 + 5] = 1.0;
        let px = compose(&c, 0.9, 0.0, 1.0, &mut rng);
        assert_eq!(px[5 * 16 + 5], 0);
        assert_eq!(px[0], 230);
        // A plane turned away from the light (depth falling to the right: normal toward +x) gets hatched; a flat one
        // facing the viewer does not.
        let mut c = Canvas::new(32, 32);
        let turned: Vec<f32> = (0..32 * 32).map(|k| -((k % 32) as f32) * 0.02).collect();
        hatch(&mut c, &DepthView { depth: &turned, width: 32, height: 32 }, 100.0, 0.5, 4.0, 1.0, &mut rng);
        assert!(c.ink.iter().any(|&a| a > 0.2));
        let mut c = Canvas::new(32, 32);
        let flat = vec![0.0f32; 32 * 32];
        hatch(&mut c, &DepthView { depth: &flat, width: 32, height: 32 }, 100.0, 0.5, 4.0, 1.0, &mut rng);
        assert!(c.ink.iter().all(|&a| a == 0.0));
    }
}

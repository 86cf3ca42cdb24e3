//! The drawing surface: an ink-coverage layer (0 = paper, 1 = full ink) and pencil-like strokes
//! with varying width, pressure and wobble. A stroke is a polyline in pixels; it is resampled
//! every 0.6 px, displaced along its normal by a smooth random wobble, and stamped as
//! anti-aliased discs whose radius and darkness follow a pressure profile (tapered ends and a
//! slow random variation). Coverage is combined with `max`, as graphite on paper.

use rand::Rng;
use std::f64::consts::TAU;

/// How one stroke is drawn. Widths in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pen {
    /// Full-pressure width, pixels.
    pub width: f64,
    /// Darkness at full pressure, 0..=1.
    pub ink: f64,
    /// Wobble amplitude, pixels (perpendicular displacement).
    pub wobble: f64,
    /// Pressure variation along the stroke, 0 (even) ..=1.
    pub jitter: f64,
    /// Fraction of the length over which each end tapers, 0..=0.5.
    pub taper: f64,
}

/// An ink-coverage layer of `width`×`height` pixels, row-major.
#[derive(Clone, Debug)]
pub struct Canvas {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Ink coverage per pixel, 0..=1.
    pub ink: Vec<f32>,
}

impl Canvas {
    /// A blank canvas.
    pub fn new(width: usize, height: usize) -> Canvas {
        Canvas { width, height, ink: vec![0.0; width * height] }
    }

    /// Adds coverage `a` (0..=1) at pixel (x, y), keeping the maximum; outside pixels are ignored.
    pub fn put(&mut self, x: i64, y: i64, a: f32) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let p = &mut self.ink[y as usize * self.width + x as usize];
            if a > *p {
                *p = a;
            }
        }
    }

    /// Stamps an anti-aliased disc of radius `r` (pixels) centred at (cx, cy) with darkness `a`.
    pub fn disc(&mut self, cx: f64, cy: f64, r: f64, a: f64) {
        let r = r.max(0.3);
        let (x0, x1) = ((cx - r - 1.0).floor() as i64, (cx + r + 1.0).ceil() as i64);
        let (y0, y1) = ((cy - r - 1.0).floor() as i64, (cy + r + 1.0).ceil() as i64);
        if x1 < 0 || y1 < 0 || x0 >= self.width as i64 || y0 >= self.height as i64 {
            return;
        }
        for y in y0..=y1 {
            for x in x0..=x1 {
                let d = ((x as f64 + 0.5 - cx).powi(2) + (y as f64 + 0.5 - cy).powi(2)).sqrt();
                let cov = (r + 0.5 - d).clamp(0.0, 1.0);
                if cov > 0.0 {
                    self.put(x, y, (cov * a) as f32);
                }
            }
        }
    }

    /// Draws the polyline `pts` (pixels) with `pen`; random wobble phases and pressure come from
    /// `rng`. Polylines with fewer than two points or non-finite points are skipped.
    pub fn stroke<R: Rng + ?Sized>(&mut self, pts: &[[f64; 2]], pen: &Pen, rng: &mut R) {
        if pts.len() < 2 || pts.iter().any(|p| !(p[0].is_finite() && p[1].is_finite())) {
            return;
        }
        let samples = resample(pts, 0.6);
        let n = samples.len();
        if n < 2 {
            return;
        }
        let total = 0.6 * (n - 1) as f64;
        let (l1, l2) = (rng.random_range(30.0..90.0), rng.random_range(14.0..30.0));
        let (f1, f2, f3) = (rng.random_range(0.0..TAU), rng.random_range(0.0..TAU), rng.random_range(0.0..TAU));
        let lp = rng.random_range(20.0..60.0);
        let taper_len = (pen.taper * total).max(1e-9);
        for (i, p) in samples.iter().enumerate() {
            let s = 0.6 * i as f64;
            let (a, b) = (samples[i.saturating_sub(1)], samples[(i + 1).min(n - 1)]);
            let (tx, ty) = (b[0] - a[0], b[1] - a[1]);
            let tl = (tx * tx + ty * ty).sqrt().max(1e-9);
            let (nx, ny) = (-ty / tl, tx / tl);
            let w = pen.wobble * (0.8 * (TAU * s / l1 + f1).sin() + 0.2 * (TAU * s / l2 + f2).sin());
            let end = (s.min(total - s) / taper_len).clamp(0.0, 1.0);
            let press = end.sqrt() * (1.0 - pen.jitter * 0.5 * (1.0 + (TAU * s / lp + f3).sin()));
            let r = 0.5 * pen.width * (0.35 + 0.65 * press);
            self.disc(p[0] + nx * w, p[1] + ny * w, r, pen.ink * (0.45 + 0.55 * press));
        }
    }
}

/// Resamples a polyline at `step` pixels along its length (first and last points kept).
pub fn resample(pts: &[[f64; 2]], step: f64) -> Vec<[f64; 2]> {
    let mut out = vec![pts[0]];
    let (mut next, mut acc) = (step, 0.0);
    for w in pts.windows(2) {
        let (dx, dy) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
        let len = (dx * dx + dy * dy).sqrt();
        while len > 0.0 && next <= acc + len {
            let t = (next - acc) / len;
            out.push([w[0][0] + dx * t, w[0][1] + dy * t]);
            next += step;
        }
        acc += len;
    }
    if let (Some(last), Some(end)) = (out.last(), pts.last()) {
        if (last[0] - end[0]).abs() + (last[1] - end[1]).abs() > 1e-9 {
            out.push(*end);
        }
    }
    out
}

/// Length of a polyline, pixels.
pub fn length(pts: &[[f64; 2]]) -> f64 {
    pts.windows(2).map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt()).sum()
}

/// Smooths a polyline in place with `iters` passes of the (¼, ½, ¼) filter (ends fixed).
pub fn smooth(pts: &mut [[f64; 2]], iters: usize) {
    for _ in 0..iters {
        if pts.len() < 3 {
            return;
        }
        let prev = pts.to_vec();
        for i in 1..pts.len() - 1 {
            for a in 0..2 {
                pts[i][a] = 0.25 * prev[i - 1][a] + 0.5 * prev[i][a] + 0.25 * prev[i + 1][a];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn stroke_inks_along_its_path_only() {
        let mut c = Canvas::new(64, 32);
        let pen = Pen { width: 3.0, ink: 1.0, wobble: 0.0, jitter: 0.0, taper: 0.1 };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        c.stroke(&[[5.0, 16.0], [59.0, 16.0]], &pen, &mut rng);
        assert!(c.ink[16 * 64 + 32] > 0.9, "middle of the stroke is dark");
        assert_eq!(c.ink[2 * 64 + 32], 0.0, "far from the stroke stays blank");
        assert!(c.ink[16 * 64 + 5] < c.ink[16 * 64 + 32], "ends are tapered");
        let r = resample(&[[0.0, 0.0], [3.0, 0.0]], 0.6);
        assert_eq!(r.len(), 6);
        assert!((length(&r) - 3.0).abs() < 1e-9);
        c.stroke(&[[f64::NAN, 0.0], [1.0, 1.0]], &pen, &mut rng); // ignored, no panic
    }
}

//! Pages without a figure, for the detector's "no figure" rate: blank paper, a page of notes
//! (rows of invented glyphs, handwritten or printed) and a clutter page (a doodle page or a
//! UI mock-up: lines, curves, boxes, circles, scribbles, arrows, light fills). Lengths scale
//! with the page: `pu` is 1 at a 512 px short side. None of this is the sketch renderer's
//! training background ([`sketchbody::render::sketch::background`]); the glyphs, layouts and fills
//! are this module's own.

use std::f64::consts::{PI, TAU};
use std::str::FromStr;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::filters::Rgb;
use super::{check_pixels, to_image};
use sketchbody::error::{Error, Result};
use sketchbody::image::RgbImage;
use sketchbody::render::sketch::canvas::{Canvas, Pen};
use sketchbody::render::sketch::paper::compose;

/// Stream tag mixed into the seed (ASCII "negpage").
const STREAM: u64 = 0x006E_6567_7061_6765;

/// The kind of figure-free page.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NegativePage {
    /// Paper only: tone, grain and sometimes a faint smudge; no pixel darker than gray 215.
    Blank,
    /// A page of notes: rows of glyph-like marks in words and paragraphs, handwritten (slanted,
    /// wobbly) or printed (upright, even), sometimes on ruled paper.
    Text,
    /// Doodles or a UI mock-up: straight lines, curves, boxes, circles, scribbles, arrows and
    /// light colour fills spread over the page, with nothing shaped like a person.
    Clutter,
}

impl NegativePage {
    /// Every kind, in benchmark order.
    pub const ALL: [NegativePage; 3] = [NegativePage::Blank, NegativePage::Text, NegativePage::Clutter];

    /// Short name: "blank", "text", "clutter".
    pub fn name(self) -> &'static str {
        match self {
            NegativePage::Blank => "blank",
            NegativePage::Text => "text",
            NegativePage::Clutter => "clutter",
        }
    }
}

impl std::fmt::Display for NegativePage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for NegativePage {
    type Err = Error;
    /// Parses a [`NegativePage::name`] (ASCII case ignored).
    fn from_str(s: &str) -> Result<Self> {
        NegativePage::ALL.into_iter().find(|k| k.name().eq_ignore_ascii_case(s)).ok_or_else(|| Error::OutOfRange {
            name: "kind",
            detail: format!("{s:?} is not one of blank, text, clutter"),
        })
    }
}

/// A `width`×`height` RGB page of `kind`, the same bytes for the same `seed`. Errors: empty
/// sizes, sides over 16384 px, more than 64 Mpx.
pub fn negative_page(kind: NegativePage, width: usize, height: usize, seed: u64) -> Result<RgbImage> {
    check_pixels(width, height)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ STREAM ^ ((kind as u64) << 56));
    let mut page = Page::new(width, height, &mut rng);
    match kind {
        NegativePage::Blank => page.smudge(&mut rng),
        NegativePage::Text => text(&mut page, &mut rng),
        NegativePage::Clutter => clutter(&mut page, &mut rng),
    }
    to_image(width, height, &page.finish(&mut rng))
}

/// A page being drawn: light colour fills (multiplied), one pen's ink coverage and its colour.
struct Page {
    w: usize,
    h: usize,
    /// Scale: short side / 512 px (at least 0.25).
    pu: f64,
    fill: Vec<Rgb>,
    canvas: Canvas,
    ink: Rgb,
    tone: f64,
}

impl Page {
    fn new<R: Rng + ?Sized>(w: usize, h: usize, rng: &mut R) -> Page {
        let inks = [[0.18, 0.18, 0.2], [0.1, 0.14, 0.42], [0.06, 0.06, 0.07]];
        Page {
            w,
            h,
            pu: (w.min(h) as f64 / 512.0).max(0.25),
            fill: vec![[1.0; 3]; w * h],
            canvas: Canvas::new(w, h),
            ink: inks[rng.random_range(0..inks.len())],
            tone: rng.random_range(0.955..0.99),
        }
    }

    /// A faint soft smudge (darkening at most 6 %) somewhere, on six pages in ten.
    fn smudge<R: Rng + ?Sized>(&mut self, rng: &mut R) {
        if !rng.random_bool(0.6) {
            return;
        }
        let (cx, cy) = (rng.random_range(0.0..self.w as f64), rng.random_range(0.0..self.h as f64));
        let r = rng.random_range(20.0..90.0) * self.pu;
        let dark = rng.random_range(0.02..0.06) as f32;
        for (i, f) in self.fill.iter_mut().enumerate() {
            let d2 = ((i % self.w) as f64 - cx).powi(2) + ((i / self.w) as f64 - cy).powi(2);
            let k = 1.0 - dark * (-d2 / (2.0 * r * r)).exp() as f32;
            *f = f.map(|v| v * k);
        }
    }

    /// Paints the inside of `poly` (even-odd rule at pixel centres) with `colour`, keeping the
    /// darker value per channel where fills overlap (overlaps never darken further).
    fn fill_polygon(&mut self, poly: &[[f64; 2]], colour: Rgb) {
        if poly.len() < 3 {
            return;
        }
        let (y0, y1) = poly.iter().fold((f64::MAX, f64::MIN), |m, p| (m.0.min(p[1]), m.1.max(p[1])));
        let ys = (y0.floor().max(0.0) as usize)..(y1.ceil().clamp(0.0, self.h as f64) as usize);
        for y in ys {
            let yc = y as f64 + 0.5;
            let mut xs: Vec<f64> = Vec::new();
            for k in 0..poly.len() {
                let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
                if (a[1] <= yc) != (b[1] <= yc) {
                    xs.push(a[0] + (yc - a[1]) / (b[1] - a[1]) * (b[0] - a[0]));
                }
            }
            xs.sort_by(|a, b| a.total_cmp(b));
            for span in xs.chunks_exact(2) {
                let x0 = (span[0] - 0.5).ceil().max(0.0) as usize;
                let x1 = ((span[1] - 0.5).floor() + 1.0).clamp(0.0, self.w as f64) as usize;
                for f in &mut self.fill[y * self.w + x0.min(self.w)..y * self.w + x1.max(x0.min(self.w))] {
                    *f = [f[0].min(colour[0]), f[1].min(colour[1]), f[2].min(colour[2])];
                }
            }
        }
    }

    /// Paper grain under fills and ink: `paper · (fill · (1 − c) + c · ink)` for coverage `c`.
    fn finish<R: Rng + ?Sized>(self, rng: &mut R) -> Vec<Rgb> {
        let paper = compose(&Canvas::new(self.w, self.h), self.tone, 0.025, 0.0, rng);
        let warm = [1.0, 0.995, 0.975];
        (0..self.w * self.h)
            .map(|i| {
                let (p, c, f) = (paper[i] as f32 / 255.0, self.canvas.ink[i], self.fill[i]);
                [0, 1, 2].map(|k| p * warm[k] * (f[k] * (1.0 - c) + c * self.ink[k]))
            })
            .collect()
    }
}

/// One invented glyph: strokes in a cell of x-height 1 (x right, y up from the baseline).
type Glyph = Vec<Vec<[f64; 2]>>;

/// An alphabet of 24 random glyphs of 1–2 strokes each (arcs, hooks, bars), some with
/// ascenders or descenders.
fn alphabet<R: Rng + ?Sized>(rng: &mut R) -> Vec<(Glyph, f64)> {
    (0..24)
        .map(|_| {
            let width = rng.random_range(0.45..0.85);
            let top = if rng.random_bool(0.25) { 1.8 } else { 1.0 };
            let bottom = if rng.random_bool(0.12) { -0.7 } else { 0.0 };
            let strokes = (0..rng.random_range(1..=2))
                .map(|_| {
                    if rng.random_bool(0.5) {
                        let (c, r) = ([width / 2.0, 0.5], rng.random_range(0.3..0.5));
                        let (a0, sweep) = (rng.random_range(0.0..TAU), rng.random_range(PI * 0.6..TAU * 0.95));
                        (0..=10)
                            .map(|i| {
                                let a = a0 + sweep * i as f64 / 10.0;
                                [c[0] + r * width * a.cos() * 1.2, c[1] + r * a.sin()]
                            })
                            .collect()
                    } else {
                        let n = rng.random_range(2..=3);
                        (0..n)
                            .map(|_| [rng.random_range(0.0..width), rng.random_range(bottom..top)])
                            .collect::<Vec<[f64; 2]>>()
                    }
                })
                .collect();
            (strokes, width)
        })
        .collect()
}

/// A page of notes: margins, rows of words of glyphs, ragged line ends and paragraph breaks.
fn text<R: Rng + ?Sized>(page: &mut Page, rng: &mut R) {
    let (w, h, pu) = (page.w as f64, page.h as f64, page.pu);
    let hand = rng.random_bool(0.6);
    let xh = rng.random_range(6.0..9.0) * pu;
    let row = xh * rng.random_range(2.6..3.4);
    let slant = if hand { rng.random_range(0.1..0.35) } else { 0.0 };
    let pen = if hand {
        Pen { width: rng.random_range(1.1..1.8) * pu, ink: 0.9, wobble: 0.25 * pu, jitter: 0.35, taper: 0.15 }
    } else {
        Pen { width: 1.3 * pu, ink: 0.95, wobble: 0.0, jitter: 0.0, taper: 0.0 }
    };
    let glyphs = alphabet(rng);
    let (left, right) = (rng.random_range(0.06..0.16) * w, w - rng.random_range(0.05..0.1) * w);
    let mut y = rng.random_range(0.06..0.12) * h + row;
    if rng.random_bool(0.4) {
        // Ruled paper: light blue lines under every row.
        let mut ry = y + 0.15 * xh;
        while ry < h {
            page.fill_polygon(&[[0.0, ry], [w, ry], [w, ry + 0.9 * pu], [0.0, ry + 0.9 * pu]], [0.88, 0.93, 1.0]);
            ry += row;
        }
    }
    let bottom = h - rng.random_range(0.05..0.1) * h;
    while y < bottom {
        let indent = if rng.random_bool(0.15) { 2.5 * xh } else { 0.0 };
        let end = if rng.random_bool(0.2) { left + rng.random_range(0.2..0.9) * (right - left) } else { right };
        let mut x = left + indent;
        let drift = rng.random_range(-0.02..0.02);
        while x < end - 2.0 * xh {
            let letters = rng.random_range(1..=8);
            for _ in 0..letters {
                let (glyph, gw) = &glyphs[rng.random_range(0..glyphs.len())];
                let jitter = if hand { xh * 0.08 } else { 0.0 };
                let base = y + (x - left) * drift;
                for stroke in glyph {
                    let pts: Vec<[f64; 2]> = stroke
                        .iter()
                        .map(|p| {
                            let (gx, gy) = (p[0] + slant * p[1], p[1]);
                            [x + gx * xh + rng.random_range(-1.0..=1.0) * jitter, base - gy * xh]
                        })
                        .collect();
                    page.canvas.stroke(&pts, &pen, rng);
                }
                x += (gw + 0.2) * xh;
            }
            x += xh * rng.random_range(0.7..1.2);
        }
        y += row * if rng.random_bool(0.1) { 2.0 } else { 1.0 };
    }
}

/// A smooth open curve of `n` points from `p`: heading `a` plus a sum of two slow sines.
fn wavy<R: Rng + ?Sized>(p: [f64; 2], a: f64, len: f64, rng: &mut R) -> Vec<[f64; 2]> {
    let (f1, f2, p1, p2) = (
        rng.random_range(0.5..2.0),
        rng.random_range(2.0..5.0),
        rng.random_range(0.0..TAU),
        rng.random_range(0.0..TAU),
    );
    let (a1, a2) = (rng.random_range(0.0..1.0), rng.random_range(0.0..0.4));
    let mut q = p;
    let mut pts = vec![q];
    for i in 1..=40 {
        let t = i as f64 / 40.0;
        let head = a + a1 * (TAU * f1 * t + p1).sin() + a2 * (TAU * f2 * t + p2).sin();
        q = [q[0] + head.cos() * len / 40.0, q[1] + head.sin() * len / 40.0];
        pts.push(q);
    }
    pts
}

/// An ellipse of radii `r` around `c`, rotated by `t`, as a closed polyline of 40 segments.
fn oval(c: [f64; 2], r: [f64; 2], t: f64) -> Vec<[f64; 2]> {
    (0..=40)
        .map(|i| {
            let a = TAU * i as f64 / 40.0;
            let (x, y) = (r[0] * a.cos(), r[1] * a.sin());
            [c[0] + x * t.cos() - y * t.sin(), c[1] + x * t.sin() + y * t.cos()]
        })
        .collect()
}

/// A box with corners `p` and `p + s`, as a closed polyline.
fn rect(p: [f64; 2], s: [f64; 2]) -> Vec<[f64; 2]> {
    vec![p, [p[0] + s[0], p[1]], [p[0] + s[0], p[1] + s[1]], [p[0], p[1] + s[1]], p]
}

/// A pastel fill colour, luminance at least 0.92, so a fill stays lighter than the ink level
/// on the darkest paper.
fn pastel<R: Rng + ?Sized>(rng: &mut R) -> Rgb {
    let hue = rng.random_range(0.0..TAU);
    [0.0, 2.1, 4.2].map(|o| (0.955 + 0.04 * (hue + o).cos()) as f32)
}

/// A doodle page or, on four pages in ten, a UI mock-up.
fn clutter<R: Rng + ?Sized>(page: &mut Page, rng: &mut R) {
    let (w, h, pu) = (page.w as f64, page.h as f64, page.pu);
    let pen = Pen { width: rng.random_range(1.2..2.2) * pu, ink: 0.9, wobble: 0.4 * pu, jitter: 0.3, taper: 0.1 };
    if rng.random_bool(0.4) {
        mockup(page, &pen, rng);
        return;
    }
    for _ in 0..rng.random_range(14..32) {
        let c = [rng.random_range(0.0..w), rng.random_range(0.0..h)];
        let size = rng.random_range(15.0..110.0) * pu;
        match rng.random_range(0..8) {
            0 => {
                let a = rng.random_range(0.0..TAU);
                page.canvas.stroke(&[c, [c[0] + a.cos() * size * 1.5, c[1] + a.sin() * size * 1.5]], &pen, rng);
            }
            1 => page.canvas.stroke(&wavy(c, rng.random_range(0.0..TAU), size * 2.0, rng), &pen, rng),
            2 => {
                let s = [size, size * rng.random_range(0.4..1.5)];
                if rng.random_bool(0.4) {
                    page.fill_polygon(&rect(c, s), pastel(rng));
                }
                page.canvas.stroke(&rect(c, s), &pen, rng);
            }
            3 => {
                let poly = oval(c, [size * 0.5, size * rng.random_range(0.3..0.6)], rng.random_range(0.0..PI));
                if rng.random_bool(0.4) {
                    page.fill_polygon(&poly, pastel(rng));
                }
                page.canvas.stroke(&poly, &pen, rng);
            }
            4 => {
                // Scribble: a zigzag or a run of loops.
                let loops = rng.random_bool(0.5);
                let r = size * 0.15;
                let n = if loops { 60 } else { rng.random_range(10..22) };
                let pts: Vec<[f64; 2]> = (0..n)
                    .map(|i| {
                        let t = i as f64 / n as f64;
                        if loops {
                            let a = t * TAU * 6.0;
                            [c[0] + t * size + r * a.cos(), c[1] + r * 0.8 * a.sin()]
                        } else {
                            [c[0] + t * size, c[1] + if i % 2 == 0 { r } else { -r }]
                        }
                    })
                    .collect();
                page.canvas.stroke(&pts, &Pen { width: pen.width * 0.7, ..pen }, rng);
            }
            5 => {
                // Arrow.
                let a = rng.random_range(0.0..TAU);
                let tip = [c[0] + a.cos() * size, c[1] + a.sin() * size];
                page.canvas.stroke(&[c, tip], &pen, rng);
                for s in [-1.0, 1.0] {
                    let b = a + PI - s * 0.45;
                    page.canvas.stroke(
                        &[tip, [tip[0] + b.cos() * 0.2 * size, tip[1] + b.sin() * 0.2 * size]],
                        &pen,
                        rng,
                    );
                }
            }
            6 => {
                // A filled triangle in a light colour, outlined.
                let poly: Vec<[f64; 2]> = (0..3)
                    .map(|k| {
                        let a = rng.random_range(0.0..TAU) * 0.2 + k as f64 * TAU / 3.0;
                        [c[0] + a.cos() * size * 0.5, c[1] + a.sin() * size * 0.5]
                    })
                    .collect();
                page.fill_polygon(&poly, pastel(rng));
                let mut closed = poly.clone();
                closed.push(poly[0]);
                page.canvas.stroke(&closed, &pen, rng);
            }
            _ => {
                // A small dark dot, as a bullet or a pupil-less eye of a doodle.
                let r = rng.random_range(1.5..3.5) * pu;
                page.canvas.disc(c[0], c[1], r, 0.9);
            }
        }
    }
}

/// A UI mock-up: a header bar, a column of list rows with placeholder text lines, and a grid of
/// image placeholders (boxes with a cross), with light fills on some.
fn mockup<R: Rng + ?Sized>(page: &mut Page, pen: &Pen, rng: &mut R) {
    let (w, h, pu) = (page.w as f64, page.h as f64, page.pu);
    let m = rng.random_range(0.04..0.08) * w;
    let bar = rng.random_range(0.06..0.1) * h;
    page.fill_polygon(&rect([m, m], [w - 2.0 * m, bar]), pastel(rng));
    page.canvas.stroke(&rect([m, m], [w - 2.0 * m, bar]), pen, rng);
    let thin = Pen { width: pen.width * 0.7, ..*pen };
    let split = rng.random_range(0.3..0.45) * w;
    let mut y = m + bar + 12.0 * pu;
    while y + 30.0 * pu < h - m {
        let rh = rng.random_range(26.0..44.0) * pu;
        page.canvas.stroke(&rect([m, y], [split - m - 6.0 * pu, rh]), &thin, rng);
        for k in 0..2 {
            let ly = y + rh * (0.35 + 0.3 * k as f64);
            let len = rng.random_range(0.3..0.8) * (split - m - 20.0 * pu);
            page.canvas.stroke(&[[m + 8.0 * pu, ly], [m + 8.0 * pu + len, ly]], &thin, rng);
        }
        y += rh + rng.random_range(6.0..14.0) * pu;
    }
    let (cols, rows) = (rng.random_range(2..=3), rng.random_range(2..=4));
    let (gx, gy) = (split + 6.0 * pu, m + bar + 12.0 * pu);
    let (cw, ch) = ((w - m - gx) / cols as f64, (h - m - gy) / rows as f64);
    for r in 0..rows {
        for c in 0..cols {
            let p = [gx + c as f64 * cw + 4.0 * pu, gy + r as f64 * ch + 4.0 * pu];
            let s = [cw - 8.0 * pu, ch - 8.0 * pu];
            if rng.random_bool(0.3) {
                page.fill_polygon(&rect(p, s), pastel(rng));
            }
            page.canvas.stroke(&rect(p, s), pen, rng);
            if rng.random_bool(0.6) {
                page.canvas.stroke(&[p, [p[0] + s[0], p[1] + s[1]]], &thin, rng);
                page.canvas.stroke(&[[p[0] + s[0], p[1]], [p[0], p[1] + s[1]]], &thin, rng);
            }
        }
    }
}

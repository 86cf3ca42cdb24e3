//! Art styles for the synthetic sketches (issue 15, item 5): the same figure and lines as a
//! plain sketch, painted the way artists finish character drawings, so that the sketch detector
//! trains on drawings closer to real art. An [`ArtStyle`] combines
//!
//! - a fill of the figure ([`Fill`]): flat tones per region (skin, top, bottom, shoes, hair), cel
//!   shading (the same with a hard shadow tone where the depth-buffer normal faces away from a
//!   light), manga screen tones (halftone dots in the shadow and on some clothes), or watercolour
//!   washes (soft, misregistered, unevenly pigmented tones with darker pooled edges and lighter
//!   lines);
//! - thick ink outlines (lines and the silhouette dilated to 2–5 px of full black);
//! - clothes and hair masses (a hair shape over the head, optionally long, and a skirt or coat
//!   from the hips), outlined and filled;
//! - stylised proportions ([`Build`]): chibi (big head, short limbs) or heroic (small head, long
//!   legs, broad shoulders);
//! - textured paper (tinted, fibrous, with laid lines).
//!
//! Regions come from the nearest bone of the projected skeleton, so they need no extra mesh
//! data. Every random choice comes from the caller's generator, so a style and a seed always
//! give the same image.

use rand::Rng;

use super::canvas::{Canvas, Pen};
use super::contours::DepthView;
use super::paper::shade_at;
use crate::body::proportions::Proportions;
use crate::skeleton::{joint, BONES, NUM_JOINTS};

/// How the figure is painted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fill {
    /// Lines only (with thick ink or masses this is an ink drawing).
    Lines,
    /// One flat tone per region.
    Flat,
    /// Flat tones with a hard shadow tone (cel shading).
    Cel,
    /// Halftone dots in the shadow and on some regions (manga screen tone).
    ScreenTone,
    /// Soft, uneven washes with pooled edges.
    Watercolour,
}

impl Fill {
    /// Every fill, for random choice.
    pub const ALL: [Fill; 5] = [Fill::Lines, Fill::Flat, Fill::Cel, Fill::ScreenTone, Fill::Watercolour];
}

/// Stylised body proportions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Build {
    /// The renderer's own random proportions.
    Natural,
    /// Head 1.5–2× (about the neck), legs 0.55–0.75×, arms 0.6–0.8×, torso 0.7–0.9×.
    Chibi,
    /// Head 0.7–0.85×, legs 1.1–1.3×, shoulders 1.3–1.6×, arms 1.0–1.15×, torso 1.0–1.15×.
    Heroic,
}

/// One art style.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArtStyle {
    /// How the figure is painted.
    pub fill: Fill,
    /// Thick black outlines.
    pub thick_ink: bool,
    /// Hair and clothes masses.
    pub masses: bool,
    /// Proportions.
    pub build: Build,
    /// Textured paper.
    pub textured_paper: bool,
}

impl ArtStyle {
    /// A random style: fill uniform over [`Fill::ALL`], thick ink 40 % (always with
    /// [`Fill::Lines`] unless it has masses), masses 50 %, chibi 20 % / heroic 20 %, textured paper 40 %.
    pub fn random<R: Rng + ?Sized>(rng: &mut R) -> ArtStyle {
        let fill = Fill::ALL[rng.random_range(0..Fill::ALL.len())];
        let masses = rng.random_bool(0.5);
        let thick_ink = rng.random_bool(0.4) || (fill == Fill::Lines && !masses);
        let build = match rng.random_range(0..10) {
            0 | 1 => Build::Chibi,
            2 | 3 => Build::Heroic,
            _ => Build::Natural,
        };
        ArtStyle { fill, thick_ink, masses, build, textured_paper: rng.random_bool(0.4) }
    }

    /// Proportions replacing the renderer's, `None` for [`Build::Natural`].
    pub fn proportions<R: Rng + ?Sized>(&self, rng: &mut R) -> Option<Proportions> {
        match self.build {
            Build::Natural => None,
            Build::Chibi => Some(Proportions {
                head: rng.random_range(1.5..2.0),
                legs: rng.random_range(0.55..0.75),
                arms: rng.random_range(0.6..0.8),
                torso: rng.random_range(0.7..0.9),
                shoulders: rng.random_range(0.8..1.0),
            }),
            Build::Heroic => Some(Proportions {
                head: rng.random_range(0.7..0.85),
                legs: rng.random_range(1.1..1.3),
                arms: rng.random_range(1.0..1.15),
                torso: rng.random_range(1.0..1.15),
                shoulders: rng.random_range(1.3..1.6),
            }),
        }
    }
}

/// Paint regions.
const SKIN: usize = 0;
const TOP: usize = 1;
const BOTTOM: usize = 2;
const SHOES: usize = 3;
const HAIR: usize = 4;
const NUM_REGIONS: usize = 5;

/// What [`paint`] needs of the rendered figure.
pub struct FigureView<'a> {
    /// Depth buffer (body pixels are finite).
    pub depth: DepthView<'a>,
    /// Depth-buffer scale, pixels per metre.
    pub scale: f64,
    /// Projected joints, pixels.
    pub joints: &'a [[f64; 2]; NUM_JOINTS],
    /// Image length unit (1 at 512²).
    pub unit: f64,
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = (dx * dx + dy * dy).max(1e-9);
    let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0);
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}

/// Region of a body pixel: the nearest bone's (forearms skin or sleeve by `sleeves`), shoes near
/// the ankles.
fn region_of(p: [f64; 2], j: &[[f64; 2]; NUM_JOINTS], sleeves: bool, foot_r: f64) -> usize {
    for a in [joint::R_ANKLE, joint::L_ANKLE] {
        if (p[0] - j[a][0]).hypot(p[1] - j[a][1]) < foot_r && p[1] > j[a][1] - foot_r * 0.3 {
            return SHOES;
        }
    }
    let mut best = (f64::INFINITY, 0usize);
    for (b, &(s, c)) in BONES.iter().enumerate() {
        let d = segment_distance(p, j[s], j[c]);
        if d < best.0 {
            best = (d, b);
        }
    }
    match best.1 {
        0 => SKIN,
        3 | 6 if !sleeves => SKIN,
        1..=7 => TOP,
        _ => BOTTOM,
    }
}

/// Inside test of a polygon (even-odd).
fn inside(poly: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut c = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + n - 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0] {
            c = !c;
        }
    }
    c
}

/// The hair and clothes masses: (region, closed outline) pairs.
fn masses<R: Rng + ?Sized>(j: &[[f64; 2]; NUM_JOINTS], rng: &mut R) -> Vec<(usize, Vec<[f64; 2]>)> {
    let (h, n) = (j[joint::HEAD], j[joint::NECK]);
    let (ux, uy) = (h[0] - n[0], h[1] - n[1]);
    let l = ux.hypot(uy).max(1.0);
    let (ux, uy) = (ux / l, uy / l);
    let (px, py) = (-uy, ux);
    let mut out = Vec::new();
    // Hair: a cap over the top of the head (flat below its centre, so the face stays paper),
    // optionally with a curtain hanging to the neck.
    let c = [h[0] + ux * 0.3 * l, h[1] + uy * 0.3 * l];
    let (ra, rb) = (l * rng.random_range(0.75..0.9), l * rng.random_range(0.6..0.8));
    let long = rng.random_bool(0.4);
    let hair: Vec<[f64; 2]> = (0..40)
        .map(|k| {
            let t = k as f64 / 40.0 * std::f64::consts::TAU;
            let (cs, sn) = (t.cos(), t.sin());
            // Below the centre (sn < 0 along the head axis) the cap is flat, or a long curtain
            // hangs at the sides.
            let along = if sn >= 0.0 {
                sn
            } else if long && cs.abs() > 0.6 {
                sn * 1.6
            } else {
                sn * 0.3
            };
            [c[0] + px * rb * cs + ux * ra * along, c[1] + py * rb * cs + uy * ra * along]
        })
        .collect();
    out.push((HAIR, hair));
    if rng.random_bool(0.5) {
        // A skirt or coat: a trapezoid from the hips down past the knees, widening.
        let (rh, lh) = (j[joint::R_HIP], j[joint::L_HIP]);
        let (rk, lk) = (j[joint::R_KNEE], j[joint::L_KNEE]);
        let top = rng.random_range(-0.1..0.1);
        let len = rng.random_range(0.6..1.3);
        let flare = rng.random_range(1.2..1.8);
        let mid_h = [(rh[0] + lh[0]) / 2.0, (rh[1] + lh[1]) / 2.0];
        let mid_k = [(rk[0] + lk[0]) / 2.0, (rk[1] + lk[1]) / 2.0];
        let down = [mid_k[0] - mid_h[0], mid_k[1] - mid_h[1]];
        let half = ((rh[0] - lh[0]).hypot(rh[1] - lh[1]) * 0.75).max(0.15 * l);
        let at = |t: f64, s: f64, w: f64| [mid_h[0] + down[0] * t + s * w, mid_h[1] + down[1] * t];
        out.push((
            if rng.random_bool(0.5) { BOTTOM } else { TOP },
            vec![at(top, -1.0, half), at(top, 1.0, half), at(len, 1.0, half * flare), at(len, -1.0, half * flare)],
        ));
    }
    out
}

/// Grayscale tone per region for this drawing.
fn palette<R: Rng + ?Sized>(rng: &mut R) -> [f64; NUM_REGIONS] {
    [
        rng.random_range(0.78..0.96),
        rng.random_range(0.25..0.9),
        rng.random_range(0.15..0.85),
        rng.random_range(0.1..0.5),
        rng.random_range(0.05..0.6),
    ]
}

/// Separable box blur with radius `r` (clamped borders).
fn box_blur(v: &[f32], w: usize, h: usize, r: usize) -> Vec<f32> {
    let pass = |src: &[f32], step: usize, len: usize, lines: usize, stride: usize| {
        let mut out = vec![0f32; src.len()];
        for line in 0..lines {
            let at = |k: usize| src[line * stride + k * step];
            for k in 0..len {
                let (a, b) = (k.saturating_sub(r), (k + r).min(len - 1));
                out[line * stride + k * step] = (a..=b).map(at).sum::<f32>() / (b - a + 1) as f32;
            }
        }
        out
    };
    let t = pass(v, 1, w, h, w);
    pass(&t, w, h, w, 1)
}

/// Paints the figure of `fig` in `art` over the line drawing on `canvas`: adds mass outlines
/// (`pen`) and thick ink to the canvas and returns the paint layer, a brightness factor per
/// pixel (1 = unpainted paper).
pub fn paint<R: Rng + ?Sized>(
    canvas: &mut Canvas,
    fig: &FigureView<'_>,
    art: &ArtStyle,
    pen: &Pen,
    rng: &mut R,
) -> Vec<f32> {
    let (w, h) = (canvas.width, canvas.height);
    let tones = palette(rng);
    let sleeves = rng.random_bool(0.5);
    let light = {
        let v: [f64; 3] = [if rng.random_bool(0.5) { -0.5 } else { 0.5 }, 0.55, 0.7];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / n, v[1] / n, v[2] / n]
    };
    let head_len = {
        let (a, b) = (fig.joints[joint::HEAD], fig.joints[joint::NECK]);
        (a[0] - b[0]).hypot(a[1] - b[1]).max(4.0)
    };
    let mass = if art.masses { masses(fig.joints, rng) } else { Vec::new() };
    let solid_hair = art.fill == Fill::Lines && rng.random_bool(0.5);
    // Region of every pixel (NUM_REGIONS = paper) and the figure mask.
    let mut region = vec![NUM_REGIONS as u8; w * h];
    for y in 0..h {
        for x in 0..w {
            let p = [x as f64 + 0.5, y as f64 + 0.5];
            let body = fig.depth.depth[y * w + x] != f32::NEG_INFINITY;
            let r = mass
                .iter()
                .rev()
                .find(|(_, poly)| inside(poly, p))
                .map(|m| m.0)
                .or_else(|| body.then(|| region_of(p, fig.joints, sleeves, 0.45 * head_len)));
            if let Some(r) = r {
                region[y * w + x] = r as u8;
            }
        }
    }
    for (_, poly) in &mass {
        let mut closed = poly.clone();
        closed.push(poly[0]);
        canvas.stroke(&closed, pen, rng);
    }
    let mut layer = vec![1f32; w * h];
    let shade_thr = rng.random_range(0.35..0.55);
    let dark = rng.random_range(0.55..0.75);
    let pitch = rng.random_range(4.0..7.0) * fig.unit;
    let toned = [rng.random_bool(0.3), rng.random_bool(0.5), rng.random_bool(0.5), true, true];
    for y in 0..h {
        for x in 0..w {
            let k = y * w + x;
            let r = region[k] as usize;
            if r == NUM_REGIONS {
                continue;
            }
            let shade = shade_at(&fig.depth, fig.scale, x, y, light).unwrap_or(0.0);
            layer[k] = match art.fill {
                Fill::Lines => {
                    if r == HAIR && solid_hair {
                        0.08
                    } else {
                        1.0
                    }
                }
                Fill::Flat => tones[r] as f32,
                Fill::Cel => (tones[r] * if shade > shade_thr { dark } else { 1.0 }) as f32,
                Fill::ScreenTone => {
                    // Dots on a 45° grid; radius grows with the shade (and on toned regions).
                    let (u, v) = ((x as f64 + y as f64) / pitch, (x as f64 - y as f64) / pitch);
                    let d = ((u - u.round()).powi(2) + (v - v.round()).powi(2)).sqrt();
                    let cover = if shade > shade_thr {
                        0.42
                    } else if toned[r] {
                        0.28
                    } else {
                        0.0
                    };
                    if d < cover || r == HAIR {
                        0.12
                    } else {
                        1.0
                    }
                }
                Fill::Watercolour => 1.0,
            };
        }
    }
    if art.fill == Fill::Watercolour {
        // Washes: the region tones misregistered by a few px, blurred, with pigment pooling at
        // their edges and low-frequency unevenness.
        let (ox, oy) =
            ((rng.random_range(-4.0..4.0) * fig.unit) as i64, (rng.random_range(-4.0..4.0) * fig.unit) as i64);
        let mut wash = vec![0f32; w * h];
        let mut cover = vec![0f32; w * h];
        for y in 0..h as i64 {
            for x in 0..w as i64 {
                let (sx, sy) = (x - ox, y - oy);
                if sx < 0 || sy < 0 || sx >= w as i64 || sy >= h as i64 {
                    continue;
                }
                let r = region[sy as usize * w + sx as usize] as usize;
                if r < NUM_REGIONS {
                    let shade = shade_at(&fig.depth, fig.scale, sx as usize, sy as usize, light).unwrap_or(0.0);
                    wash[y as usize * w + x as usize] = (1.0 - tones[r] * 0.9 + 0.15 * shade) as f32;
                    cover[y as usize * w + x as usize] = 1.0;
                }
            }
        }
        let rad = ((2.0 * fig.unit).round() as usize).max(1);
        let wash = box_blur(&wash, w, h, rad);
        let cover = box_blur(&cover, w, h, rad * 2);
        const G: usize = 6;
        let grid: Vec<f64> = (0..(G + 1) * (G + 1)).map(|_| rng.random_range(0.7..1.2)).collect();
        for y in 0..h {
            for x in 0..w {
                let k = y * w + x;
                let gx = x as f64 / w as f64 * G as f64;
                let gy = y as f64 / h as f64 * G as f64;
                let (i, jy) = (gx as usize, gy as usize);
                let g = grid[jy * (G + 1) + i];
                let edge = 1.0 + 1.2 * (1.0 - (2.0 * cover[k] - 1.0).abs()) * (cover[k] > 0.05) as u8 as f32;
                let pigment = (wash[k] * g as f32 * edge).clamp(0.0, 0.9);
                layer[k] = 1.0 - pigment;
            }
        }
        // Lighter, brush-like lines.
        let lighten = rng.random_range(0.5..0.85) as f32;
        for a in &mut canvas.ink {
            *a *= lighten;
        }
    }
    if art.thick_ink {
        // The silhouette and the lines, dilated and darkened.
        for y in 1..h.saturating_sub(1) {
            for x in 1..w.saturating_sub(1) {
                let k = y * w + x;
                let fg = |k: usize| region[k] as usize != NUM_REGIONS;
                if fg(k) && (!fg(k - 1) || !fg(k + 1) || !fg(k - w) || !fg(k + w)) {
                    canvas.ink[k] = 1.0;
                }
            }
        }
        let r = ((rng.random_range(0.8..2.2) * fig.unit).round() as i64).max(1);
        let src = canvas.ink.clone();
        for y in 0..h as i64 {
            for x in 0..w as i64 {
                let mut m = 0f32;
                for dy in -r..=r {
                    for dx in -r..=r {
                        let (sx, sy) = (x + dx, y + dy);
                        if dx * dx + dy * dy <= r * r && sx >= 0 && sy >= 0 && sx < w as i64 && sy < h as i64 {
                            m = m.max(src[sy as usize * w + sx as usize]);
                        }
                    }
                }
                canvas.ink[y as usize * w + x as usize] = (m * 1.6).min(1.0);
            }
        }
    }
    layer
}

/// Textured paper under the paint and ink: tint `tone`, fibres (grain and low-frequency
/// mottling) of strength `noise`, faint laid lines when `textured`. Returns 8-bit gray pixels.
pub fn compose<R: Rng + ?Sized>(
    canvas: &Canvas,
    layer: &[f32],
    tone: f64,
    noise: f64,
    textured: bool,
    rng: &mut R,
) -> Vec<u8> {
    let (w, h) = (canvas.width, canvas.height);
    let (tone, noise) =
        if textured { (rng.random_range(0.8..0.97), rng.random_range(0.03..0.09)) } else { (tone, noise) };
    let laid = if textured { rng.random_range(0.01..0.04) } else { 0.0 };
    let period = rng.random_range(5.0..10.0);
    const G: usize = 16;
    let grid: Vec<f64> = (0..(G + 1) * (G + 1)).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let (i, j) = ((x * G / w.max(1)).min(G - 1), (y * G / h.max(1)).min(G - 1));
            let mottle = grid[j * (G + 1) + i];
            let grain: f64 = rng.random_range(-1.0..1.0);
            let lines = laid * ((y as f64 / period * std::f64::consts::TAU).sin());
            let paper = (tone + noise * (0.5 * mottle + 0.5 * grain) + lines).clamp(0.0, 1.0);
            let k = y * w + x;
            let v = paper * layer[k] as f64 * (1.0 - canvas.ink[k] as f64);
            out.push((255.0 * v).round().clamp(0.0, 255.0) as u8);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_follow_the_skeleton_and_polygons_contain_their_centre() {
        let j: [[f64; 2]; NUM_JOINTS] = [
            [50.0, 10.0],
            [50.0, 25.0],
            [40.0, 27.0],
            [35.0, 45.0],
            [33.0, 60.0],
            [60.0, 27.0],
            [65.0, 45.0],
            [67.0, 60.0],
            [50.0, 60.0],
            [44.0, 60.0],
            [44.0, 80.0],
            [44.0, 100.0],
            [56.0, 60.0],
            [56.0, 80.0],
            [56.0, 100.0],
        ];
        assert_eq!(region_of([50.0, 12.0], &j, false, 5.0), SKIN);
        assert_eq!(region_of([50.0, 40.0], &j, false, 5.0), TOP);
        assert_eq!(region_of([34.0, 55.0], &j, false, 5.0), SKIN);
        assert_eq!(region_of([34.0, 55.0], &j, true, 5.0), TOP);
        assert_eq!(region_of([44.0, 72.0], &j, false, 5.0), BOTTOM);
        assert_eq!(region_of([44.0, 101.0], &j, false, 5.0), SHOES);
        let sq = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        assert!(inside(&sq, [5.0, 5.0]) && !inside(&sq, [11.0, 5.0]));
        let b = box_blur(&[0.0, 0.0, 3.0, 0.0, 0.0], 5, 1, 1);
        assert_eq!(b, vec![0.0, 1.0, 1.0, 1.0, 0.0]);
    }

    #[test]
    fn random_styles_cover_every_fill_and_build() {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let styles: Vec<ArtStyle> = (0..200).map(|_| ArtStyle::random(&mut rng)).collect();
        for f in Fill::ALL {
            assert!(styles.iter().any(|s| s.fill == f), "{f:?}");
        }
        for b in [Build::Natural, Build::Chibi, Build::Heroic] {
            assert!(styles.iter().any(|s| s.build == b), "{b:?}");
        }
        for s in &styles {
            if let Some(p) = s.proportions(&mut rng) {
                p.validate().unwrap();
            }
        }
    }
}

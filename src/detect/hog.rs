//! The 32-dimensional HOG of Felzenszwalb et al. (PAMI 2010), following the definitions of their
//! deformable-part-model code (`features.cc`): per-pixel gradients (central differences, the
//! colour channel with the largest magnitude), snapped to 18 signed orientations, bilinearly
//! voted into `sbin`-pixel cells; each cell normalised by the energies of its four 2x2 blocks,
//! clipped at 0.2; 18 contrast-sensitive + 9 insensitive orientation features, 4 texture
//! (gradient-energy) features and a truncation feature (0 here; 1 only in pyramid padding).
//! The output loses a one-cell border: (cells − 2) per axis.

use super::model::FEAT_DIM;

/// A planar floating-point image, values in 0..=255, 1 (gray) or 3 (RGB) channels.
#[derive(Clone, Debug, PartialEq)]
pub struct Planes {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// 1 or 3.
    pub channels: usize,
    /// `channels` planes of `width * height` values, row-major.
    pub data: Vec<f32>,
}

impl Planes {
    /// Plane `c`, row-major.
    pub fn plane(&self, c: usize) -> &[f32] {
        let n = self.width * self.height;
        &self.data[c * n..(c + 1) * n]
    }
}

/// A HOG feature map: `rows` x `cols` cells of [`FEAT_DIM`] values, row-major (y, x, feature).
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureMap {
    /// Cells down.
    pub rows: usize,
    /// Cells across.
    pub cols: usize,
    /// `rows * cols * FEAT_DIM` values.
    pub data: Vec<f32>,
}

impl FeatureMap {
    /// The features of cell (x, y).
    pub fn cell(&self, x: usize, y: usize) -> &[f32] {
        let i = (y * self.cols + x) * FEAT_DIM;
        &self.data[i..i + FEAT_DIM]
    }
}

const EPS: f64 = 0.0001;
const NORIENT: usize = 9;

/// Unit vectors of the 9 orientations i·π/9 (cos, sin).
fn orientations() -> [(f64, f64); NORIENT] {
    let mut u = [(0.0, 0.0); NORIENT];
    for (i, v) in u.iter_mut().enumerate() {
        let a = i as f64 * std::f64::consts::PI / 9.0;
        *v = (a.cos(), a.sin());
    }
    u
}

/// Per-pixel gradients of an image as the HOG uses them: for every interior pixel (1 ≤ x ≤
/// width − 2, 1 ≤ y ≤ height − 2) the orientation bin (0..18) and the magnitude of the central
/// difference of the channel with the largest one. Independent of the cell size, so the two
/// cell sizes of one pyramid image share it.
#[derive(Clone, Debug, PartialEq)]
pub struct Gradients {
    /// Image width, px.
    pub width: usize,
    /// Image height, px.
    pub height: usize,
    /// Orientation bin per pixel, row-major (border pixels 0).
    orient: Vec<u8>,
    /// Magnitude per pixel, row-major (border pixels 0).
    mag: Vec<f64>,
}

/// The gradients of `im` (see [`Gradients`]). Computed a row at a time with branch-free
/// selects (vectorisable); per pixel the same arithmetic and comparisons, in the same order, as
/// the plain loop of `features.cc`: the first channel of largest squared magnitude, then the
/// first orientation of largest |dot| (its contrast-sensitive bin when the dot is negative).
pub fn gradients(im: &Planes) -> Gradients {
    let (w, h) = (im.width, im.height);
    let mut orient = vec![0u8; w * h];
    let mut mag = vec![0f64; w * h];
    if w < 3 || h < 3 {
        return Gradients { width: w, height: h, orient, mag };
    }
    let uv = orientations();
    let n = w - 2;
    let (mut dx, mut dy, mut v) = (vec![0f64; n], vec![0f64; n], vec![0f64; n]);
    let (mut best, mut bo) = (vec![0f64; n], vec![0u64; n]);
    for sy in 1..h - 1 {
        v.fill(-1.0);
        for c in 0..im.channels {
            let p = im.plane(c);
            let (up, row, down) = (&p[(sy - 1) * w + 1..][..n], &p[sy * w..][..w], &p[(sy + 1) * w + 1..][..n]);
            let (left, right) = (&row[..n], &row[2..]);
            for ((((dx, dy), v), (&l, &r)), (&u, &d)) in
                dx.iter_mut().zip(dy.iter_mut()).zip(v.iter_mut()).zip(left.iter().zip(right)).zip(up.iter().zip(down))
            {
                let gx = (r - l) as f64;
                let gy = (d - u) as f64;
                let m = gx * gx + gy * gy;
                let take = m > *v;
                *dx = if take { gx } else { *dx };
                *dy = if take { gy } else { *dy };
                *v = if take { m } else { *v };
            }
        }
        best.fill(0.0);
        bo.fill(0);
        for (o, &(cu, su)) in uv.iter().enumerate() {
            let (o, o2) = (o as u64, (o + NORIENT) as u64);
            for (((b, k), &x), &y) in best.iter_mut().zip(bo.iter_mut()).zip(&dx).zip(&dy) {
                let dot = cu * x + su * y;
                // |dot| > b picks dot's sign: positive -> o, negative -> o + 9 (the plain loop
                // tests dot > b first, and both cannot hold since b ≥ 0).
                let (gt, lt) = (dot > *b, -dot > *b);
                *b = if gt | lt { dot.abs() } else { *b };
                *k = if gt {
                    o
                } else if lt {
                    o2
                } else {
                    *k
                };
            }
        }
        let (orow, mrow) = (&mut orient[sy * w + 1..][..n], &mut mag[sy * w + 1..][..n]);
        for i in 0..n {
            orow[i] = bo[i] as u8;
            mrow[i] = v[i].sqrt();
        }
    }
    Gradients { width: w, height: h, orient, mag }
}

/// Computes the HOG feature map of `im` with cells of `sbin` pixels. The cell grid has
/// round(height / sbin) x round(width / sbin) cells; the map has two fewer per axis (empty when
/// that is ≤ 0).
pub fn hog(im: &Planes, sbin: usize) -> FeatureMap {
    hog_from_gradients(&gradients(im), sbin)
}

/// [`hog`] from precomputed [`gradients`] of the image.
pub fn hog_from_gradients(g: &Gradients, sbin: usize) -> FeatureMap {
    let (w, h) = (g.width, g.height);
    let bh = (h as f64 / sbin as f64).round() as usize;
    let bw = (w as f64 / sbin as f64).round() as usize;
    let out_r = bh.saturating_sub(2);
    let out_c = bw.saturating_sub(2);
    if out_r == 0 || out_c == 0 || w < 3 || h < 3 {
        return FeatureMap { rows: out_r, cols: out_c, data: vec![0.0; out_r * out_c * FEAT_DIM] };
    }
    // Orientation histograms, 18 per cell, layout (cell_y, cell_x, orientation).
    let mut hist = vec![0f64; bh * bw * 18];
    let vis_h = bh * sbin;
    let vis_w = bw * sbin;
    let sb = sbin as f64;
    // Per column: the left cell of its bilinear vote and the weight of the right one.
    let cols: Vec<(isize, f64)> = (0..vis_w)
        .map(|x| {
            let xp = (x as f64 + 0.5) / sb - 0.5;
            let ixp = xp.floor() as isize;
            (ixp, xp - ixp as f64)
        })
        .collect();
    for y in 1..vis_h.saturating_sub(1) {
        let sy = y.min(h - 2);
        let yp = (y as f64 + 0.5) / sb - 0.5;
        let iyp = yp.floor() as isize;
        let vy0 = yp - iyp as f64;
        let vy1 = 1.0 - vy0;
        for (x, &(ixp, vx0)) in cols.iter().enumerate().take(vis_w.saturating_sub(1)).skip(1) {
            let sx = x.min(w - 2);
            let (best_o, mag) = (g.orient[sy * w + sx] as usize, g.mag[sy * w + sx]);
            let vx1 = 1.0 - vx0;
            let mut vote = |cx: isize, cy: isize, wgt: f64| {
                if cx >= 0 && cy >= 0 && (cx as usize) < bw && (cy as usize) < bh {
                    hist[((cy as usize) * bw + cx as usize) * 18 + best_o] += wgt * mag;
                }
            };
            vote(ixp, iyp, vx1 * vy1);
            vote(ixp + 1, iyp, vx0 * vy1);
            vote(ixp, iyp + 1, vx1 * vy0);
            vote(ixp + 1, iyp + 1, vx0 * vy0);
        }
    }
    // Energy of each cell: sum over the 9 unsigned orientations of (h_o + h_{o+9})².
    let norm: Vec<f64> =
        hist.chunks_exact(18).map(|c| (0..NORIENT).map(|o| (c[o] + c[o + NORIENT]).powi(2)).sum()).collect();
    let nb = |cx: usize, cy: usize| norm[cy * bw + cx];
    let block =
        |cx: usize, cy: usize| 1.0 / (nb(cx, cy) + nb(cx + 1, cy) + nb(cx, cy + 1) + nb(cx + 1, cy + 1) + EPS).sqrt();
    let mut data = vec![0f32; out_r * out_c * FEAT_DIM];
    for y in 0..out_r {
        for x in 0..out_c {
            // The four 2x2 blocks containing cell (x+1, y+1).
            let n = [block(x + 1, y + 1), block(x + 1, y), block(x, y + 1), block(x, y)];
            let src = &hist[((y + 1) * bw + x + 1) * 18..][..18];
            let dst = &mut data[(y * out_c + x) * FEAT_DIM..][..FEAT_DIM];
            let mut t = [0f64; 4];
            for o in 0..18 {
                let mut s = 0.0;
                for (k, nk) in n.iter().enumerate() {
                    let hk = (src[o] * nk).min(0.2);
                    t[k] += hk;
                    s += hk;
                }
                dst[o] = (0.5 * s) as f32;
            }
            for o in 0..NORIENT {
                let sum = src[o] + src[o + NORIENT];
                let s: f64 = n.iter().map(|nk| (sum * nk).min(0.2)).sum();
                dst[18 + o] = (0.5 * s) as f32;
            }
            for k in 0..4 {
                dst[27 + k] = (0.2357 * t[k]) as f32;
            }
            dst[31] = 0.0;
        }
    }
    FeatureMap { rows: out_r, cols: out_c, data }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planes(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Planes {
        let mut data = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                data.push(f(x, y));
            }
        }
        Planes { width: w, height: h, channels: 1, data }
    }

    /// The plain per-pixel loop of `features.cc` that [`gradients`] vectorises.
    fn gradients_reference(im: &Planes) -> Gradients {
        let (w, h) = (im.width, im.height);
        let (mut orient, mut mag) = (vec![0u8; w * h], vec![0f64; w * h]);
        let uv = orientations();
        for sy in 1..h.saturating_sub(1) {
            for sx in 1..w.saturating_sub(1) {
                let (mut dx, mut dy, mut v) = (0f64, 0f64, -1f64);
                for c in 0..im.channels {
                    let p = im.plane(c);
                    let gx = (p[sy * w + sx + 1] - p[sy * w + sx - 1]) as f64;
                    let gy = (p[(sy + 1) * w + sx] - p[(sy - 1) * w + sx]) as f64;
                    let m = gx * gx + gy * gy;
                    if m > v {
                        (dx, dy, v) = (gx, gy, m);
                    }
                }
                let (mut best_dot, mut best_o) = (0f64, 0usize);
                for (o, &(cu, su)) in uv.iter().enumerate() {
                    let dot = cu * dx + su * dy;
                    if dot > best_dot {
                        best_dot = dot;
                        best_o = o;
                    } else if -dot > best_dot {
                        best_dot = -dot;
                        best_o = o + NORIENT;
                    }
                }
                orient[sy * w + sx] = best_o as u8;
                mag[sy * w + sx] = v.sqrt();
            }
        }
        Gradients { width: w, height: h, orient, mag }
    }

    #[test]
    fn vectorised_gradients_equal_the_plain_loop() {
        // Colour noise with flat patches, ties between channels and exact axis-aligned gradients.
        let (w, h) = (53, 37);
        let mut data = vec![0f32; 3 * w * h];
        for (i, d) in data.iter_mut().enumerate() {
            let (x, y) = ((i % w) as u32, ((i / w) % h) as u32);
            *d = if x < 10 && y < 10 {
                128.0
            } else if x % 7 == 0 {
                (y * 3) as f32
            } else {
                ((i as u32).wrapping_mul(2_654_435_761) >> 24) as f32
            };
        }
        let colour = Planes { width: w, height: h, channels: 3, data: data.clone() };
        assert_eq!(gradients(&colour), gradients_reference(&colour));
        let gray = Planes { width: w, height: h, channels: 1, data: data[..w * h].to_vec() };
        assert_eq!(gradients(&gray), gradients_reference(&gray));
        let g = gradients(&gray);
        assert!(g.orient.iter().any(|&o| o >= 9) && g.orient.iter().any(|&o| (1..9).contains(&o)));
        for (w, h) in [(2, 5), (3, 3), (5, 2)] {
            let p = Planes { width: w, height: h, channels: 1, data: (0..w * h).map(|i| i as f32).collect() };
            assert_eq!(gradients(&p), gradients_reference(&p), "{w}x{h}");
        }
    }

    #[test]
    fn sizes_follow_rounded_cells_minus_border() {
        let m = hog(&planes(41, 30, |x, _| x as f32), 4);
        assert_eq!((m.rows, m.cols), (6, 8)); // round(30/4)=8-2, round(41/4)=10-2
        assert_eq!(hog(&planes(8, 8, |_, _| 0.0), 4).data.len(), 0);
    }

    #[test]
    fn flat_image_has_zero_features_and_ramp_votes_one_orientation() {
        let m = hog(&planes(40, 40, |_, _| 77.0), 4);
        assert!(m.data.iter().all(|&v| v == 0.0));
        // Horizontal ramp: gradient along +x, orientation 0 (sensitive) and 0 (insensitive).
        let m = hog(&planes(40, 40, |x, _| 3.0 * x as f32), 4);
        let c = m.cell(3, 3);
        assert!(c[0] > 0.3, "orientation 0 = {}", c[0]);
        for o in 1..18 {
            assert_eq!(c[o], 0.0, "orientation {o}");
        }
        assert!((c[18] - c[0]).abs() < 1e-6);
        // Interior cell: all four block norms equal, each h = min(0.5, 0.2) -> 0.5 * 4 * 0.2 = 0.4.
        assert!((c[0] - 0.4).abs() < 1e-6, "{}", c[0]);
        assert!((c[27] - (0.2357 * 0.2) as f32).abs() < 1e-6);
        assert_eq!(c[31], 0.0);
        // Reversed ramp: contrast-sensitive orientation 9, same insensitive feature.
        let r = hog(&planes(40, 40, |x, _| 200.0 - 3.0 * x as f32), 4);
        assert!((r.cell(3, 3)[9] - c[0]).abs() < 1e-6 && (r.cell(3, 3)[18] - c[18]).abs() < 1e-6);
    }

    #[test]
    fn colour_uses_the_strongest_channel() {
        let (w, h) = (32, 32);
        let mut data = vec![0f32; 3 * w * h];
        for y in 0..h {
            for x in 0..w {
                data[y * w + x] = x as f32; // weak x-gradient in R
                data[2 * w * h + y * w + x] = 5.0 * y as f32; // strong y-gradient in B
            }
        }
        let m = hog(&Planes { width: w, height: h, channels: 3, data }, 4);
        let c = m.cell(2, 2);
        // A +y gradient (angle π/2) lies between orientations 4π/9 and 5π/9 (a tie up to rounding).
        let best = (0..18).max_by(|&a, &b| c[a].total_cmp(&c[b])).unwrap();
        assert!(best == 4 || best == 5, "best orientation {best}");
        assert_eq!(c[0], 0.0);
    }
}

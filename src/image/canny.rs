//! Canny edge detection, bit-exact with OpenCV 4.6 `cv::Canny(src, dst, t1, t2, aperture, L2)`.
//!
//! Steps, as OpenCV performs them: Sobel gradients with `BORDER_REPLICATE` (aperture 7 scaled by
//! 1/16 and rounded half-to-even, thresholds divided by 16); L1 (`|dx|+|dy|`) or squared-L2
//! magnitude with zero magnitude outside the image; non-maximum suppression in four directions
//! using the fixed-point tangent test (`tan 22.5° ≈ 13573 / 2^15`) and OpenCV's asymmetric `>` /
//! `>=` comparisons; hysteresis over 8-connected weak pixels reachable from strong ones.
//! Row bands run in parallel (rayon); the result does not depend on the thread count.

use rayon::prelude::*;

use super::gray::to_gray;
use super::sobel::{deriv_kernel, div16_round_even, horizontal_pass, smooth_kernel, vertical_pass};
use super::view::{GrayImage, ImageView};
use crate::error::{ensure_finite, Error, Result};

/// Canny settings, with OpenCV's meaning.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CannyParams {
    /// Hysteresis threshold on the gradient magnitude; the smaller of the two thresholds is the
    /// "weak" one, the larger the "strong" one (either order is accepted, as in OpenCV).
    pub threshold1: f64,
    /// The other hysteresis threshold.
    pub threshold2: f64,
    /// Sobel aperture: 3, 5 or 7.
    pub aperture: u32,
    /// `true`: magnitude `sqrt(dx² + dy²)` (compared squared); `false`: `|dx| + |dy|`.
    pub l2_gradient: bool,
}

impl Default for CannyParams {
    /// 50 / 150, aperture 3, L1: a good default for clean line art.
    fn default() -> Self {
        Self { threshold1: 50.0, threshold2: 150.0, aperture: 3, l2_gradient: false }
    }
}

/// Thresholds in the integer units compared against the magnitude.
struct IntThresholds {
    low: i32,
    high: i32,
}

/// OpenCV's `cvFloor` for in-range values. Values at or beyond ±2^31 saturate (OpenCV's own
/// conversion is undefined there; saturating keeps "a threshold above every gradient" meaning
/// "no edges").
fn floor_to_i32(v: f64) -> i32 {
    v.floor().clamp(i32::MIN as f64, i32::MAX as f64) as i32
}

impl CannyParams {
    /// Validates the settings and converts the thresholds exactly as OpenCV does.
    fn int_thresholds(&self) -> Result<IntThresholds> {
        let mut low = ensure_finite("threshold1", self.threshold1)?;
        let mut high = ensure_finite("threshold2", self.threshold2)?;
        if !matches!(self.aperture, 3 | 5 | 7) {
            return Err(Error::InvalidAperture(self.aperture as i64));
        }
        if low > high {
            std::mem::swap(&mut low, &mut high);
        }
        if self.aperture == 7 {
            low /= 16.0;
            high /= 16.0;
        }
        if self.l2_gradient {
            low = low.min(32767.0);
            high = high.min(32767.0);
            if low > 0.0 {
                low *= low;
            }
            if high > 0.0 {
                high *= high;
            }
        }
        Ok(IntThresholds { low: floor_to_i32(low), high: floor_to_i32(high) })
    }
}

/// Runs Canny on any view (gray used as is; RGB/RGBA first converted with OpenCV's
/// `COLOR_RGB2GRAY`) and returns the edge map: 255 on edges, 0 elsewhere.
pub fn canny(src: &ImageView<'_>, params: &CannyParams) -> Result<GrayImage> {
    let mut out = GrayImage::filled(src.width(), src.height(), 0)?;
    let w = src.width();
    canny_into(src, params, out.as_bytes_mut(), w)?;
    Ok(out)
}

/// Like [`canny`] but writes into a caller buffer of `src.height()` rows, `out_stride` bytes
/// apart (`out_stride >= width`). Bytes between rows are left untouched. On error nothing is
/// written.
pub fn canny_into(src: &ImageView<'_>, params: &CannyParams, out: &mut [u8], out_stride: usize) -> Result<()> {
    let t = params.int_thresholds()?;
    let (w, h) = (src.width(), src.height());
    let needed = ImageView::required_len(w, h, 1, out_stride)?;
    if out.len() < needed {
        return Err(Error::BufferTooSmall { name: "out", len: out.len(), needed, unit: "bytes" });
    }
    let converted;
    let gray = if src.channels() == 1 {
        *src
    } else {
        converted = to_gray(src)?;
        converted.view()
    };
    let map = edge_map(&gray, params.aperture as usize, params.l2_gradient, &t);
    let mw = w + 2;
    for y in 0..h {
        let mrow = &map[(y + 1) * mw + 1..(y + 1) * mw + 1 + w];
        for (o, &m) in out[y * out_stride..y * out_stride + w].iter_mut().zip(mrow) {
            *o = ((m == STRONG) as u8).wrapping_neg();
        }
    }
    Ok(())
}

/// Map values, as in OpenCV: may still become an edge / cannot be an edge / is an edge.
const WEAK: u8 = 0;
const NOT_EDGE: u8 = 1;
const STRONG: u8 = 2;

/// Rows per parallel band; small enough to balance, large enough to amortise band overlap.
const BAND_ROWS: usize = 64;

/// Non-maximum suppression and thresholding into a `(w+2) x (h+2)` map with a border of
/// [`NOT_EDGE`], followed by hysteresis. Returns the map.
fn edge_map(gray: &ImageView<'_>, aperture: usize, l2: bool, t: &IntThresholds) -> Vec<u8> {
    let (w, h) = (gray.width(), gray.height());
    let mw = w + 2;
    let mut map = vec![NOT_EDGE; mw * (h + 2)];
    let interior = &mut map[mw..mw * (h + 1)];
    let bands: Vec<(usize, &mut [u8])> = interior.chunks_mut(BAND_ROWS * mw).enumerate().collect();
    let process = |(b, rows): (usize, &mut [u8])| -> Vec<u32> {
        let y0 = b * BAND_ROWS;
        let y1 = (y0 + BAND_ROWS).min(h);
        let mut band = Band::new(gray, aperture, l2, t);
        band.run(y0, y1, rows, mw)
    };
    // With one worker (or a small image) stay on the calling thread: handing work to the pool
    // would only add two thread wake-ups per call.
    let parallel = rayon::current_num_threads() > 1 && h > BAND_ROWS && w * h >= 1 << 16;
    let strong: Vec<Vec<u32>> =
        if parallel { bands.into_par_iter().map(process).collect() } else { bands.into_iter().map(process).collect() };
    hysteresis(&mut map, mw, strong);
    map
}

/// Grows strong pixels through 8-connected weak pixels. `strong` holds map indices.
fn hysteresis(map: &mut [u8], mw: usize, strong: Vec<Vec<u32>>) {
    let mut stack = Vec::with_capacity(strong.iter().map(Vec::len).sum());
    for band in &strong {
        stack.extend_from_slice(band);
    }
    let offsets = [
        1isize,
        -1,
        mw as isize - 1,
        mw as isize,
        mw as isize + 1,
        -(mw as isize) - 1,
        -(mw as isize),
        -(mw as isize) + 1,
    ];
    while let Some(i) = stack.pop() {
        for &o in &offsets {
            let n = (i as isize + o) as usize;
            if map[n] == WEAK {
                map[n] = STRONG;
                stack.push(n as u32);
            }
        }
    }
}

/// Per-band working state: ring buffers of horizontal passes and of gradient rows.
struct Band<'a, 'g> {
    gray: &'a ImageView<'g>,
    aperture: usize,
    l2: bool,
    t: &'a IntThresholds,
    /// Aperture 5/7: horizontal smooth/deriv rows, slot = logical row mod aperture.
    hs: Vec<Vec<i32>>,
    hd: Vec<Vec<i32>>,
    /// Aperture 5/7: vertical-pass scratch.
    vx: Vec<i32>,
    vy: Vec<i32>,
    /// Aperture 3: the three source rows around the current one, padded by replication.
    pad: [Vec<u8>; 3],
    /// Gradient rows of the last three image rows g: slot = (g + 3) mod 3. Every aperture's
    /// gradients fit in i16 (OpenCV stores them as CV_16S too).
    dx: [Vec<i16>; 3],
    dy: [Vec<i16>; 3],
    /// Magnitudes with one zero column on each side.
    mag: [Vec<i32>; 3],
    /// Scratch for the strong pixels of one row (written branch-free).
    found: Vec<u32>,
}

impl<'a, 'g> Band<'a, 'g> {
    fn new(gray: &'a ImageView<'g>, aperture: usize, l2: bool, t: &'a IntThresholds) -> Self {
        let w = gray.width();
        let ring = || if aperture == 3 { Vec::new() } else { vec![vec![0i32; w]; aperture] };
        let three16 = || [vec![0i16; w], vec![0i16; w], vec![0i16; w]];
        Self {
            gray,
            aperture,
            l2,
            t,
            hs: ring(),
            hd: ring(),
            vx: vec![0; if aperture == 3 { 0 } else { w }],
            vy: vec![0; if aperture == 3 { 0 } else { w }],
            pad: [vec![0u8; w + 2], vec![0u8; w + 2], vec![0u8; w + 2]],
            dx: three16(),
            dy: three16(),
            mag: [vec![0i32; w + 2], vec![0i32; w + 2], vec![0i32; w + 2]],
            found: vec![0; w],
        }
    }

    /// Map rows `y0..y1` (in `rows`, `mw` bytes each); returns map indices of strong pixels.
    fn run(&mut self, y0: usize, y1: usize, rows: &mut [u8], mw: usize) -> Vec<u32> {
        let h = self.gray.height() as isize;
        let r = (self.aperture / 2) as isize;
        let mut strong = Vec::new();
        let mut next_h = y0 as isize - 1 - r;
        for gy in y0 as isize - 1..=y1 as isize {
            let slot = (gy + 3) as usize % 3;
            if gy >= 0 && gy < h {
                if self.aperture == 3 {
                    self.gradient3(gy, slot);
                } else {
                    while next_h <= gy + r {
                        self.horizontal(next_h);
                        next_h += 1;
                    }
                    self.gradient_generic(gy, slot);
                }
                self.magnitude(slot);
            } else {
                self.mag[slot].fill(0);
            }
            let y = gy - 1;
            if y >= y0 as isize {
                let local = (y as usize - y0) * mw;
                let base = (y as usize + 1) * mw;
                self.suppress(y, &mut rows[local..local + mw], base, &mut strong);
            }
        }
        strong
    }

    /// Aperture 3, fused: dx and dy of image row `gy` from the replicated-border rows around it,
    /// with adds and shifts only (exact in i16: |dx|, |dy| <= 1020).
    fn gradient3(&mut self, gy: isize, slot: usize) {
        let h = self.gray.height() as isize;
        let w = self.gray.width();
        for (i, pad) in self.pad.iter_mut().enumerate() {
            let src = self.gray.row((gy + i as isize - 1).clamp(0, h - 1) as usize);
            pad[1..w + 1].copy_from_slice(src);
            pad[0] = src[0];
            pad[w + 1] = src[w - 1];
        }
        let [p0, p1, p2] = &self.pad;
        let (l0, c0, r0) = (&p0[..w], &p0[1..w + 1], &p0[2..w + 2]);
        let (l1, r1) = (&p1[..w], &p1[2..w + 2]);
        let (l2, c2, r2) = (&p2[..w], &p2[1..w + 1], &p2[2..w + 2]);
        let dx = &mut self.dx[slot][..w];
        let dy = &mut self.dy[slot][..w];
        for x in 0..w {
            let (a, b, c) = (l0[x] as i16, c0[x] as i16, r0[x] as i16);
            let (d, f) = (l1[x] as i16, r1[x] as i16);
            let (g, k, m) = (l2[x] as i16, c2[x] as i16, r2[x] as i16);
            dx[x] = (c - a) + ((f - d) << 1) + (m - g);
            dy[x] = (g + (k << 1) + m) - (a + (b << 1) + c);
        }
    }

    /// Horizontal pass of logical row `ly` (source row clamped into the image), apertures 5/7.
    fn horizontal(&mut self, ly: isize) {
        let h = self.gray.height() as isize;
        let src = self.gray.row(ly.clamp(0, h - 1) as usize);
        let slot = ly.rem_euclid(self.aperture as isize) as usize;
        horizontal_pass(
            src,
            smooth_kernel(self.aperture),
            deriv_kernel(self.aperture),
            &mut self.hs[slot],
            &mut self.hd[slot],
        );
    }

    /// Gradient of image row `gy` for apertures 5 and 7 (7: scaled by 1/16, rounded half-even).
    fn gradient_generic(&mut self, gy: isize, slot: usize) {
        let k = self.aperture;
        let r = (k / 2) as isize;
        let mut hd: [&[i32]; 7] = [&[]; 7];
        let mut hs: [&[i32]; 7] = [&[]; 7];
        for i in 0..k {
            let s = (gy + i as isize - r).rem_euclid(k as isize) as usize;
            hd[i] = &self.hd[s];
            hs[i] = &self.hs[s];
        }
        vertical_pass(&hd[..k], smooth_kernel(k), &mut self.vx);
        vertical_pass(&hs[..k], deriv_kernel(k), &mut self.vy);
        let scale = |v: i32| if k == 7 { div16_round_even(v) } else { v };
        for (o, &v) in self.dx[slot].iter_mut().zip(&self.vx) {
            *o = scale(v) as i16;
        }
        for (o, &v) in self.dy[slot].iter_mut().zip(&self.vy) {
            *o = scale(v) as i16;
        }
    }

    /// Magnitude of the gradient row in `slot`: `|dx| + |dy|` or `dx² + dy²`.
    fn magnitude(&mut self, slot: usize) {
        let (dx, dy) = (&self.dx[slot], &self.dy[slot]);
        let w = dx.len();
        let inner = &mut self.mag[slot][1..w + 1];
        if self.l2 {
            for ((m, &a), &b) in inner.iter_mut().zip(dx.iter()).zip(dy.iter()) {
                *m = a as i32 * a as i32 + b as i32 * b as i32;
            }
        } else {
            for ((m, &a), &b) in inner.iter_mut().zip(dx.iter()).zip(dy.iter()) {
                *m = (a as i32).abs() + (b as i32).abs();
            }
        }
    }

    /// Non-maximum suppression of image row `y` into its map row.
    fn suppress(&mut self, y: isize, map_row: &mut [u8], base: usize, strong: &mut Vec<u32>) {
        const CHUNK: usize = 16;
        // Gradient row g lives in ring slot (g + 3) mod 3 (see `run`).
        let slot = |g: isize| (g + 3) as usize % 3;
        let w = self.gray.width();
        let (prev, cur, next) =
            (&self.mag[slot(y - 1)][..w + 2], &self.mag[slot(y)][..w + 2], &self.mag[slot(y + 1)][..w + 2]);
        let (dx, dy) = (&self.dx[slot(y)][..w], &self.dy[slot(y)][..w]);
        let out = &mut map_row[1..w + 1];
        let (low, high) = (self.t.low, self.t.high);
        // Magnitudes are >= 0, so for low >= 0 `low - m` cannot overflow and is negative exactly
        // when m > low: OR-ing sign bits finds a candidate in a chunk with plain SSE2 ops.
        let skippable = |chunk: &[i32]| low >= 0 && chunk.iter().fold(0, |acc, &m| acc | (low - m)) >= 0;
        let found = &mut self.found[..w];
        let mut n = 0;
        let mut x = 0;
        while x < w {
            let end = (x + CHUNK).min(w);
            if end - x == CHUNK && skippable(&cur[x + 1..end + 1]) {
                out[x..end].fill(NOT_EDGE);
            } else {
                let rows = NmsRows {
                    up: [&prev[x..end], &prev[x + 1..end + 1], &prev[x + 2..end + 2]],
                    mid: [&cur[x..end], &cur[x + 1..end + 1], &cur[x + 2..end + 2]],
                    down: [&next[x..end], &next[x + 1..end + 1], &next[x + 2..end + 2]],
                };
                nms_span(&rows, &dx[x..end], &dy[x..end], low, high, &mut out[x..end]);
                for i in x..end {
                    found[n] = (base + i + 1) as u32;
                    n += (out[i] == STRONG) as usize;
                }
            }
            x = end;
        }
        strong.extend_from_slice(&found[..n]);
        map_row[0] = NOT_EDGE;
        map_row[w + 1] = NOT_EDGE;
    }
}

/// Magnitudes of a span and its 8 neighbours: `up/mid/down[k][i]` is the magnitude at column
/// `i + k - 1` of the row above / the row itself / the row below.
struct NmsRows<'a> {
    up: [&'a [i32]; 3],
    mid: [&'a [i32]; 3],
    down: [&'a [i32]; 3],
}

/// OpenCV's non-maximum suppression test on a span, written branch-free so it vectorises:
/// the direction is horizontal when `|dy| 2^15 < |dx| 13573` (tan 22.5°), vertical when
/// `|dy| 2^15 > |dx| (13573 + 2^16)` (tan 67.5°), else diagonal (up-left/down-right when dx and dy
/// have the same sign). A candidate beats the neighbour before it strictly and the one after it
/// with `>=` on the axes, `>` on the diagonals, and has `m > low`; it is strong when `m > high`.
#[inline(always)]
fn nms_span(rows: &NmsRows<'_>, dx: &[i16], dy: &[i16], low: i32, high: i32, out: &mut [u8]) {
    const TG22: i32 = 13573;
    let n = out.len();
    let (dx, dy) = (&dx[..n], &dy[..n]);
    let [ul, u, ur] = rows.up.map(|r| &r[..n]);
    let [l, m, r] = rows.mid.map(|r| &r[..n]);
    let [dl, d, dr] = rows.down.map(|r| &r[..n]);
    for i in 0..n {
        let mv = m[i];
        let (xs, ys) = (dx[i] as i32, dy[i] as i32);
        let ax = xs.abs();
        let ay = ys.abs() << 15;
        let tg22x = ax * TG22;
        let tg67x = tg22x + (ax << 16);
        let horizontal = ay < tg22x;
        let vertical = ay > tg67x;
        let anti = (xs ^ ys) < 0;
        let diag_before = if anti { ur[i] } else { ul[i] };
        let diag_after = if anti { dl[i] } else { dr[i] };
        let before = if horizontal {
            l[i]
        } else if vertical {
            u[i]
        } else {
            diag_before
        };
        let after = if horizontal {
            r[i]
        } else if vertical {
            d[i]
        } else {
            diag_after
        };
        let axis = horizontal | vertical;
        let beats_after = (mv > after) | (axis & (mv == after));
        let candidate = (mv > low) & (mv > before) & beats_after;
        let is_strong = candidate & (mv > high);
        out[i] = (!candidate) as u8 * NOT_EDGE + is_strong as u8 * STRONG;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plain, unoptimised Canny written from OpenCV 4.6's definition (separable Sobel with
    /// replicated borders, aperture 7 scaled by 1/16 and rounded half-even, L1 or squared L2
    /// magnitude, tangent-based non-maximum suppression with `>` before and `>=` after on the
    /// axes, `>` on both diagonal neighbours, zero magnitude outside the image, 8-connected
    /// hysteresis). The optimised banded code must agree with it bit for bit; the ctest
    /// cross-check compares the same code with OpenCV itself.
    fn reference_canny(px: &[u8], w: usize, h: usize, p: &CannyParams) -> Vec<u8> {
        let k = p.aperture as usize;
        let smooth: Vec<i64> = match k {
            3 => vec![1, 2, 1],
            5 => vec![1, 4, 6, 4, 1],
            _ => vec![1, 6, 15, 20, 15, 6, 1],
        };
        let deriv: Vec<i64> = match k {
            3 => vec![-1, 0, 1],
            5 => vec![-1, -2, 0, 2, 1],
            _ => vec![-1, -4, -5, 0, 5, 4, 1],
        };
        let r = (k / 2) as isize;
        let at = |x: isize, y: isize| {
            px[y.clamp(0, h as isize - 1) as usize * w + x.clamp(0, w as isize - 1) as usize] as i64
        };
        let mut gx = vec![0i32; w * h];
        let mut gy = vec![0i32; w * h];
        for y in 0..h as isize {
            for x in 0..w as isize {
                let (mut sx, mut sy) = (0i64, 0i64);
                for j in -r..=r {
                    for i in -r..=r {
                        let v = at(x + i, y + j);
                        sx += deriv[(i + r) as usize] * smooth[(j + r) as usize] * v;
                        sy += smooth[(i + r) as usize] * deriv[(j + r) as usize] * v;
                    }
                }
                let scale = |s: i64| -> i32 {
                    if k == 7 {
                        ((s as f64) / 16.0).round_ties_even() as i32
                    } else {
                        s as i32
                    }
                };
                gx[y as usize * w + x as usize] = scale(sx).clamp(-32768, 32767);
                gy[y as usize * w + x as usize] = scale(sy).clamp(-32768, 32767);
            }
        }
        let mag: Vec<i64> = (0..w * h)
            .map(|i| {
                let (a, b) = (gx[i] as i64, gy[i] as i64);
                if p.l2_gradient {
                    a * a + b * b
                } else {
                    a.abs() + b.abs()
                }
            })
            .collect();
        let m_at = |x: isize, y: isize| {
            if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
                0
            } else {
                mag[y as usize * w + x as usize]
            }
        };
        // OpenCV's threshold handling, written out here again (not `int_thresholds`): ordered,
        // divided by 16 for aperture 7, for L2 capped at 32767 and squared when positive, floored.
        let (mut low, mut high) = (p.threshold1.min(p.threshold2), p.threshold1.max(p.threshold2));
        if k == 7 {
            (low, high) = (low / 16.0, high / 16.0);
        }
        if p.l2_gradient {
            let square = |t: f64| if t > 0.0 { t.min(32767.0).powi(2) } else { t };
            (low, high) = (square(low), square(high));
        }
        let (low, high) = (low.floor() as i64, high.floor() as i64);
        // 0: not an edge, 1: weak, 2: strong.
        let mut class = vec![0u8; w * h];
        const TG22: i64 = 13573;
        for y in 0..h as isize {
            for x in 0..w as isize {
                let i = y as usize * w + x as usize;
                let m = mag[i];
                if m <= low {
                    continue;
                }
                let (dx, dy) = (gx[i] as i64, gy[i] as i64);
                let ax = dx.abs();
                let ay = dy.abs() << 15;
                let tg22x = ax * TG22;
                let keep = if ay < tg22x {
                    m > m_at(x - 1, y) && m >= m_at(x + 1, y)
                } else if ay > tg22x + (ax << 16) {
                    m > m_at(x, y - 1) && m >= m_at(x, y + 1)
                } else {
                    let s = if (dx ^ dy) < 0 { -1 } else { 1 };
                    m > m_at(x - s, y - 1) && m > m_at(x + s, y + 1)
                };
                if keep {
                    class[i] = if m > high { 2 } else { 1 };
                }
            }
        }
        let mut stack: Vec<usize> = (0..w * h).filter(|&i| class[i] == 2).collect();
        while let Some(i) = stack.pop() {
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            for (ox, oy) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
                let (nx, ny) = (x + ox, y + oy);
                if nx >= 0 && ny >= 0 && nx < w as isize && ny < h as isize {
                    let n = ny as usize * w + nx as usize;
                    if class[n] == 1 {
                        class[n] = 2;
                        stack.push(n);
                    }
                }
            }
        }
        class.iter().map(|&c| if c == 2 { 255 } else { 0 }).collect()
    }

    /// A deterministic test image: blocks of flat grey, a ramp and seeded noise, so every
    /// gradient direction, many tied magnitudes and thin weak chains occur.
    fn test_image(w: usize, h: usize, seed: u64) -> Vec<u8> {
        use rand::Rng;
        let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(seed);
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let block = if (x / 7 + y / 5) % 3 == 0 { 200 } else { 40 };
                let ramp = (x * 3 + y * 2) % 60;
                let noise = rng.random_range(0..24);
                (block + ramp + noise).min(255) as u8
            })
            .collect()
    }

    /// The banded, vectorised Canny equals the plain reference for every aperture, L1 and L2,
    /// and several threshold pairs per setting (one with equal thresholds, one given high-low).
    #[test]
    fn matches_plain_reference_for_every_setting() {
        let (w, h) = (61, 47);
        for seed in 0..3u64 {
            let px = test_image(w, h, seed);
            let src = ImageView::gray(&px, w, h).unwrap();
            for aperture in [3u32, 5, 7] {
                for l2_gradient in [false, true] {
                    let thresholds: &[(f64, f64)] = match (aperture, l2_gradient) {
                        (3, false) => &[(50.0, 150.0), (100.0, 100.0), (80.0, 400.0), (200.0, 40.0)],
                        (3, true) => &[(50.0, 150.0), (30.0, 120.0), (100.0, 100.0)],
                        (5, false) => &[(300.0, 900.0), (500.0, 2000.0)],
                        (5, true) => &[(200.0, 800.0), (400.0, 1500.0)],
                        (7, false) => &[(2000.0, 8000.0), (4000.0, 16000.0)],
                        _ => &[(1500.0, 6000.0), (3000.0, 12000.0)],
                    };
                    for &(threshold1, threshold2) in thresholds {
                        let p = CannyParams { threshold1, threshold2, aperture, l2_gradient };
                        let got = canny(&src, &p).unwrap();
                        let want = reference_canny(&px, w, h, &p);
                        let diff = got.as_bytes().iter().zip(&want).filter(|(a, b)| a != b).count();
                        let edges = want.iter().filter(|&&v| v == 255).count();
                        assert!(edges > 20 && edges < w * h / 2, "setting exercises edges: {edges}");
                        assert_eq!(
                            diff, 0,
                            "seed {seed} aperture {aperture} l2 {l2_gradient} t {threshold1}/{threshold2}"
                        );
                    }
                }
            }
        }
    }

    /// The thresholds are strict: a step whose magnitude equals `threshold2` is not strong and
    /// one that equals `threshold1` is not even weak; one more grey level makes it an edge.
    #[test]
    fn thresholds_are_strict_at_the_exact_magnitude() {
        let (w, h) = (16, 9);
        // A vertical step of `d` grey levels: Sobel 3 gives |dx| = 4·d on the two columns beside it.
        let step = |d: u8| -> Vec<u8> { (0..w * h).map(|i| if i % w < 8 { 100 } else { 100 + d }).collect() };
        let edges = |px: &[u8], t1: f64, t2: f64| {
            let src = ImageView::gray(px, w, h).unwrap();
            let p = CannyParams { threshold1: t1, threshold2: t2, ..CannyParams::default() };
            canny(&src, &p).unwrap().as_bytes().iter().filter(|&&v| v == 255).count()
        };
        let px = step(25); // magnitude 100
        assert_eq!(edges(&px, 50.0, 100.0), 0, "m == high is not strong");
        assert_eq!(edges(&px, 50.0, 99.0), h, "m > high: one column of edges");
        assert_eq!(edges(&px, 99.5, 99.9), h, "fractional thresholds floor to 99");
        assert_eq!(edges(&px, 100.0, 100.0), 0);
        // L2 compares squared magnitudes: 100² against floor(t)².
        let src = ImageView::gray(&px, w, h).unwrap();
        let l2 = |t2: f64| {
            let p = CannyParams { threshold1: 10.0, threshold2: t2, aperture: 3, l2_gradient: true };
            canny(&src, &p).unwrap().as_bytes().iter().filter(|&&v| v == 255).count()
        };
        assert_eq!(l2(100.0), 0, "100² is not > 100²");
        assert_eq!(l2(99.99), h, "99.99² floors below 100²");
    }

    /// Hysteresis follows weak chains in all eight directions, up-left and up-right included:
    /// a diagonal step edge, faint at its upper end and strong at its lower end, is kept whole.
    #[test]
    fn hysteresis_follows_every_neighbour_direction() {
        let (w, h) = (40, 40);
        for flip in [false, true] {
            // A diagonal step edge (one-pixel diagonal chains after suppression) whose contrast
            // grows down the image: weak edges only at the top, strong ones at the bottom.
            let px: Vec<u8> = (0..w * h)
                .map(|i| {
                    let (x, y) = (i % w, i / w);
                    let bright = if flip { x + y > w - 1 } else { x > y };
                    if bright {
                        (110 + 3 * y) as u8
                    } else {
                        100
                    }
                })
                .collect();
            let src = ImageView::gray(&px, w, h).unwrap();
            let p = CannyParams { threshold1: 20.0, threshold2: 300.0, ..CannyParams::default() };
            let got = canny(&src, &p).unwrap();
            let want = reference_canny(&px, w, h, &p);
            assert_eq!(got.as_bytes(), &want[..], "flip {flip}");
            let upper = got.as_bytes()[..10 * w].iter().filter(|&&v| v == 255).count();
            assert!(upper > 0, "the faint end (rows < 10) is reached from the strong end (flip {flip})");
            let strong_only = CannyParams { threshold1: 300.0, ..p };
            let alone = canny(&src, &strong_only).unwrap();
            assert!(alone.as_bytes()[..10 * w].iter().all(|&v| v == 0), "rows < 10 hold weak pixels only");
            assert!(alone.as_bytes().contains(&255), "the lower rows hold strong pixels");
            // Aperture 7 divides both thresholds by 16 (OpenCV): the weak one, too, cuts the
            // chain's faint end, which a weak threshold of 0 would keep. The first setting
            // (thresholds multiples of 16) where it does is compared with the reference.
            let p7 = |t1: f64, t2: f64| CannyParams { threshold1: t1, threshold2: t2, aperture: 7, l2_gradient: false };
            let setting = [(1000.0, 5000.0), (2000.0, 5000.0), (2000.0, 8000.0), (4000.0, 8000.0)]
                .into_iter()
                .map(|(a, b)| (16.0 * a, 16.0 * b))
                .find(|&(t1, t2)| {
                    let cut = reference_canny(&px, w, h, &p7(t1, t2));
                    cut.contains(&255) && cut != reference_canny(&px, w, h, &p7(0.0, t2))
                });
            let (t1, t2) = setting.expect("a setting where aperture 7's weak threshold cuts the chain");
            let got = canny(&src, &p7(t1, t2)).unwrap();
            assert_eq!(got.as_bytes(), &reference_canny(&px, w, h, &p7(t1, t2))[..], "aperture 7, flip {flip}");
        }
    }

    /// Finding 1: a wrapping output stride is an error and the buffer is untouched.
    #[test]
    fn wrapping_output_stride_writes_nothing() {
        let px = [100u8, 200, 100, 200, 100, 200, 100, 200, 100, 200, 100, 200];
        let src = ImageView::gray(&px, 4, 3).unwrap();
        let mut out = [0xA5u8; 64];
        let e = canny_into(&src, &CannyParams::default(), &mut out, 1 << 63).unwrap_err();
        assert!(matches!(e, Error::OutOfRange { name: "stride", .. }), "{e}");
        assert!(out.iter().all(|&b| b == 0xA5));
        canny_into(&src, &CannyParams::default(), &mut out, 16).unwrap();
        assert!(out[4..16].iter().all(|&b| b == 0xA5), "padding between rows untouched");
    }
}

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
use super::view::{check_size, GrayImage, ImageView};
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
    check_size(w, h)?;
    if out_stride < w {
        return Err(Error::BadStride { stride: out_stride, row_bytes: w });
    }
    let needed = out_stride * (h - 1) + w;
    if out.len() < needed {
        return Err(Error::BufferTooSmall { len: out.len(), needed });
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
            *o = if m == STRONG { 255 } else { 0 };
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
    let strong: Vec<Vec<u32>> = if h > BAND_ROWS && w * h >= 1 << 16 {
        bands.into_par_iter().map(process).collect()
    } else {
        bands.into_iter().map(process).collect()
    };
    hysteresis(&mut map, mw, strong);
    map
}

/// Grows strong pixels through 8-connected weak pixels. `strong` holds map indices.
fn hysteresis(map: &mut [u8], mw: usize, strong: Vec<Vec<u32>>) {
    let mut stack: Vec<u32> = strong.into_iter().flatten().collect();
    let offsets = [1isize, -1, mw as isize - 1, mw as isize, mw as isize + 1, -(mw as isize) - 1, -(mw as isize), -(mw as isize) + 1];
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
    /// Horizontal smooth/deriv rows, slot = logical row mod aperture.
    hs: Vec<Vec<i32>>,
    hd: Vec<Vec<i32>>,
    /// Gradient rows of the last three image rows g: slot = (g + 3) mod 3.
    dx: [Vec<i32>; 3],
    dy: [Vec<i32>; 3],
    /// Magnitudes with one zero column on each side.
    mag: [Vec<i32>; 3],
}

impl<'a, 'g> Band<'a, 'g> {
    fn new(gray: &'a ImageView<'g>, aperture: usize, l2: bool, t: &'a IntThresholds) -> Self {
        let w = gray.width();
        let ring = || vec![vec![0i32; w]; aperture];
        let three = || [vec![0i32; w], vec![0i32; w], vec![0i32; w]];
        Self {
            gray,
            aperture,
            l2,
            t,
            hs: ring(),
            hd: ring(),
            dx: three(),
            dy: three(),
            mag: [vec![0i32; w + 2], vec![0i32; w + 2], vec![0i32; w + 2]],
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
                while next_h <= gy + r {
                    self.horizontal(next_h);
                    next_h += 1;
                }
                self.gradient(gy, slot);
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

    /// Horizontal pass of logical row `ly` (source row clamped into the image).
    fn horizontal(&mut self, ly: isize) {
        let h = self.gray.height() as isize;
        let src = self.gray.row(ly.clamp(0, h - 1) as usize);
        let slot = ly.rem_euclid(self.aperture as isize) as usize;
        horizontal_pass(src, smooth_kernel(self.aperture), deriv_kernel(self.aperture), &mut self.hs[slot], &mut self.hd[slot]);
    }

    /// Gradient and magnitude of image row `gy` into ring slot `slot`.
    fn gradient(&mut self, gy: isize, slot: usize) {
        let k = self.aperture;
        let r = (k / 2) as isize;
        let idx: Vec<usize> = (0..k as isize).map(|i| (gy + i - r).rem_euclid(k as isize) as usize).collect();
        {
            let hd: Vec<&[i32]> = idx.iter().map(|&s| self.hd[s].as_slice()).collect();
            vertical_pass(&hd, smooth_kernel(k), &mut self.dx[slot]);
            let hs: Vec<&[i32]> = idx.iter().map(|&s| self.hs[s].as_slice()).collect();
            vertical_pass(&hs, deriv_kernel(k), &mut self.dy[slot]);
        }
        let (dx, dy) = (&mut self.dx[slot], &mut self.dy[slot]);
        if k == 7 {
            dx.iter_mut().for_each(|v| *v = div16_round_even(*v));
            dy.iter_mut().for_each(|v| *v = div16_round_even(*v));
        }
        let mag = &mut self.mag[slot];
        let w = dx.len();
        let inner = &mut mag[1..w + 1];
        if self.l2 {
            for ((m, &a), &b) in inner.iter_mut().zip(dx.iter()).zip(dy.iter()) {
                *m = a * a + b * b;
            }
        } else {
            for ((m, &a), &b) in inner.iter_mut().zip(dx.iter()).zip(dy.iter()) {
                *m = a.abs() + b.abs();
            }
        }
    }

    /// Non-maximum suppression of image row `y` into its map row.
    fn suppress(&self, y: isize, map_row: &mut [u8], base: usize, strong: &mut Vec<u32>) {
        const TG22: i32 = 13573;
        // Gradient row g lives in ring slot (g + 3) mod 3 (see `run`).
        let slot = |g: isize| (g + 3) as usize % 3;
        let (prev, cur, next) = (&self.mag[slot(y - 1)], &self.mag[slot(y)], &self.mag[slot(y + 1)]);
        let (dx, dy) = (&self.dx[slot(y)], &self.dy[slot(y)]);
        let (low, high) = (self.t.low, self.t.high);
        let w = dx.len();
        for x in 0..w {
            let m = cur[x + 1];
            let mut state = NOT_EDGE;
            if m > low {
                let (xs, ys) = (dx[x], dy[x]);
                let ax = xs.abs();
                let ay = ys.abs() << 15;
                let tg22x = ax.wrapping_mul(TG22);
                let local_max = if ay < tg22x {
                    m > cur[x] && m >= cur[x + 2]
                } else {
                    let tg67x = tg22x.wrapping_add(ax << 16);
                    if ay > tg67x {
                        m > prev[x + 1] && m >= next[x + 1]
                    } else {
                        let s: isize = if (xs ^ ys) < 0 { -1 } else { 1 };
                        m > prev[(x as isize + 1 - s) as usize] && m > next[(x as isize + 1 + s) as usize]
                    }
                };
                if local_max {
                    if m > high {
                        state = STRONG;
                        strong.push((base + x + 1) as u32);
                    } else {
                        state = WEAK;
                    }
                }
            }
            map_row[x + 1] = state;
        }
        map_row[0] = NOT_EDGE;
        map_row[w + 1] = NOT_EDGE;
    }
}

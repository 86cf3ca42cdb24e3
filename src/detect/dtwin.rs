//! An exact pruned distance transform: the windowed brute force behind
//! [`super::dt::distance_transform`].
//!
//! For the deformation cost `c(d) = a d² + b d` (a > 0, d = probe − source position) and a
//! source line whose values span `range = max − min`, a displacement with `a |d|² − |b| |d| >
//! range` can never win against `d = 0` (it loses at least `range` in cost and gains at most
//! `range` in score), so the maximum over the window `|d| ≤ R` of [`radius`] is exact. Along y
//! the window loop runs over whole source rows (vectorised over x), along x over shifted copies
//! of one line (vectorised over the outputs); no per-element branch. Lines whose window would be
//! wider than [`MAX_RADIUS`] (flat costs or a large value range) fall back to the
//! lower-envelope kernel; probes outside the source get their own bounded window
//! ([`outside_window`]), so the result is always exact.
//! Ties (equal values) go to the smallest source index, as in the envelope method.

use super::conv::ScoreMap;
use super::dt::{dt1d_fast, Scratch, Transformed};

/// Largest window radius (in cells) run as a brute force; wider windows use the envelope.
pub const MAX_RADIUS: usize = 20;

/// The window radius R: every displacement |d| > R loses strictly against d = 0 on a line whose
/// values span `range` (with a margin of at least `a` in score, far above float rounding).
/// `None` when the window would exceed [`MAX_RADIUS`] or the inputs are not finite / a ≤ 0.
pub fn radius(a: f64, b: f64, range: f64) -> Option<usize> {
    if !(a > 0.0) || !b.is_finite() || !range.is_finite() {
        return None;
    }
    let root = (b.abs() + (b * b + 4.0 * a * range.max(0.0)).sqrt()) / (2.0 * a);
    let r = root.floor() + 1.0;
    (r <= MAX_RADIUS as f64).then_some(r as usize)
}

/// `max − min` of `v`, NaN when `v` holds a NaN or an infinity (then [`radius`] declines and the
/// envelope kernel runs); eight lanes of plain arithmetic so that it vectorises.
#[allow(clippy::eq_op)] // `x - x` on purpose: 0 for finite x, NaN otherwise, and it vectorises
fn value_range(v: &[f32]) -> f64 {
    let (mut lo, mut hi, mut bad) = ([f32::INFINITY; 8], [f32::NEG_INFINITY; 8], [0f32; 8]);
    let mut chunks = v.chunks_exact(8);
    for ch in &mut chunks {
        for k in 0..8 {
            let x = ch[k];
            lo[k] = if x < lo[k] { x } else { lo[k] };
            hi[k] = if x > hi[k] { x } else { hi[k] };
            // x − x is 0 for finite x and NaN for NaN or ±∞.
            bad[k] += x - x;
        }
    }
    for &x in chunks.remainder() {
        lo[0] = if x < lo[0] { x } else { lo[0] };
        hi[0] = if x > hi[0] { x } else { hi[0] };
        bad[0] += x - x;
    }
    if bad.iter().any(|b| b.is_nan()) {
        return f64::NAN;
    }
    let lo = lo.iter().fold(f32::INFINITY, |a, &b| a.min(b));
    let hi = hi.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b));
    hi as f64 - lo as f64
}

/// The source positions a probe `q` outside the line `0..n` can take its maximum from: the
/// nearest position p0 scores at least `s(p0) − c(q − p0)`, so a position p can win only if
/// `c(q − p) ≤ range + c(q − p0)`; [`radius`] of that bound around q, or the whole line.
fn outside_window(a: f64, b: f64, range: f64, q: i64, n: i64) -> (i64, i64) {
    let d0 = (q - q.clamp(0, n - 1)) as f64;
    match radius(a, b, range + a * d0 * d0 + b * d0) {
        Some(r) => ((q - r as i64).max(0), (q + r as i64).min(n - 1)),
        None => (0, n - 1),
    }
}

/// Cost `a d² + b d` as f32.
#[inline]
fn cost(a: f64, b: f64, d: i64) -> f32 {
    let d = d as f64;
    (a * d * d + b * d) as f32
}

/// One window step: `best[i] = max(best[i], vals[i] − c)`, `arg[i] = tag` where it grew
/// (strictly, so earlier steps win ties). Written with bit masks so that it compiles to vector
/// selects; run with AVX2 when the processor has it.
#[inline]
pub(super) fn max_step(best: &mut [f32], arg: &mut [i32], vals: &[f32], c: f32, tag: i32) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor supports AVX2 (checked just above), the only requirement
            // of calling a `target_feature(enable = "avx2")` function.
            unsafe { max_step_avx2(best, arg, vals, c, tag) };
            return;
        }
    }
    max_step_body(best, arg, vals, c, tag);
}

/// [`max_step_body`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn max_step_avx2(best: &mut [f32], arg: &mut [i32], vals: &[f32], c: f32, tag: i32) {
    max_step_body(best, arg, vals, c, tag);
}

/// The portable body of [`max_step`].
#[inline(always)]
fn max_step_body(best: &mut [f32], arg: &mut [i32], vals: &[f32], c: f32, tag: i32) {
    let n = best.len().min(arg.len()).min(vals.len());
    for ((bv, g), &s) in best[..n].iter_mut().zip(arg[..n].iter_mut()).zip(&vals[..n]) {
        let v = s - c;
        let (old, og) = (*bv, *g);
        let m = -((v > old) as i32);
        *bv = f32::from_bits((v.to_bits() & m as u32) | (old.to_bits() & !m as u32));
        *g = (tag & m) | (og & !m);
    }
}

/// Reusable buffers of one transform.
#[derive(Default)]
struct Buffers {
    envelope: Scratch,
    ext: Vec<f32>,
    best: Vec<f32>,
    arg: Vec<i32>,
    line: Vec<f32>,
    out: Vec<f32>,
    out_arg: Vec<u16>,
}

/// 2-D transform with the windowed brute force where it is exact and cheap (see the module
/// doc); same contract as [`super::dt::distance_transform`].
pub fn transform(src: &ScoreMap, w: [f64; 4], offx: i64, offy: i64, rows: usize, cols: usize) -> Transformed {
    let (sr, sc) = (src.rows, src.cols);
    let mut buf = Buffers::default();
    // Pass 1 along y, row-major (rows out) x (sc).
    let mut tmp = vec![0f32; rows * sc];
    let mut tmp_iy = vec![0u16; rows * sc];
    let range = value_range(&src.data);
    match radius(w[2], w[3], range) {
        Some(r) => pass_y_window(src, w[2], w[3], range, offy, r, &mut tmp, &mut tmp_iy, &mut buf),
        None => {
            buf.line.resize(sr, 0.0);
            buf.out.resize(rows, 0.0);
            buf.out_arg.resize(rows, 0);
            for x in 0..sc {
                for y in 0..sr {
                    buf.line[y] = src.data[y * sc + x];
                }
                dt1d_fast(&buf.line, w[2], w[3], offy, &mut buf.out, &mut buf.out_arg, &mut buf.envelope);
                for y in 0..rows {
                    tmp[y * sc + x] = buf.out[y];
                    tmp_iy[y * sc + x] = buf.out_arg[y];
                }
            }
        }
    }
    // Pass 2 along x for every output row.
    let mut score = ScoreMap::filled(rows, cols, 0.0);
    let mut ix = vec![0u16; rows * cols];
    let mut iy = vec![0u16; rows * cols];
    for y in 0..rows {
        let line = &tmp[y * sc..(y + 1) * sc];
        let (d, g) = (&mut score.data[y * cols..(y + 1) * cols], &mut ix[y * cols..(y + 1) * cols]);
        let range = value_range(line);
        match radius(w[0], w[1], range) {
            Some(r) => line_window(line, w[0], w[1], range, offx, r, d, g, &mut buf),
            None => dt1d_fast(line, w[0], w[1], offx, d, g, &mut buf.envelope),
        }
        for x in 0..cols {
            iy[y * cols + x] = tmp_iy[y * sc + ix[y * cols + x] as usize];
        }
    }
    Transformed { score, ix, iy }
}

/// Pass along y over whole rows: output row y probes source row q = `off` + y; for q inside the
/// map only source rows within `r` of q can win, outside it those of [`outside_window`].
#[allow(clippy::too_many_arguments)]
fn pass_y_window(
    src: &ScoreMap,
    a: f64,
    b: f64,
    range: f64,
    off: i64,
    r: usize,
    tmp: &mut [f32],
    tmp_iy: &mut [u16],
    buf: &mut Buffers,
) {
    let (sr, sc) = (src.rows as i64, src.cols);
    let rows = tmp.len() / sc.max(1);
    buf.arg.resize(sc, 0);
    for y in 0..rows {
        let q = off + y as i64;
        let (lo, hi) = if (0..sr).contains(&q) {
            ((q - r as i64).max(0), (q + r as i64).min(sr - 1))
        } else {
            outside_window(a, b, range, q, sr)
        };
        let best = &mut tmp[y * sc..(y + 1) * sc];
        best.fill(f32::NEG_INFINITY);
        let arg = &mut buf.arg[..sc];
        arg.fill(lo as i32);
        for p in lo..=hi {
            let c = cost(a, b, q - p);
            let row = &src.data[p as usize * sc..(p as usize + 1) * sc];
            let pv = p as i32;
            max_step(best, arg, row, c, pv);
        }
        for (t, &g) in tmp_iy[y * sc..(y + 1) * sc].iter_mut().zip(arg.iter()) {
            *t = g as u16;
        }
    }
}

/// One line along x: output i probes q = `off` + i; candidates p = q + e for |e| ≤ `r`, as
/// shifted reads of a copy of the line padded with −∞; probes outside the line scan their [`outside_window`].
#[allow(clippy::too_many_arguments)]
fn line_window(
    line: &[f32],
    a: f64,
    b: f64,
    range: f64,
    off: i64,
    r: usize,
    dst: &mut [f32],
    arg: &mut [u16],
    buf: &mut Buffers,
) {
    let (n, m, ri) = (line.len() as i64, dst.len(), r as i64);
    // ext[p + pad] = line[p], −∞ elsewhere; every read base + i + e stays inside.
    let pad = ri + (-off).max(0);
    let len = (pad + n).max(pad + off + m as i64 + ri).max(0) as usize;
    buf.ext.clear();
    buf.ext.resize(len, f32::NEG_INFINITY);
    buf.ext[pad as usize..(pad + n) as usize].copy_from_slice(line);
    buf.best.clear();
    buf.best.resize(m, f32::NEG_INFINITY);
    buf.arg.clear();
    buf.arg.resize(m, -ri as i32);
    let (best, ea) = (&mut buf.best[..], &mut buf.arg[..m]);
    for e in -ri..=ri {
        let c = cost(a, b, -e);
        let start = (pad + off + e) as usize;
        let shifted = &buf.ext[start..start + m];
        let ev = e as i32;
        max_step(best, ea, shifted, c, ev);
    }
    for i in 0..m {
        let q = off + i as i64;
        if (0..n).contains(&q) {
            dst[i] = best[i];
            arg[i] = (q + ea[i] as i64) as u16;
        } else {
            let (lo, hi) = outside_window(a, b, range, q, n);
            let (mut bv, mut bp) = (f32::NEG_INFINITY, lo as usize);
            for p in lo as usize..=hi as usize {
                let v = line[p] - cost(a, b, q - p as i64);
                if v > bv {
                    bv = v;
                    bp = p;
                }
            }
            dst[i] = bv;
            arg[i] = bp as u16;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::dt::{distance_transform_envelope, distance_transform_reference};
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn radius_bounds_the_winning_displacements() {
        // a R² − |b| R must exceed the range for R + 1 and beyond.
        let r = radius(0.04, 0.01, 3.0).unwrap();
        assert_eq!(r, 9);
        assert!(0.04 * 9.0f64.powi(2) - 0.01 * 9.0 > 3.0);
        assert!(0.04 * 8.0f64.powi(2) - 0.01 * 8.0 < 3.0 + 0.04);
        assert_eq!(radius(0.04, 0.0, 0.0), Some(1));
        assert_eq!(radius(0.001, 0.0, 10.0), None);
        assert_eq!(radius(0.0, 0.0, 1.0), None);
        assert_eq!(radius(0.1, 0.0, f64::INFINITY), None);
        assert_eq!(radius(0.1, 0.0, f64::NAN), None);
        assert_eq!(value_range(&[1.0, -2.5, 0.0, 3.0, 1.0, 1.0, 1.0, 1.0, 1.0, -4.0]), 7.0);
        assert!(value_range(&[1.0, f32::NAN, 0.0]).is_nan());
        assert!(value_range(&[0.0; 9].iter().chain(&[f32::NEG_INFINITY]).copied().collect::<Vec<_>>()).is_nan());
    }

    /// Random maps, weights and shifts covering both the windowed and the fallback lines: the
    /// same maxima as the textbook reference, and the same arg-max. Values and weights are
    /// multiples of 1/8 on half the trials, so that costs and scores are exact in f32 and ties
    /// are real (b = 0 makes ±d tie): those must resolve like the reference too.
    #[test]
    fn windowed_equals_the_reference_on_random_data_with_ties() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut windowed, mut ties) = (0, 0);
        for trial in 0..300 {
            let exact = trial % 2 == 0;
            let (sr, sc) = (rng.random_range(1..50usize), rng.random_range(1..50usize));
            let span = if trial % 3 == 0 { 12.0 } else { 3.0 };
            let data = (0..sr * sc)
                .map(|_| {
                    let v: f32 = rng.random_range(-span..0.5);
                    if exact {
                        (v * 4.0).round() / 4.0
                    } else {
                        v
                    }
                })
                .collect();
            let src = ScoreMap { rows: sr, cols: sc, data };
            let mut wgt = || {
                if exact {
                    [0.125, 0.25, 0.5][rng.random_range(0..3usize)]
                } else {
                    rng.random_range(0.004..0.3)
                }
            };
            let (ax, ay) = (wgt(), wgt());
            let mut lin =
                || if exact { [0.0, 0.125, -0.25][rng.random_range(0..3usize)] } else { rng.random_range(-0.06..0.06) };
            let w = [ax, lin(), ay, lin()];
            let (offx, offy) = (rng.random_range(-6i64..6), rng.random_range(-6i64..6));
            let (rows, cols) = (rng.random_range(1..50usize), rng.random_range(1..50usize));
            windowed += radius(w[2], w[3], value_range(&src.data)).is_some() as usize;
            let f = transform(&src, w, offx, offy, rows, cols);
            let r = distance_transform_reference(&src, w, offx, offy, rows, cols);
            let e = distance_transform_envelope(&src, w, offx, offy, rows, cols);
            for i in 0..rows * cols {
                let (a, b) = (f.score.data[i], r.score.data[i]);
                assert!((a - b).abs() <= 1e-5 * (1.0 + b.abs()), "trial {trial} at {i}: {a} vs {b}");
                assert_eq!(e.score.data[i], b, "trial {trial} at {i}: envelope");
                if exact {
                    assert_eq!((f.ix[i], f.iy[i]), (r.ix[i], r.iy[i]), "trial {trial} at {i}: arg-max on exact data");
                    assert_eq!(a, b, "trial {trial} at {i}: exact data");
                    ties += (src.data.iter().filter(|&&v| v == src.data[0]).count() > 1) as usize;
                } else {
                    let (qx, qy) = ((offx + (i % cols) as i64) as f64, (offy + (i / cols) as i64) as f64);
                    let at = |cx: u16, cy: u16| {
                        let (dx, dy) = (qx - cx as f64, qy - cy as f64);
                        src.at(cx as usize, cy as usize) as f64
                            - w[0] * dx * dx
                            - w[1] * dx
                            - w[2] * dy * dy
                            - w[3] * dy
                    };
                    assert!(
                        (at(f.ix[i], f.iy[i]) - at(r.ix[i], r.iy[i])).abs() < 1e-5,
                        "trial {trial} at {i}: arg-max differs"
                    );
                }
            }
        }
        assert!(windowed > 100 && windowed < 300, "{windowed} of 300 trials windowed along y");
        assert!(ties > 1000, "{ties} outputs on maps with repeated values");
    }
}

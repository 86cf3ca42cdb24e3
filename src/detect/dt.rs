//! The generalised distance transform of Felzenszwalb & Huttenlocher for a quadratic
//! deformation, written as a maximum: `M(q) = max_v s(v) − a (q − v)² − b (q − v)` (a > 0),
//! computed exactly in linear time from the upper envelope of the parabolas (1-D), then per axis
//! (y first, then x) in 2-D. Output positions are shifted as in the authors' `shiftdt`: output
//! index i probes source position `offset + i`, so the anchor is applied at the same time.

use super::conv::ScoreMap;

/// 1-D transform of `src` into `len_out` outputs probing `offset + i`; writes the maxima to
/// `dst` and the maximising source indices to `arg`.
fn dt1d(
    src: &[f32],
    a: f64,
    b: f64,
    offset: i64,
    dst: &mut [f32],
    arg: &mut [u16],
    v: &mut Vec<usize>,
    z: &mut Vec<f64>,
) {
    let n = src.len();
    v.clear();
    v.resize(n, 0);
    z.clear();
    z.resize(n + 1, f64::INFINITY);
    z[0] = f64::NEG_INFINITY;
    let f = |i: usize| -(src[i] as f64); // minimise a(q-v)² + b(q-v) − s(v)
    let inter = |q: usize, p: usize| {
        let (qf, pf) = (q as f64, p as f64);
        ((f(q) - f(p)) + a * (qf * qf - pf * pf) - b * (qf - pf)) / (2.0 * a * (qf - pf))
    };
    let mut k = 0usize;
    for q in 1..n {
        let mut s = inter(q, v[k]);
        while k > 0 && s <= z[k] {
            k -= 1;
            s = inter(q, v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    read_envelope(src, a, b, offset, |k| v[k], z, dst, arg);
}

/// Evaluates an upper envelope at the probes `offset + i`: parabola k (vertex `vertex(k)`) is
/// the maximum on z[k] .. z[k+1]; writes each probe's value to `dst` and its vertex to `arg`.
#[allow(clippy::too_many_arguments)]
fn read_envelope(
    src: &[f32],
    a: f64,
    b: f64,
    offset: i64,
    vertex: impl Fn(usize) -> usize,
    z: &[f64],
    dst: &mut [f32],
    arg: &mut [u16],
) {
    let mut k = 0;
    for (i, (d, g)) in dst.iter_mut().zip(arg.iter_mut()).enumerate() {
        let q = (offset + i as i64) as f64;
        while z[k + 1] < q {
            k += 1;
        }
        let p = vertex(k);
        let dq = q - p as f64;
        *d = (src[p] as f64 - a * dq * dq - b * dq) as f32;
        *g = p as u16;
    }
}

/// Scratch buffers of [`dt1d_fast`], reused across the lines of a transform.
#[derive(Default)]
pub(super) struct Scratch {
    /// Envelope parabola vertices.
    v: Vec<u32>,
    /// Envelope boundaries (z[k] .. z[k+1] is where parabola k is the maximum).
    z: Vec<f64>,
    /// h(p) = a p² − b p − s(p): intersections are (h(q) − h(p)) / (2 a (q − p)).
    h: Vec<f64>,
    /// 1 / (2 a d) for d = 0..n (d = 0 unused), for a = `recip_a`.
    recip: Vec<f64>,
    /// The quadratic weight `recip` was computed for.
    recip_a: f64,
}

/// The same transform as [`dt1d`] with the per-vertex terms and the reciprocals of the
/// intersection denominators precomputed (no division and no closure in the envelope loop) and
/// buffers reused. This is the kernel of [`distance_transform_envelope`] and the fallback of the
/// windowed kernel. (Filling the outputs one
/// envelope segment at a time was tried and was slower on real score maps: segments are short.)
pub(super) fn dt1d_fast(src: &[f32], a: f64, b: f64, offset: i64, dst: &mut [f32], arg: &mut [u16], s: &mut Scratch) {
    let n = src.len();
    if s.recip.len() < n || s.recip_a != a {
        s.recip.clear();
        s.recip.push(0.0);
        s.recip.extend((1..n).map(|d| 1.0 / (2.0 * a * d as f64)));
        s.recip_a = a;
    }
    s.h.clear();
    s.h.extend(src.iter().enumerate().map(|(p, &v)| {
        let pf = p as f64;
        a * pf * pf - b * pf - v as f64
    }));
    s.v.resize(n, 0);
    s.z.resize(n + 1, 0.0);
    let (h, r, v, z) = (&s.h[..n], &s.recip[..n], &mut s.v[..n], &mut s.z[..n + 1]);
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    let mut k = 0usize;
    for q in 1..n {
        let hq = h[q];
        loop {
            let p = v[k] as usize;
            let x = (hq - h[p]) * r[q - p];
            if k == 0 || x > z[k] {
                k += 1;
                v[k] = q as u32;
                z[k] = x;
                break;
            }
            k -= 1;
        }
    }
    z[k + 1] = f64::INFINITY;
    read_envelope(src, a, b, offset, |k| v[k] as usize, z, dst, arg);
}

/// Result of a 2-D transform: best scores and the child positions attaining them.
#[derive(Clone, Debug)]
pub struct Transformed {
    /// Best score per output position (`rows` x `cols` of the parent grid).
    pub score: ScoreMap,
    /// Child x (column) per output position.
    pub ix: Vec<u16>,
    /// Child y (row) per output position.
    pub iy: Vec<u16>,
}

/// 2-D transform of the child score map `src` with deformation weights `w` = (dx², dx, dy², dy)
/// (a cost subtracted from the score, dx = probe − child position), probing child position
/// (offx + x, offy + y) for output (x, y) of a `rows` x `cols` grid. The exact pruned
/// (windowed brute-force) kernel of [`super::dtwin`] where its window is small, the envelope
/// kernel elsewhere; equal to [`distance_transform_reference`] up to float rounding (arg-max
/// equal except at ties within rounding).
pub fn distance_transform(src: &ScoreMap, w: [f64; 4], offx: i64, offy: i64, rows: usize, cols: usize) -> Transformed {
    super::dtwin::transform(src, w, offx, offy, rows, cols)
}

/// [`distance_transform`] with the lower-envelope kernel on every line (precomputed terms, no
/// pruning): the optimised kernel before the windowed one, kept for comparison.
pub fn distance_transform_envelope(
    src: &ScoreMap,
    w: [f64; 4],
    offx: i64,
    offy: i64,
    rows: usize,
    cols: usize,
) -> Transformed {
    let mut s = Scratch::default();
    separable(src, rows, cols, |line, axis, dst, arg| {
        let (a, b, off) = if axis == 0 { (w[2], w[3], offy) } else { (w[0], w[1], offx) };
        dt1d_fast(line, a, b, off, dst, arg, &mut s);
    })
}

/// The plain reference of [`distance_transform`] (the textbook 1-D envelope per line).
pub fn distance_transform_reference(
    src: &ScoreMap,
    w: [f64; 4],
    offx: i64,
    offy: i64,
    rows: usize,
    cols: usize,
) -> Transformed {
    let (mut v, mut z) = (Vec::new(), Vec::new());
    separable(src, rows, cols, |line, axis, dst, arg| {
        let (a, b, off) = if axis == 0 { (w[2], w[3], offy) } else { (w[0], w[1], offx) };
        dt1d(line, a, b, off, dst, arg, &mut v, &mut z);
    })
}

/// The 2-D driver: `line_dt(line, axis, dst, arg)` transforms one source line (axis 0: a column,
/// along y; axis 1: a row of the pass-1 result, along x), first along y for every source
/// column, then along x for every output row.
fn separable(
    src: &ScoreMap,
    rows: usize,
    cols: usize,
    mut line_dt: impl FnMut(&[f32], usize, &mut [f32], &mut [u16]),
) -> Transformed {
    let (sr, sc) = (src.rows, src.cols);
    // Pass 1 along y for every source column: tmp is (rows out) x (sc), stored column-major.
    let mut col = vec![0f32; sr];
    let mut tmp = vec![0f32; sc * rows];
    let mut tmp_iy = vec![0u16; sc * rows];
    for x in 0..sc {
        for y in 0..sr {
            col[y] = src.data[y * sc + x];
        }
        line_dt(&col, 0, &mut tmp[x * rows..(x + 1) * rows], &mut tmp_iy[x * rows..(x + 1) * rows]);
    }
    // Pass 2 along x for every output row.
    let mut score = ScoreMap::filled(rows, cols, 0.0);
    let mut ix = vec![0u16; rows * cols];
    let mut iy = vec![0u16; rows * cols];
    let mut line = vec![0f32; sc];
    for y in 0..rows {
        for x in 0..sc {
            line[x] = tmp[x * rows + y];
        }
        let (d, g) = (&mut score.data[y * cols..(y + 1) * cols], &mut ix[y * cols..(y + 1) * cols]);
        line_dt(&line, 1, d, g);
        for x in 0..cols {
            iy[y * cols + x] = tmp_iy[ix[y * cols + x] as usize * rows + y];
        }
    }
    Transformed { score, ix, iy }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_brute_force() {
        let (sr, sc) = (9, 11);
        let src = ScoreMap {
            rows: sr,
            cols: sc,
            data: (0..sr * sc).map(|i| ((i * 7919 % 97) as f32 - 48.0) / 10.0).collect(),
        };
        for &(w, offx, offy, rows, cols) in &[
            ([0.3, 0.1, 0.5, -0.2], 0i64, 0i64, 9usize, 11usize),
            ([0.01, -0.05, 0.02, 0.04], -3, 4, 7, 13),
            ([2.0, 0.0, 1.0, 0.0], 5, -2, 12, 6),
        ] {
            let t = distance_transform(&src, w, offx, offy, rows, cols);
            for y in 0..rows {
                for x in 0..cols {
                    let (qx, qy) = ((offx + x as i64) as f64, (offy + y as i64) as f64);
                    let mut best = f64::NEG_INFINITY;
                    for cy in 0..sr {
                        for cx in 0..sc {
                            let (dx, dy) = (qx - cx as f64, qy - cy as f64);
                            let s = src.at(cx, cy) as f64 - w[0] * dx * dx - w[1] * dx - w[2] * dy * dy - w[3] * dy;
                            best = best.max(s);
                        }
                    }
                    let got = t.score.at(x, y) as f64;
                    assert!((got - best).abs() < 1e-4, "w {w:?} ({x},{y}): {got} vs {best}");
                    let (cx, cy) = (t.ix[y * cols + x] as f64, t.iy[y * cols + x] as f64);
                    let (dx, dy) = (qx - cx, qy - cy);
                    let at = src.at(cx as usize, cy as usize) as f64
                        - w[0] * dx * dx
                        - w[1] * dx
                        - w[2] * dy * dy
                        - w[3] * dy;
                    assert!((at - best).abs() < 1e-4, "argmax at ({x},{y})");
                }
            }
        }
    }

    /// The optimised kernel equals the textbook reference on random maps, weights and shifts
    /// (same maxima, same arg-max wherever the maximum is not a tie).
    #[test]
    fn fast_matches_the_reference_on_random_data() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for trial in 0..40 {
            let (sr, sc) = (rng.random_range(1..60usize), rng.random_range(1..60usize));
            let src =
                ScoreMap { rows: sr, cols: sc, data: (0..sr * sc).map(|_| rng.random_range(-3.0f32..1.0)).collect() };
            let w = [
                rng.random_range(0.005..0.5),
                rng.random_range(-0.1..0.1),
                rng.random_range(0.005..0.5),
                rng.random_range(-0.1..0.1),
            ];
            let (offx, offy) = (rng.random_range(-8i64..8), rng.random_range(-8i64..8));
            let (rows, cols) = (rng.random_range(1..60usize), rng.random_range(1..60usize));
            let f = distance_transform(&src, w, offx, offy, rows, cols);
            let r = distance_transform_reference(&src, w, offx, offy, rows, cols);
            for i in 0..rows * cols {
                let (a, b) = (f.score.data[i], r.score.data[i]);
                assert!((a - b).abs() <= 1e-5 * (1.0 + b.abs()), "trial {trial} at {i}: {a} vs {b}");
                if (f.ix[i], f.iy[i]) != (r.ix[i], r.iy[i]) {
                    // Only an exact tie may pick another child position.
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
                        (at(f.ix[i], f.iy[i]) - at(r.ix[i], r.iy[i])).abs() < 1e-9,
                        "trial {trial} at {i}: arg-max differs"
                    );
                }
            }
        }
    }
}

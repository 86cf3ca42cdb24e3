//! The generalised distance transform of Felzenszwalb & Huttenlocher for a quadratic
//! deformation, written as a maximum: `M(q) = max_v s(v) − a (q − v)² − b (q − v)` (a > 0),
//! computed exactly in linear time from the upper envelope of the parabolas (1-D), then per axis
//! (y first, then x) in 2-D. Output positions are shifted as in the authors' `shiftdt`: output
//! index i probes source position `offset + i`, so the anchor is applied at the same time.

use super::conv::ScoreMap;

/// 1-D transform of `src` into `len_out` outputs probing `offset + i`; writes the maxima to
/// `dst` and the maximising source indices to `arg`.
fn dt1d(src: &[f32], a: f64, b: f64, offset: i64, dst: &mut [f32], arg: &mut [u16], v: &mut Vec<usize>, z: &mut Vec<f64>) {
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
    let mut k = 0;
    for (i, (d, g)) in dst.iter_mut().zip(arg.iter_mut()).enumerate() {
        let q = (offset + i as i64) as f64;
        while z[k + 1] < q {
            k += 1;
        }
        let p = v[k];
        let dq = q - p as f64;
        *d = (src[p] as f64 - a * dq * dq - b * dq) as f32;
        *g = p as u16;
    }
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
/// (offx + x, offy + y) for output (x, y) of a `rows` x `cols` grid.
pub fn distance_transform(src: &ScoreMap, w: [f64; 4], offx: i64, offy: i64, rows: usize, cols: usize) -> Transformed {
    let (sr, sc) = (src.rows, src.cols);
    let mut v = Vec::with_capacity(sr.max(sc) + 1);
    let mut z = Vec::with_capacity(sr.max(sc) + 2);
    // Pass 1 along y for every source column: tmp is (rows out) x (sc), stored column-major.
    let mut col = vec![0f32; sr];
    let mut tmp = vec![0f32; sc * rows];
    let mut tmp_iy = vec![0u16; sc * rows];
    for x in 0..sc {
        for y in 0..sr {
            col[y] = src.data[y * sc + x];
        }
        dt1d(&col, w[2], w[3], offy, &mut tmp[x * rows..(x + 1) * rows], &mut tmp_iy[x * rows..(x + 1) * rows], &mut v, &mut z);
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
        dt1d(&line, w[0], w[1], offx, d, g, &mut v, &mut z);
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
        let src = ScoreMap { rows: sr, cols: sc, data: (0..sr * sc).map(|i| ((i * 7919 % 97) as f32 - 48.0) / 10.0).collect() };
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
                    let at = src.at(cx as usize, cy as usize) as f64 - w[0] * dx * dx - w[1] * dx - w[2] * dy * dy - w[3] * dy;
                    assert!((at - best).abs() < 1e-4, "argmax at ({x},{y})");
                }
            }
        }
    }
}

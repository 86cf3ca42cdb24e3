//! Part filter responses: valid-mode correlation of each filter with a padded feature map,
//! `response(x, y) = Σ_{dy,dx,f} feat(x+dx, y+dy, f) · w(dy, dx, f)` (the DPM code's `fconv`),
//! filters in parallel. One filter row (cols × 32 values) is contiguous in both the filter and the
//! feature map, so the inner loop is a long dot product the compiler vectorises.

use rayon::prelude::*;

use super::hog::FeatureMap;
use super::model::{Filter, FEAT_DIM};

/// A dense score map, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct ScoreMap {
    /// Rows (y).
    pub rows: usize,
    /// Columns (x).
    pub cols: usize,
    /// `rows * cols` values.
    pub data: Vec<f32>,
}

impl ScoreMap {
    /// A map filled with `v`.
    pub fn filled(rows: usize, cols: usize, v: f32) -> Self {
        Self { rows, cols, data: vec![v; rows * cols] }
    }
    /// Value at (x, y).
    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.cols + x]
    }
}

/// Dot product with 8 independent accumulators (vectorisable).
#[inline]
fn dot(a: &[f32], b: &[f32]) -> f32 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0f32; 8];
    let mut ca = a.chunks_exact(8);
    let mut cb = b.chunks_exact(8);
    for (x, y) in (&mut ca).zip(&mut cb) {
        for i in 0..8 {
            acc[i] += x[i] * y[i];
        }
    }
    let mut s: f32 = acc.iter().sum();
    for (x, y) in ca.remainder().iter().zip(cb.remainder()) {
        s += x * y;
    }
    s
}

/// Response of one filter on `feat`; `None` when the filter does not fit.
pub fn response(feat: &FeatureMap, f: &Filter) -> Option<ScoreMap> {
    if feat.rows < f.rows || feat.cols < f.cols {
        return None;
    }
    let (rows, cols) = (feat.rows - f.rows + 1, feat.cols - f.cols + 1);
    let row_len = feat.cols * FEAT_DIM;
    let span = f.cols * FEAT_DIM;
    let mut out = ScoreMap::filled(rows, cols, 0.0);
    for y in 0..rows {
        let o = &mut out.data[y * cols..(y + 1) * cols];
        for dy in 0..f.rows {
            let frow = &feat.data[(y + dy) * row_len..(y + dy + 1) * row_len];
            let wrow = &f.w[dy * span..(dy + 1) * span];
            for (x, v) in o.iter_mut().enumerate() {
                *v += dot(&frow[x * FEAT_DIM..x * FEAT_DIM + span], wrow);
            }
        }
    }
    Some(out)
}

/// Responses of all `filters` on `feat` (index = filter id; `None` where a filter does not fit),
/// by matrix products ([`super::fastconv`]); equal to [`responses_reference`] up to float
/// summation order (relative differences ~1e-6).
pub fn responses(feat: &FeatureMap, filters: &[Filter]) -> Vec<Option<ScoreMap>> {
    super::fastconv::responses(feat, filters)
}

/// The plain scalar reference of [`responses`]: dot products per position, rows in parallel;
/// within a row every filter reuses the same few feature rows while they are in cache.
pub fn responses_reference(feat: &FeatureMap, filters: &[Filter]) -> Vec<Option<ScoreMap>> {
    let same = filters.first().map(|f| (f.rows, f.cols));
    if filters.len() < 2 || filters.iter().any(|f| Some((f.rows, f.cols)) != same) {
        return filters.par_iter().map(|f| response(feat, f)).collect();
    }
    let (fr, fc) = same.unwrap_or((1, 1));
    if feat.rows < fr || feat.cols < fc {
        return filters.iter().map(|_| None).collect();
    }
    let (rows, cols, nf) = (feat.rows - fr + 1, feat.cols - fc + 1, filters.len());
    let row_len = feat.cols * FEAT_DIM;
    let span = fc * FEAT_DIM;
    // Layout (y, filter, x) while computing, then split per filter.
    let mut buf = vec![0f32; rows * nf * cols];
    buf.par_chunks_mut(nf * cols).enumerate().for_each(|(y, out)| {
        for (f, o) in filters.iter().zip(out.chunks_exact_mut(cols)) {
            for dy in 0..fr {
                let frow = &feat.data[(y + dy) * row_len..(y + dy + 1) * row_len];
                let wrow = &f.w[dy * span..(dy + 1) * span];
                for (x, v) in o.iter_mut().enumerate() {
                    *v += dot(&frow[x * FEAT_DIM..x * FEAT_DIM + span], wrow);
                }
            }
        }
    });
    (0..nf)
        .map(|k| {
            let mut m = ScoreMap::filled(rows, cols, 0.0);
            for y in 0..rows {
                m.data[y * cols..(y + 1) * cols].copy_from_slice(&buf[(y * nf + k) * cols..(y * nf + k + 1) * cols]);
            }
            Some(m)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_a_naive_correlation() {
        let feat = FeatureMap {
            rows: 6,
            cols: 7,
            data: (0..6 * 7 * FEAT_DIM).map(|i| ((i * 37 % 101) as f32 - 50.0) / 50.0).collect(),
        };
        let f = Filter {
            rows: 3,
            cols: 2,
            w: (0..3 * 2 * FEAT_DIM).map(|i| ((i * 13 % 29) as f32 - 14.0) / 7.0).collect(),
        };
        let r = response(&feat, &f).unwrap();
        assert_eq!((r.rows, r.cols), (4, 6));
        for y in 0..4 {
            for x in 0..6 {
                let mut s = 0f64;
                for dy in 0..3 {
                    for dx in 0..2 {
                        for k in 0..FEAT_DIM {
                            s += feat.cell(x + dx, y + dy)[k] as f64 * f.w[(dy * 2 + dx) * FEAT_DIM + k] as f64;
                        }
                    }
                }
                assert!((r.at(x, y) as f64 - s).abs() < 1e-3, "({x},{y}): {} vs {s}", r.at(x, y));
            }
        }
        let big = Filter { rows: 7, cols: 1, w: vec![0.0; 7 * FEAT_DIM] };
        assert!(response(&feat, &big).is_none());
        // The batched path (equal sizes) equals the single-filter path.
        let g = Filter { w: f.w.iter().map(|v| -0.5 * v).collect(), ..f.clone() };
        let all = responses_reference(&feat, &[f.clone(), g.clone()]);
        assert_eq!(all[0].as_ref(), Some(&r));
        assert_eq!(all[1], response(&feat, &g));
        assert!(responses_reference(&feat, &[big.clone(), big.clone()]).iter().all(Option::is_none));
        assert!(responses(&feat, &[big.clone(), big]).iter().all(Option::is_none));
    }

    /// The matrix-product path equals the scalar reference on random maps and filters of mixed
    /// sizes (some not fitting), up to float summation order.
    #[test]
    fn fast_path_matches_the_reference_on_random_data() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let sizes = [(5, 5), (5, 5), (3, 2), (5, 5), (1, 1), (2, 4), (5, 5), (9, 3)];
        let filters: Vec<Filter> = sizes
            .iter()
            .map(|&(rows, cols)| Filter {
                rows,
                cols,
                w: (0..rows * cols * FEAT_DIM).map(|_| rng.random_range(-1.0..1.0)).collect(),
            })
            .collect();
        for &(rows, cols) in &[(5usize, 5usize), (6, 40), (37, 23), (120, 9), (8, 70)] {
            let feat = FeatureMap {
                rows,
                cols,
                data: (0..rows * cols * FEAT_DIM).map(|_| rng.random_range(0.0..0.4)).collect(),
            };
            let fast = responses(&feat, &filters);
            for (k, f) in filters.iter().enumerate() {
                let want = response(&feat, f);
                match (&fast[k], &want) {
                    (None, None) => assert!(f.rows > rows || f.cols > cols),
                    (Some(a), Some(b)) => {
                        assert_eq!((a.rows, a.cols), (b.rows, b.cols), "filter {k} on {rows}x{cols}");
                        for (i, (x, y)) in a.data.iter().zip(&b.data).enumerate() {
                            assert!(
                                (x - y).abs() <= 1e-4 * (1.0 + y.abs()),
                                "filter {k} on {rows}x{cols} at {i}: {x} vs {y}"
                            );
                        }
                    }
                    _ => panic!("filter {k} on {rows}x{cols}: fits in one path only"),
                }
            }
        }
    }
}

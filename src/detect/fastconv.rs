//! Fast part filter responses as matrix products (the optimised path behind
//! [`conv::responses`](super::conv::responses); [`conv::responses_reference`](super::conv::responses_reference)
//! is the plain scalar reference it is tested against).
//!
//! For a filter of `fr` x `fc` cells, the response at output position p = y · cols + x (cols =
//! the feature map's width, so the last `fc − 1` columns of every row are computed and dropped)
//! is Σ_dy ⟨window_dy(p), w_dy⟩, where window_dy(p) is the `fc · 32` contiguous values starting at
//! cell (x, y + dy) and w_dy the filter's row dy. Stacking the windows of all positions gives a
//! matrix whose rows overlap in memory (row stride 32 values, column stride 1), so no im2col copy
//! is needed: per dy one product (positions x fc·32) · (fc·32 x filters) accumulates into the
//! (positions x filters) result. Filters of equal size share the products; the products run on
//! nalgebra's general matrix multiply (matrixmultiply's cache-blocked kernels with run-time
//! AVX2/FMA/AVX-512 selection), in row bands on rayon.

use nalgebra::{DMatrix, DMatrixView, Dyn};
use rayon::prelude::*;

use super::conv::ScoreMap;
use super::hog::FeatureMap;
use super::model::{Filter, FEAT_DIM};

/// Target number of output positions per parallel band (a few matrixmultiply row blocks).
const BAND_POSITIONS: usize = 2048;
/// nalgebra hands a product to matrixmultiply only when every dimension exceeds 5; its own
/// small-matrix loop is slow and mishandles the overlapping window rows (it corrupted memory in
/// a trial), so groups of at most this many filters and bands of at most this many positions
/// take the scalar path.
const MIN_GEMM_DIM: usize = 5;

/// Responses of all `filters` on `feat` (index = filter id; `None` where a filter does not fit),
/// equal to the reference up to float summation order.
pub fn responses(feat: &FeatureMap, filters: &[Filter]) -> Vec<Option<ScoreMap>> {
    let mut out: Vec<Option<ScoreMap>> = filters.iter().map(|_| None).collect();
    // Group filters by size; each group shares its matrix products.
    let mut sizes: Vec<(usize, usize)> = filters.iter().map(|f| (f.rows, f.cols)).collect();
    sizes.sort_unstable();
    sizes.dedup();
    for (fr, fc) in sizes {
        if feat.rows < fr || feat.cols < fc {
            continue;
        }
        let ids: Vec<usize> = (0..filters.len()).filter(|&k| (filters[k].rows, filters[k].cols) == (fr, fc)).collect();
        let group: Vec<&Filter> = ids.iter().map(|&k| &filters[k]).collect();
        if group.len() <= MIN_GEMM_DIM {
            // Too few filters to share a product: the scalar path.
            for k in ids {
                out[k] = super::conv::response(feat, &filters[k]);
            }
            continue;
        }
        for (k, m) in ids.into_iter().zip(group_responses(feat, &group)) {
            out[k] = Some(m);
        }
    }
    out
}

/// Responses of filters that all have the same size and fit in `feat`.
fn group_responses(feat: &FeatureMap, group: &[&Filter]) -> Vec<ScoreMap> {
    let (fr, fc) = (group[0].rows, group[0].cols);
    let (rows, cols) = (feat.rows - fr + 1, feat.cols - fc + 1);
    let (n, len) = (group.len(), fr * fc * FEAT_DIM);
    let span = fc * FEAT_DIM;
    // All weights, filter after filter: row dy of filter g starts at g·len + dy·span.
    let weights: Vec<f32> = group.iter().flat_map(|f| f.w.iter().copied()).collect();
    let band_rows = (BAND_POSITIONS / feat.cols).clamp(1, rows);
    let bands: Vec<(usize, usize)> = (0..rows).step_by(band_rows).map(|y0| (y0, (y0 + band_rows).min(rows))).collect();
    // Per band: a (positions x filters) column-major matrix, positions p = (y − y0) · feat.cols + x.
    let results: Vec<DMatrix<f32>> = bands
        .par_iter()
        .map(|&(y0, y1)| {
            let m = (y1 - y0 - 1) * feat.cols + cols;
            let mut c = DMatrix::<f32>::zeros(m, n);
            if m <= MIN_GEMM_DIM {
                // A band of a few positions: plain dot products.
                for (g, f) in group.iter().enumerate() {
                    for p in 0..m {
                        c[(p, g)] = (0..fr)
                            .map(|dy| {
                                let at = ((y0 + dy) * feat.cols) * FEAT_DIM + p * FEAT_DIM;
                                feat.data[at..at + span]
                                    .iter()
                                    .zip(&f.w[dy * span..(dy + 1) * span])
                                    .map(|(a, b)| a * b)
                                    .sum::<f32>()
                            })
                            .sum();
                    }
                }
                return c;
            }
            for dy in 0..fr {
                let start = (y0 + dy) * feat.cols * FEAT_DIM;
                // Windows: row p at start + 32 p, `span` values (in bounds: the last window of the
                // last band ends at the end of row y1 − 1 + dy ≤ feat.rows − 1).
                let a = DMatrixView::from_slice_with_strides_generic(
                    &feat.data[start..],
                    Dyn(m),
                    Dyn(span),
                    Dyn(FEAT_DIM),
                    Dyn(1),
                );
                let w = DMatrixView::from_slice_with_strides_generic(
                    &weights[dy * span..],
                    Dyn(span),
                    Dyn(n),
                    Dyn(1),
                    Dyn(len),
                );
                c.gemm(1.0, &a, &w, 1.0);
            }
            c
        })
        .collect();
    (0..n)
        .map(|g| {
            let mut s = ScoreMap::filled(rows, cols, 0.0);
            for (&(y0, y1), c) in bands.iter().zip(&results) {
                let col = c.column(g);
                let col = col.as_slice();
                for y in y0..y1 {
                    let p = (y - y0) * feat.cols;
                    s.data[y * cols..(y + 1) * cols].copy_from_slice(&col[p..p + cols]);
                }
            }
            s
        })
        .collect()
}

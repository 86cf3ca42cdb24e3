//! PCA through the Gram matrix (samples ≪ coordinates): eigenvectors u_k of X Xᵀ give unit
//! basis vectors v_k = Xᵀ u_k / √λ_k and sample weights √λ_k · u_k. Side data that is linear in
//! the shape (the joints) gets the same combination: J_k = X_jᵀ u_k / √λ_k.

use nalgebra::{DMatrix, SymmetricEigen};
use rayon::prelude::*;

use crate::error::{Error, Result};

/// A PCA of row samples.
pub struct Pca {
    /// Mean sample.
    pub mean: Vec<f64>,
    /// Mean of the side data.
    pub side_mean: Vec<f64>,
    /// Unit-norm basis vectors, largest variance first.
    pub basis: Vec<Vec<f64>>,
    /// Side-data displacement per unit weight of each basis vector.
    pub side_basis: Vec<Vec<f64>>,
    /// Every eigenvalue of the centred Gram matrix (sum of squares along each direction),
    /// descending, negative round-off clipped to 0.
    pub eigenvalues: Vec<f64>,
    /// Training weights: `weights[i][k]` is sample i's weight on basis vector k.
    pub weights: Vec<Vec<f64>>,
}

fn centre(rows: &[Vec<f64>]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = rows.len() as f64;
    let dim = rows[0].len();
    let mean: Vec<f64> = (0..dim).map(|d| rows.iter().map(|r| r[d]).sum::<f64>() / n).collect();
    let centred = rows.par_iter().map(|r| r.iter().zip(&mean).map(|(a, m)| a - m).collect()).collect();
    (mean, centred)
}

/// PCA of `samples` (n rows of equal length) keeping `k` components (`k < n`), carrying the
/// per-sample `side` rows along. Deterministic for any thread count: every sum runs in a fixed
/// order inside one task. Each basis vector's sign makes its largest-magnitude entry positive.
pub fn pca(samples: &[Vec<f64>], side: &[Vec<f64>], k: usize) -> Result<Pca> {
    let n = samples.len();
    if n < 2 || k == 0 || k >= n || side.len() != n {
        return Err(Error::OutOfRange {
            name: "PCA sizes",
            detail: format!("{n} samples, {} side rows, {k} components (need 0 < k < n)", side.len()),
        });
    }
    let (mean, x) = centre(samples);
    let (side_mean, xs) = centre(side);
    // Upper triangle only (row i holds j = i..n); every dot product runs in index order.
    let gram_rows: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|i| (i..n).map(|j| x[i].iter().zip(&x[j]).map(|(a, b)| a * b).sum()).collect())
        .collect();
    let gram = DMatrix::from_fn(n, n, |i, j| if i <= j { gram_rows[i][j - i] } else { gram_rows[j][i - j] });
    let eig = SymmetricEigen::new(gram);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]).then(a.cmp(&b)));
    let eigenvalues: Vec<f64> = order.iter().map(|&i| eig.eigenvalues[i].max(0.0)).collect();
    if eigenvalues[k - 1] <= 0.0 {
        return Err(Error::OutOfRange {
            name: "PCA components",
            detail: format!("only {} non-zero components", eigenvalues.iter().filter(|&&l| l > 0.0).count()),
        });
    }
    // Σ_i u_i · row_i / s, accumulated over the rows in order.
    let combine = |rows: &[Vec<f64>], u: &[f64], s: f64| -> Vec<f64> {
        let mut acc = vec![0.0; rows[0].len()];
        for (r, ui) in rows.iter().zip(u) {
            for (a, v) in acc.iter_mut().zip(r) {
                *a += ui * v;
            }
        }
        acc.iter().map(|a| a / s).collect()
    };
    let parts: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> = (0..k)
        .into_par_iter()
        .map(|c| {
            let col = order[c];
            let mut u: Vec<f64> = eig.eigenvectors.column(col).iter().copied().collect();
            let s = eigenvalues[c].sqrt();
            let mut v = combine(&x, &u, s);
            let big = v.iter().copied().fold(0.0f64, |best, e| if e.abs() > best.abs() { e } else { best });
            if big < 0.0 {
                v.iter_mut().for_each(|e| *e = -*e);
                u.iter_mut().for_each(|e| *e = -*e);
            }
            let j = combine(&xs, &u, s);
            (v, j, u.iter().map(|e| e * s).collect())
        })
        .collect();
    let mut basis = Vec::with_capacity(k);
    let mut side_basis = Vec::with_capacity(k);
    let mut weights = vec![vec![0.0; k]; n];
    for (c, (v, j, w)) in parts.into_iter().enumerate() {
        basis.push(v);
        side_basis.push(j);
        for (i, wi) in w.into_iter().enumerate() {
            weights[i][c] = wi;
        }
    }
    Ok(Pca { mean, side_mean, basis, side_basis, eigenvalues, weights })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_planar_cloud_and_its_side_data() {
        // Points on a line in 3-D (direction (1,2,2)/3) plus small noise along (0,1,-1)/√2.
        let dir = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
        let ts = [-2.0, -1.0, 0.0, 1.0, 2.0, 3.0];
        let es = [0.1, -0.1, -0.1, 0.1, 0.0, 0.0];
        let rows: Vec<Vec<f64>> = ts
            .iter()
            .zip(&es)
            .map(|(t, e)| (0..3).map(|d| t * dir[d] + e * [0.0, 1.0, -1.0][d] / 2f64.sqrt()).collect())
            .collect();
        let side: Vec<Vec<f64>> = ts.iter().map(|t| vec![2.0 * t + 1.0]).collect();
        let p = pca(&rows, &side, 2).unwrap();
        for d in 0..3 {
            assert!((p.basis[0][d] - dir[d]).abs() < 1e-9, "basis 0 entry {d}: {} vs {}", p.basis[0][d], dir[d]);
        }
        // Side data is exactly linear in t, which is the weight on component 0 (+ mean).
        assert!((p.side_basis[0][0] - 2.0).abs() < 1e-9, "side basis {}", p.side_basis[0][0]);
        let total: f64 = p.eigenvalues.iter().sum();
        let sq: f64 = rows.iter().flat_map(|r| r.iter().zip(&p.mean).map(|(a, m)| (a - m).powi(2))).sum();
        assert!((total - sq).abs() < 1e-9);
        for (i, t) in ts.iter().enumerate() {
            assert!((p.weights[i][0] - (t - 0.5)).abs() < 1e-9, "weight {i}");
        }
        assert!(pca(&rows, &side, 6).is_err());
    }
}

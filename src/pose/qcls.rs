//! Least squares under the two-sided quadratic constraint of eq. (3):
//! minimise ‖A w − r‖² subject to lo ≤ g(w) ≤ hi, g(w) = ‖e + E w‖² − Σ l².
//!
//! With H = AᵀA (plus a 1e-12 relative ridge) = L Lᵀ and L⁻¹ EᵀE L⁻ᵀ = V Λ Vᵀ, the KKT point of
//! an active bound is `z(λ) = (β − λγ) / (1 + λΛ)` (elementwise; β = VᵀL⁻¹Aᵀr,
//! γ = VᵀL⁻¹Eᵀe, w = L⁻ᵀV z), and g(z(λ)) decreases monotonically in λ on (−1/Λ_max, ∞). So:
//! the unconstrained solution (λ = 0) if it is feasible; else bisection for λ > 0 (upper bound,
//! convex: global optimum) or λ ∈ (−1/Λ_max, 0) (lower bound: the global optimum of a
//! trust-region-like problem), including the "hard case". The bound is met to ~1e-14 relative.

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::problem::LengthConstraint;

/// Outcome of [`solve`].
#[derive(Clone, Debug)]
pub struct QclsSolution {
    /// The weights.
    pub w: DVector<f64>,
    /// Whether lo ≤ g(w) ≤ hi could be met (otherwise `w` is the least violating point found).
    pub feasible: bool,
}

/// Solves the constrained least squares (see the module doc). `a` is m × k with k ≥ 1.
pub fn solve(a: &DMatrix<f64>, r: &DVector<f64>, con: &LengthConstraint, lo: f64, hi: f64) -> QclsSolution {
    let k = a.ncols();
    let h = a.transpose() * a;
    let scale = (h.trace() / k as f64).max(f64::MIN_POSITIVE);
    let mut ridge = 1e-12 * scale;
    let chol = loop {
        let mut hr = h.clone();
        for i in 0..k {
            hr[(i, i)] += ridge;
        }
        if let Some(c) = hr.cholesky() {
            break c;
        }
        ridge *= 100.0;
    };
    let l = chol.l();
    let q = con.em.transpose() * &con.em;
    let qv = con.em.transpose() * &con.e;
    let c0 = con.e.norm_squared() - con.sum_sq;
    // M = L⁻¹ Q L⁻ᵀ
    let w1 = l.solve_lower_triangular(&q).unwrap_or_else(|| DMatrix::zeros(k, k));
    let m = l.solve_lower_triangular(&w1.transpose()).unwrap_or_else(|| DMatrix::zeros(k, k));
    let m = (&m + m.transpose()) * 0.5;
    let eig = SymmetricEigen::new(m);
    let lam: Vec<f64> = eig.eigenvalues.iter().map(|v| v.max(0.0)).collect();
    let v = eig.eigenvectors;
    let atr = a.transpose() * r;
    let beta = v.transpose() * l.solve_lower_triangular(&atr).unwrap_or_else(|| DVector::zeros(k));
    let gamma = v.transpose() * l.solve_lower_triangular(&qv).unwrap_or_else(|| DVector::zeros(k));
    let z_of = |mu: f64| -> DVector<f64> {
        DVector::from_iterator(k, (0..k).map(|i| (beta[i] - mu * gamma[i]) / (1.0 + mu * lam[i])))
    };
    let g_of =
        |z: &DVector<f64>| -> f64 { (0..k).map(|i| lam[i] * z[i] * z[i] + 2.0 * gamma[i] * z[i]).sum::<f64>() + c0 };
    // g(z(μ)) without building z(μ) (the same arithmetic as `g_of(&z_of(μ))`).
    let g_at = |mu: f64| -> f64 {
        (0..k)
            .map(|i| {
                let z = (beta[i] - mu * gamma[i]) / (1.0 + mu * lam[i]);
                lam[i] * z * z + 2.0 * gamma[i] * z
            })
            .sum::<f64>()
            + c0
    };
    let back = |z: &DVector<f64>| -> DVector<f64> {
        l.transpose().solve_upper_triangular(&(&v * z)).unwrap_or_else(|| DVector::zeros(k))
    };

    let z0 = z_of(0.0);
    let g0 = g_of(&z0);
    if g0 >= lo && g0 <= hi {
        return QclsSolution { w: back(&z0), feasible: true };
    }
    let lmax = lam.iter().cloned().fold(0.0, f64::max);
    if !(lmax > 0.0) {
        return QclsSolution { w: back(&z0), feasible: false };
    }
    if g0 > hi {
        // λ > 0: bracket then bisect.
        let (mut a_l, mut b_l) = (0.0, 1.0 / lmax);
        let mut n = 0;
        while g_at(b_l) > hi {
            a_l = b_l;
            b_l *= 4.0;
            n += 1;
            if n > 200 {
                return QclsSolution { w: back(&z_of(b_l)), feasible: false };
            }
        }
        let mu = bisect(a_l, b_l, |mu| g_at(mu) - hi);
        return QclsSolution { w: back(&z_of(mu)), feasible: true };
    }
    // g0 < lo: λ in (−1/Λmax, 0).
    let lower = -1.0 / lmax;
    let mut inner = 0.0;
    for n in 1..=60 {
        let mu = lower * (1.0 - 0.5f64.powi(n));
        if g_at(mu) >= lo {
            let mu = bisect(inner, mu, |mu| g_at(mu) - lo);
            return QclsSolution { w: back(&z_of(mu)), feasible: true };
        }
        inner = mu;
    }
    // Hard case: at λ = −1/Λmax the top eigen-directions are free; move along one to reach lo.
    let top = (0..k).fold(0, |b, i| if lam[i] > lam[b] { i } else { b });
    let mut z = DVector::from_iterator(
        k,
        (0..k).map(|i| {
            if (lam[i] - lmax).abs() <= 1e-12 * lmax {
                0.0
            } else {
                (beta[i] - lower * gamma[i]) / (1.0 + lower * lam[i])
            }
        }),
    );
    let rest = g_of(&z);
    // g(z + t e_top) = rest + lmax t² + 2 (lmax z_top + γ_top) t, with z_top = 0.
    let (qa, qb, qc) = (lmax, 2.0 * gamma[top], rest - lo);
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return QclsSolution { w: back(&z), feasible: false };
    }
    z[top] = (-qb + disc.sqrt()) / (2.0 * qa);
    QclsSolution { w: back(&z), feasible: true }
}

/// Bisection for the sign change of a decreasing-in-|x − a| function between `a` (f ≥ 0 side
/// or ≤ 0 side) and `b`; returns the end point whose f is on the feasible side (f ≤ 0 for the
/// upper bound search, f ≥ 0 for the lower), refined to machine precision.
fn bisect(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let fb = f(b);
    let (mut a, mut b) = (a, b);
    for _ in 0..200 {
        let mid = 0.5 * (a + b);
        if mid == a || mid == b {
            break;
        }
        if (f(mid) > 0.0) == (fb > 0.0) {
            b = mid;
        } else {
            a = mid;
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_problem(seed: u64) -> (DMatrix<f64>, DVector<f64>, LengthConstraint) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut m = |r: usize, c: usize| DMatrix::from_fn(r, c, |_, _| rng.random_range(-1.0..1.0));
        let a = m(20, 4);
        let r = m(20, 1).column(0).into_owned();
        let em = m(12, 4);
        let e = m(12, 1).column(0).into_owned();
        (a, r, LengthConstraint { e, em, sum_sq: 3.0 })
    }

    #[test]
    fn meets_active_bounds_and_beats_feasible_samples() {
        use rand::{Rng, SeedableRng};
        for seed in 0..20 {
            let (a, r, con) = random_problem(seed);
            let free = solve(&a, &r, &con, -1e9, 1e9).w;
            let g_free = con.value(&free);
            // Smallest reachable g: at w = −Q⁺q.
            let q = con.em.transpose() * &con.em;
            let w_min = -(q.clone().pseudo_inverse(1e-12).unwrap() * con.em.transpose() * &con.e);
            let g_min = con.value(&w_min);
            assert!(g_min < g_free);
            let mid = 0.5 * (g_min + g_free);
            for (lo, hi) in [(mid - 1.0, mid), (g_free + 0.5, g_free + 1.0), (mid, mid)] {
                let s = solve(&a, &r, &con, lo, hi);
                assert!(s.feasible, "seed {seed}");
                let g = con.value(&s.w);
                assert!(g >= lo - 1e-9 && g <= hi + 1e-9, "seed {seed}: g = {g} not in [{lo}, {hi}]");
                let f = (&a * &s.w - &r).norm_squared();
                // No feasible random perturbation (retracted onto the bound) does better.
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed + 100);
                for _ in 0..200 {
                    let d = DVector::from_fn(4, |_, _| rng.random_range(-0.3..0.3));
                    let target = if g > 0.5 * (lo + hi) { hi } else { lo };
                    if let Some(w2) = con.retract(&(&s.w + d), &con.gradient(&s.w), target) {
                        let f2 = (&a * &w2 - &r).norm_squared();
                        assert!(f2 >= f - 1e-9 * f.max(1.0), "seed {seed}: {f2} < {f}");
                    }
                }
            }
        }
    }
}

//! The structured-SVM quadratic program, solved by dual coordinate descent (Hsieh et al. 2008)
//! over a cache of examples, as Yang & Ramanan train their model:
//! minimise ½‖w‖² + C Σᵢ max(0, 1 − yᵢ w·φᵢ) subject to w_j ≥ lb on the quadratic deformation
//! weights. The dual keeps one αᵢ ∈ [0, C] per cached example; with v = Σ αᵢ yᵢ φᵢ the optimal
//! multipliers of the bounds give w_j = max(v_j, lb) on bounded coordinates and w_j = v_j
//! elsewhere, so each coordinate step updates v and re-derives w on the touched coordinates.

use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::features::SparseVec;

/// One cached example.
#[derive(Clone, Debug)]
pub struct Example {
    /// Its feature vector.
    pub x: SparseVec,
    /// +1 (a figure) or −1 (a background configuration).
    pub y: f64,
    /// Dual variable in [0, C].
    pub alpha: f64,
    /// Identity (for de-duplicating mined negatives); positives use their index.
    pub key: u64,
    /// ‖x‖², cached.
    norm2: f64,
}

impl Example {
    /// A new example with α = 0.
    pub fn new(x: SparseVec, y: f64, key: u64) -> Example {
        let norm2 = x.norm2();
        Example { x, y, alpha: 0.0, key, norm2 }
    }
}

/// Solver state.
pub struct Qp {
    /// Σ αᵢ yᵢ φᵢ (unconstrained part of w).
    v: Vec<f64>,
    /// The effective w (bounds applied).
    pub w: Vec<f64>,
    lower: Vec<Option<f64>>,
    /// Box bound of every α.
    pub c: f64,
    /// The cache.
    pub examples: Vec<Example>,
}

/// What a solve did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveStats {
    /// Passes over the cache.
    pub passes: usize,
    /// Largest projected-gradient violation in the last pass.
    pub violation: f64,
    /// Primal objective ½‖w‖² + C Σ hinge.
    pub primal: f64,
    /// Support vectors (α > 0).
    pub support: usize,
}

impl Qp {
    /// A solver for `dim` parameters, `bounded` coordinates bounded below by `lb`.
    pub fn new(dim: usize, bounded: &[usize], lb: f64, c: f64) -> Qp {
        let mut lower = vec![None; dim];
        let mut w = vec![0.0; dim];
        for &o in bounded {
            lower[o] = Some(lb);
            w[o] = lb;
        }
        Qp { v: vec![0.0; dim], w, lower, c, examples: Vec::new() }
    }

    fn step(&mut self, i: usize) -> f64 {
        let e = &self.examples[i];
        if e.norm2 <= 0.0 {
            return 0.0;
        }
        let g = e.y * e.x.dot(&self.w) - 1.0;
        let pg = if e.alpha <= 0.0 {
            g.min(0.0)
        } else if e.alpha >= self.c {
            g.max(0.0)
        } else {
            g
        };
        if pg.abs() < 1e-12 {
            return 0.0;
        }
        let new = (e.alpha - g / e.norm2).clamp(0.0, self.c);
        let d = (new - e.alpha) * e.y;
        if d != 0.0 {
            e.x.add_to(&mut self.v, d);
            for &(o, n) in &e.x.blocks {
                for j in o as usize..(o + n) as usize {
                    self.w[j] = match self.lower[j] {
                        Some(lb) => self.v[j].max(lb),
                        None => self.v[j],
                    };
                }
            }
        }
        self.examples[i].alpha = new;
        pg.abs()
    }

    /// Coordinate descent until the largest violation is below `tol` or `max_passes` passes;
    /// the visiting order of each pass is a permutation drawn from `seed`.
    pub fn solve(&mut self, max_passes: usize, tol: f64, seed: u64) -> SolveStats {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut order: Vec<usize> = (0..self.examples.len()).collect();
        let mut passes = 0;
        let mut violation = f64::INFINITY;
        while passes < max_passes && violation > tol {
            order.shuffle(&mut rng);
            violation = 0.0;
            for &i in &order {
                violation = violation.max(self.step(i));
            }
            passes += 1;
        }
        SolveStats {
            passes,
            violation,
            primal: self.primal(),
            support: self.examples.iter().filter(|e| e.alpha > 0.0).count(),
        }
    }

    /// ½‖w‖² + C Σ hinge over the cache.
    pub fn primal(&self) -> f64 {
        let reg = 0.5 * self.w.iter().map(|x| x * x).sum::<f64>();
        reg + self.c * self.examples.iter().map(|e| (1.0 - e.y * e.x.dot(&self.w)).max(0.0)).sum::<f64>()
    }

    /// Drops cached negatives with α = 0 that are outside the margin by more than `slack`
    /// (w · φ < −1 − slack), then, when more than `max_negatives` remain, those with α = 0 and
    /// the lowest scores. Never drops positives or support vectors, so w is unchanged.
    pub fn prune(&mut self, slack: f64, max_negatives: usize) {
        let w = &self.w;
        self.examples.retain(|e| e.y > 0.0 || e.alpha > 0.0 || e.x.dot(w) >= -1.0 - slack);
        let negs = self.examples.iter().filter(|e| e.y < 0.0).count();
        if negs > max_negatives {
            let mut free: Vec<(f64, usize)> = self
                .examples
                .iter()
                .enumerate()
                .filter(|(_, e)| e.y < 0.0 && e.alpha <= 0.0)
                .map(|(i, e)| (e.x.dot(w), i))
                .collect();
            free.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let drop: std::collections::HashSet<usize> =
                free.iter().take(negs - max_negatives).map(|&(_, i)| i).collect();
            let mut k = 0;
            self.examples.retain(|_| {
                k += 1;
                !drop.contains(&(k - 1))
            });
        }
    }

    /// Keys of the cached examples (for de-duplication).
    pub fn has_key(&self, key: u64) -> bool {
        self.examples.iter().any(|e| e.key == key)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sv(v: &[f32]) -> SparseVec {
        SparseVec { blocks: vec![(0, v.len() as u32)], values: v.to_vec() }
    }

    #[test]
    fn separates_a_small_problem_with_the_margin_and_respects_bounds() {
        let mut qp = Qp::new(3, &[2], 0.5, 10.0);
        qp.examples.push(Example::new(sv(&[2.0, 1.0, 0.0]), 1.0, 0));
        qp.examples.push(Example::new(sv(&[1.5, 2.0, 0.0]), 1.0, 1));
        qp.examples.push(Example::new(sv(&[-1.0, -0.5, 1.0]), -1.0, 2));
        qp.examples.push(Example::new(sv(&[-2.0, 0.5, 0.0]), -1.0, 3));
        let s = qp.solve(1000, 1e-9, 1);
        assert!(s.violation <= 1e-9, "{s:?}");
        for e in &qp.examples {
            assert!(e.y * e.x.dot(&qp.w) >= 1.0 - 1e-6, "margin {}", e.y * e.x.dot(&qp.w));
        }
        assert!(qp.w[2] >= 0.5);
        // The negative's third feature pushes w[2] down; the bound holds it at 0.5.
        assert_eq!(qp.w[2], 0.5);
        // Same seed, same solution.
        let w1 = qp.w.clone();
        let mut again = Qp::new(3, &[2], 0.5, 10.0);
        again.examples = qp.examples.iter().map(|e| Example::new(e.x.clone(), e.y, e.key)).collect();
        again.solve(1000, 1e-9, 1);
        assert_eq!(again.w, w1);
    }

    #[test]
    fn pruning_keeps_support_vectors() {
        let mut qp = Qp::new(2, &[], 0.0, 1.0);
        qp.examples.push(Example::new(sv(&[1.0, 0.0]), 1.0, 0));
        qp.examples.push(Example::new(sv(&[-1.0, 0.0]), -1.0, 1));
        qp.examples.push(Example::new(sv(&[-50.0, 0.0]), -1.0, 2));
        qp.solve(1000, 1e-9, 3);
        let w = qp.w.clone();
        qp.prune(0.5, 10);
        assert_eq!(qp.examples.len(), 2);
        assert!(qp.has_key(1) && !qp.has_key(2));
        assert_eq!(qp.w, w);
    }
}

//! Mixture labels: k-means (Lloyd's algorithm, k-means++ seeding from a seed) on 2-D offsets.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn d2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

/// Labels in `0..k` for `points` (k ≥ 1; fewer distinct points than k leave clusters empty but
/// labels valid), deterministic for a seed; 50 Lloyd iterations at most.
pub fn kmeans(points: &[[f64; 2]], k: usize, seed: u64) -> Vec<usize> {
    if points.is_empty() || k <= 1 {
        return vec![0; points.len()];
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut centres = vec![points[rng.random_range(0..points.len())]];
    while centres.len() < k {
        let dist: Vec<f64> =
            points.iter().map(|&p| centres.iter().map(|&c| d2(p, c)).fold(f64::INFINITY, f64::min)).collect();
        let total: f64 = dist.iter().sum();
        if total <= 0.0 {
            centres.push(centres[0]);
            continue;
        }
        let mut r = rng.random_range(0.0..total);
        let mut pick = points.len() - 1;
        for (i, &d) in dist.iter().enumerate() {
            if r < d {
                pick = i;
                break;
            }
            r -= d;
        }
        centres.push(points[pick]);
    }
    let nearest = |p: [f64; 2], cs: &[[f64; 2]]| {
        (0..cs.len()).min_by(|&a, &b| d2(p, cs[a]).total_cmp(&d2(p, cs[b]))).unwrap_or(0)
    };
    let mut labels: Vec<usize> = points.iter().map(|&p| nearest(p, &centres)).collect();
    for _ in 0..50 {
        let mut sum = vec![[0.0; 2]; k];
        let mut n = vec![0usize; k];
        for (&p, &l) in points.iter().zip(&labels) {
            sum[l][0] += p[0];
            sum[l][1] += p[1];
            n[l] += 1;
        }
        for c in 0..k {
            if n[c] > 0 {
                centres[c] = [sum[c][0] / n[c] as f64, sum[c][1] / n[c] as f64];
            }
        }
        let next: Vec<usize> = points.iter().map(|&p| nearest(p, &centres)).collect();
        if next == labels {
            break;
        }
        labels = next;
    }
    labels
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_well_separated_groups() {
        let mut pts = Vec::new();
        for i in 0..30 {
            let j = (i % 5) as f64 * 0.1;
            pts.push([j, j]);
            pts.push([10.0 + j, j]);
            pts.push([j, -10.0 - j]);
        }
        let l = kmeans(&pts, 3, 7);
        assert_eq!(l, kmeans(&pts, 3, 7));
        for g in 0..3 {
            let first = l[g];
            assert!((0..30).all(|i| l[3 * i + g] == first), "group {g} split");
        }
        assert!(l[0] != l[1] && l[1] != l[2] && l[0] != l[2]);
        assert_eq!(kmeans(&pts, 1, 7), vec![0; pts.len()]);
    }
}

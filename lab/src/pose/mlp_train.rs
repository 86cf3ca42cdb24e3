//! Training the learned factor prior's small network ([`Mlp`]) by mini-batch Adam on the mean
//! squared error, in `f32` on one thread, deterministic for a seed.

use nalgebra::DMatrix;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};

use sketchbody::error::{Error, Result};
use sketchbody::pose::mlp::{Layer, Mlp};

/// Parameters of [`train`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlpParams {
    /// Width of each hidden layer.
    pub hidden: usize,
    /// Number of hidden layers (≥ 1).
    pub hidden_layers: usize,
    /// Passes over the training samples.
    pub epochs: usize,
    /// Samples per Adam step.
    pub batch: usize,
    /// Adam's initial step size, decayed to 0 along a cosine over the epochs.
    pub learning_rate: f64,
    /// Seed of the initial weights and of the sample order.
    pub seed: u64,
}

impl Default for MlpParams {
    fn default() -> Self {
        MlpParams { hidden: 128, hidden_layers: 2, epochs: 20, batch: 256, learning_rate: 1e-3, seed: 1 }
    }
}

/// Adam's moment estimates of one parameter array.
struct Moments {
    m: DMatrix<f32>,
    v: DMatrix<f32>,
}

impl Moments {
    fn zeros(r: usize, c: usize) -> Self {
        Moments { m: DMatrix::zeros(r, c), v: DMatrix::zeros(r, c) }
    }

    /// One Adam step on `p` with gradient `g`, step size `lr`, step number `t` (from 1).
    fn step(&mut self, p: &mut DMatrix<f32>, g: &DMatrix<f32>, lr: f32, t: i32) {
        const B1: f32 = 0.9;
        const B2: f32 = 0.999;
        const EPS: f32 = 1e-8;
        let (c1, c2) = (1.0 - B1.powi(t), 1.0 - B2.powi(t));
        for ((p, g), (m, v)) in p.iter_mut().zip(g.iter()).zip(self.m.iter_mut().zip(self.v.iter_mut())) {
            *m = B1 * *m + (1.0 - B1) * g;
            *v = B2 * *v + (1.0 - B2) * g * g;
            *p -= lr * (*m / c1) / ((*v / c2).sqrt() + EPS);
        }
    }
}

/// Trains a network from `x` (one sample per column, already standardised) to `t` (one target
/// vector per column) by mini-batch Adam on the mean squared error (module doc); `progress` is
/// called after each epoch with the epoch number and its mean training loss. Errors:
/// [`Error::OutOfRange`] for no samples, mismatched columns or zero-sized parameters,
/// [`Error::Degenerate`] when the training diverges (non-finite weights).
pub fn train(x: &DMatrix<f32>, t: &DMatrix<f32>, p: &MlpParams, mut progress: impl FnMut(usize, f64)) -> Result<Mlp> {
    let n = x.ncols();
    if n == 0 || t.ncols() != n || x.nrows() == 0 || t.nrows() == 0 {
        return Err(Error::OutOfRange { name: "samples", detail: format!("{n} inputs, {} targets", t.ncols()) });
    }
    if p.hidden == 0 || p.hidden_layers == 0 || p.batch == 0 || p.epochs == 0 || !(p.learning_rate > 0.0) {
        return Err(Error::OutOfRange { name: "network parameters", detail: format!("{p:?}") });
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(p.seed);
    let mut sizes = vec![x.nrows()];
    sizes.extend(std::iter::repeat_n(p.hidden, p.hidden_layers));
    sizes.push(t.nrows());
    // Weights and biases U(±1/√inputs).
    let mut w: Vec<DMatrix<f32>> = Vec::new();
    let mut b: Vec<DMatrix<f32>> = Vec::new();
    for k in 0..sizes.len() - 1 {
        let r = 1.0 / (sizes[k] as f32).sqrt();
        w.push(DMatrix::from_fn(sizes[k + 1], sizes[k], |_, _| rng.random_range(-r..=r)));
        b.push(DMatrix::from_fn(sizes[k + 1], 1, |_, _| rng.random_range(-r..=r)));
    }
    let mut mw: Vec<Moments> = w.iter().map(|m| Moments::zeros(m.nrows(), m.ncols())).collect();
    let mut mb: Vec<Moments> = b.iter().map(|m| Moments::zeros(m.nrows(), 1)).collect();
    let mut order: Vec<usize> = (0..n).collect();
    let steps_per_epoch = n.div_ceil(p.batch);
    let total = (p.epochs * steps_per_epoch) as f64;
    let mut step = 0usize;
    let layers = w.len();
    for epoch in 0..p.epochs {
        order.shuffle(&mut rng);
        let mut loss = 0.0f64;
        for chunk in order.chunks(p.batch) {
            let m = chunk.len();
            let xb = DMatrix::from_fn(x.nrows(), m, |r, c| x[(r, chunk[c])]);
            let tb = DMatrix::from_fn(t.nrows(), m, |r, c| t[(r, chunk[c])]);
            // Forward, keeping each layer's activation.
            let mut acts = vec![xb];
            for k in 0..layers {
                let mut z = &w[k] * &acts[k];
                for mut col in z.column_iter_mut() {
                    col += b[k].column(0);
                }
                if k + 1 < layers {
                    z.apply(|v| *v = v.tanh());
                }
                acts.push(z);
            }
            let out = &acts[layers];
            let diff = out - &tb;
            loss += diff.iter().map(|v| (*v as f64).powi(2)).sum::<f64>() / t.nrows() as f64;
            let mut delta = diff * (2.0 / (m * t.nrows()) as f32);
            // Backward and the Adam step, last layer first.
            step += 1;
            let lr = (0.5 * p.learning_rate * (1.0 + (std::f64::consts::PI * (step - 1) as f64 / total).cos())) as f32;
            for k in (0..layers).rev() {
                let gw = &delta * acts[k].transpose();
                let gb = DMatrix::from_fn(delta.nrows(), 1, |r, _| delta.row(r).sum());
                let next = if k > 0 {
                    let mut d = w[k].transpose() * &delta;
                    d.zip_apply(&acts[k], |g, a| *g *= 1.0 - a * a);
                    Some(d)
                } else {
                    None
                };
                mw[k].step(&mut w[k], &gw, lr, step as i32);
                mb[k].step(&mut b[k], &gb, lr, step as i32);
                if let Some(d) = next {
                    delta = d;
                }
            }
        }
        progress(epoch + 1, loss / n as f64);
    }
    let net = Mlp {
        layers: (0..layers)
            .map(|k| Layer {
                inputs: w[k].ncols(),
                outputs: w[k].nrows(),
                weights: (0..w[k].nrows()).flat_map(|r| w[k].row(r).iter().copied().collect::<Vec<_>>()).collect(),
                bias: b[k].iter().copied().collect(),
            })
            .collect(),
    };
    net.check("trained network").map_err(|_| Error::Degenerate("network training diverged".into()))?;
    Ok(net)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth nonlinear target a linear model cannot follow.
    fn data(n: usize, seed: u64) -> (DMatrix<f32>, DMatrix<f32>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let x = DMatrix::from_fn(3, n, |_, _| rng.random_range(-1.5f32..=1.5));
        let t = DMatrix::from_fn(2, n, |r, c| {
            let (a, b, d) = (x[(0, c)], x[(1, c)], x[(2, c)]);
            if r == 0 {
                a * b + d.sin()
            } else {
                (a - d).abs() - 0.5 * b * b
            }
        });
        (x, t)
    }

    fn mse(net: &Mlp, x: &DMatrix<f32>, t: &DMatrix<f32>) -> f64 {
        let mut s = 0.0;
        for c in 0..x.ncols() {
            let xi: Vec<f64> = x.column(c).iter().map(|v| *v as f64).collect();
            let y = net.forward(&xi).unwrap();
            s += y.iter().zip(t.column(c).iter()).map(|(a, b)| (a - *b as f64).powi(2)).sum::<f64>();
        }
        s / (x.ncols() * t.nrows()) as f64
    }

    #[test]
    fn training_fits_a_nonlinear_function_and_is_deterministic() {
        let (x, t) = data(4000, 1);
        let (xv, tv) = data(1000, 2);
        let p = MlpParams { hidden: 32, epochs: 30, batch: 64, learning_rate: 3e-3, ..MlpParams::default() };
        let mut losses = Vec::new();
        let net = train(&x, &t, &p, |_, l| losses.push(l)).unwrap();
        assert_eq!(losses.len(), 30);
        assert!(losses[29] < 0.2 * losses[0], "{losses:?}");
        // The variance of the held-out targets.
        let var = {
            let m: Vec<f64> = (0..2).map(|r| tv.row(r).iter().map(|v| *v as f64).sum::<f64>() / 1000.0).collect();
            tv.column_iter().map(|c| (0..2).map(|r| (c[r] as f64 - m[r]).powi(2)).sum::<f64>()).sum::<f64>() / 2000.0
        };
        let held = mse(&net, &xv, &tv);
        assert!(held < 0.05 * var, "held-out mse {held} against variance {var}");
        let again = train(&x, &t, &p, |_, _| ()).unwrap();
        assert_eq!(net, again);
        let other = train(&x, &t, &MlpParams { seed: 2, ..p }, |_, _| ()).unwrap();
        assert_ne!(net, other);
        assert!(net.forward(&[0.0; 2]).is_none());
        net.check("net").unwrap();
    }

    #[test]
    fn bad_input_is_rejected() {
        let (x, t) = data(10, 1);
        let p = MlpParams::default();
        assert!(matches!(train(&x, &t.columns(0, 5).into_owned(), &p, |_, _| ()), Err(Error::OutOfRange { .. })));
        assert!(matches!(train(&x, &t, &MlpParams { hidden: 0, ..p }, |_, _| ()), Err(Error::OutOfRange { .. })));
        assert!(matches!(
            train(&x, &t, &MlpParams { learning_rate: 0.0, ..p }, |_, _| ()),
            Err(Error::OutOfRange { .. })
        ));
        train(&x, &t, &MlpParams { epochs: 1, hidden: 4, ..p }, |_, _| ()).unwrap().check("n").unwrap();
    }
}

//! A small fully connected network (tanh hidden layers, a linear output layer): the regressor of
//! the learned factor prior ([`super::factor_prior`]). Inference is in `f64` from weights stored
//! as `f32`; the training is in the `sketchbody-lab` crate.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// One dense layer: `y = W x + b`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    /// Number of inputs.
    pub inputs: usize,
    /// Number of outputs.
    pub outputs: usize,
    /// Weights, row-major: `outputs` rows of `inputs`.
    pub weights: Vec<f32>,
    /// Biases, one per output.
    pub bias: Vec<f32>,
}

/// The network: every layer but the last is followed by `tanh`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mlp {
    /// The layers, input first.
    pub layers: Vec<Layer>,
}

impl Mlp {
    /// Number of inputs (0 for a network without layers).
    pub fn inputs(&self) -> usize {
        self.layers.first().map_or(0, |l| l.inputs)
    }

    /// Number of outputs (0 for a network without layers).
    pub fn outputs(&self) -> usize {
        self.layers.last().map_or(0, |l| l.outputs)
    }

    /// Checks the shapes (each layer's inputs are the previous layer's outputs, arrays of their
    /// sizes) and that every value is finite. Errors: [`Error::CorruptData`] naming `what`.
    pub fn check(&self, what: &str) -> Result<()> {
        if self.layers.is_empty() {
            return Err(Error::CorruptData(format!("{what}: a network without layers")));
        }
        for (i, l) in self.layers.iter().enumerate() {
            let chained = i == 0 || self.layers[i - 1].outputs == l.inputs;
            if !chained
                || l.inputs == 0
                || l.outputs == 0
                || l.weights.len() != l.inputs * l.outputs
                || l.bias.len() != l.outputs
            {
                return Err(Error::CorruptData(format!("{what}: layer {i} has arrays of the wrong size")));
            }
            if l.weights.iter().chain(&l.bias).any(|v| !v.is_finite()) {
                return Err(Error::CorruptData(format!("{what}: layer {i} has non-finite weights")));
            }
        }
        Ok(())
    }

    /// The network's output for `x` (length [`Self::inputs`]); `None` when `x` has another
    /// length.
    pub fn forward(&self, x: &[f64]) -> Option<Vec<f64>> {
        if x.len() != self.inputs() {
            return None;
        }
        let mut a = x.to_vec();
        for (i, l) in self.layers.iter().enumerate() {
            let hidden = i + 1 < self.layers.len();
            a = (0..l.outputs)
                .map(|o| {
                    let row = &l.weights[o * l.inputs..(o + 1) * l.inputs];
                    let v = row.iter().zip(&a).fold(l.bias[o] as f64, |s, (w, x)| s + *w as f64 * x);
                    if hidden {
                        v.tanh()
                    } else {
                        v
                    }
                })
                .collect();
        }
        Some(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn net() -> Mlp {
        let layer = |inputs: usize, outputs: usize| Layer {
            inputs,
            outputs,
            weights: (0..inputs * outputs).map(|k| 0.1 * k as f32 - 0.2).collect(),
            bias: vec![0.05; outputs],
        };
        Mlp { layers: vec![layer(3, 4), layer(4, 2)] }
    }

    #[test]
    fn forward_applies_tanh_then_the_linear_output() {
        let n = net();
        let x = [0.5, -1.0, 2.0];
        let h: Vec<f64> = (0..4)
            .map(|o| {
                let w = &n.layers[0].weights[3 * o..3 * o + 3];
                (0.05f32 as f64 + w.iter().zip(&x).map(|(w, x)| *w as f64 * x).sum::<f64>()).tanh()
            })
            .collect();
        let y = n.forward(&x).unwrap();
        for o in 0..2 {
            let w = &n.layers[1].weights[4 * o..4 * o + 4];
            let want = 0.05f32 as f64 + w.iter().zip(&h).map(|(w, h)| *w as f64 * h).sum::<f64>();
            assert!((y[o] - want).abs() < 1e-12, "{o}: {} vs {want}", y[o]);
        }
        assert!(n.forward(&[0.0; 2]).is_none());
        assert_eq!((n.inputs(), n.outputs()), (3, 2));
    }

    #[test]
    fn corrupt_networks_are_rejected() {
        let net = net();
        net.check("n").unwrap();
        let mut bad = net.clone();
        bad.layers[1].weights.pop();
        assert!(matches!(bad.check("n"), Err(Error::CorruptData(m)) if m.contains("wrong size")));
        let mut bad = net.clone();
        bad.layers[0].bias[0] = f32::NAN;
        assert!(matches!(bad.check("n"), Err(Error::CorruptData(m)) if m.contains("non-finite")));
        assert!(Mlp { layers: vec![] }.check("n").is_err());
    }
}

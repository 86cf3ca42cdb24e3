//! The joint feature vector φ of a placement and the parameter vector w, laid out so that the
//! engine's score of a configuration is exactly `w · φ` (`tree::detect_level` adds filter
//! responses and co-occurrence biases and subtracts `d · (dx², dx, dy², dy)`).
//!
//! Layout of w (all parts have the same K mixtures and F×F filters):
//! - filter of (part i, mixture m): `F·F·32` weights at `(i·K + m)·F·F·32` (y, x, feature);
//! - deformation of (part i ≥ 1, mixture m): 4 weights (dx², dx, dy², dy) at
//!   `DEF0 + ((i−1)·K + m)·4`; φ holds `−(dx², dx, dy², dy)` with dx = parent + anchor − 1 − child;
//! - bias of the root: one weight at `BIAS0`; of (part i ≥ 1, parent mixture l, mixture m): at
//!   `BIAS0 + 1 + ((i−1)·K + l)·K + m`; φ holds 1 there.

use sketchbody::detect::hog::FeatureMap;
use sketchbody::detect::model::{Deformation, Filter, Model, Part, FEAT_DIM};
use sketchbody::error::Result;

use super::layout::{NUM_PARTS, PARENT, PART_TO_JOINT};

/// Lower bound on the quadratic deformation weights (the engine needs them > 0).
pub const DEF_LOWER_BOUND: f64 = 0.01;

/// The fixed structure of a trained model: mixtures, filter size, anchors.
#[derive(Clone, Debug, PartialEq)]
pub struct Structure {
    /// HOG cell size, px.
    pub sbin: usize,
    /// Pyramid levels per octave.
    pub interval: usize,
    /// Mixtures per part.
    pub k: usize,
    /// Filter side, cells.
    pub side: usize,
    /// Anchor (ax, ay) of (part, mixture), 1-based cells; the root's entries are unused.
    pub anchors: Vec<Vec<[i32; 2]>>,
}

/// A placement of every part on one feature map: (x, y) of the filter's top-left cell and the
/// mixture, in part order.
pub type Placement = Vec<(usize, usize, usize)>;

/// A sparse feature vector: blocks of consecutive coordinates of w.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseVec {
    /// (offset in w, length) of each block, in the order of `values`.
    pub blocks: Vec<(u32, u32)>,
    /// Concatenated block values.
    pub values: Vec<f32>,
}

impl SparseVec {
    /// `w · self`.
    pub fn dot(&self, w: &[f64]) -> f64 {
        let mut s = 0.0;
        let mut k = 0;
        for &(o, n) in &self.blocks {
            let (o, n) = (o as usize, n as usize);
            s += w[o..o + n].iter().zip(&self.values[k..k + n]).map(|(a, &b)| a * b as f64).sum::<f64>();
            k += n;
        }
        s
    }
    /// `w += a · self`.
    pub fn add_to(&self, w: &mut [f64], a: f64) {
        let mut k = 0;
        for &(o, n) in &self.blocks {
            let (o, n) = (o as usize, n as usize);
            for (x, &v) in w[o..o + n].iter_mut().zip(&self.values[k..k + n]) {
                *x += a * v as f64;
            }
            k += n;
        }
    }
    /// Squared norm.
    pub fn norm2(&self) -> f64 {
        self.values.iter().map(|&v| (v as f64) * (v as f64)).sum()
    }
}

impl Structure {
    /// Weights per filter.
    pub fn filter_len(&self) -> usize {
        self.side * self.side * FEAT_DIM
    }
    fn def0(&self) -> usize {
        NUM_PARTS * self.k * self.filter_len()
    }
    fn bias0(&self) -> usize {
        self.def0() + (NUM_PARTS - 1) * self.k * 4
    }
    /// Length of w.
    pub fn dim(&self) -> usize {
        self.bias0() + 1 + (NUM_PARTS - 1) * self.k * self.k
    }
    /// Offsets in w of the quadratic deformation weights (bounded below by [`DEF_LOWER_BOUND`]).
    pub fn bounded(&self) -> Vec<usize> {
        (0..(NUM_PARTS - 1) * self.k).flat_map(|d| [self.def0() + 4 * d, self.def0() + 4 * d + 2]).collect()
    }

    /// The initial w: zero filters and biases, deformation weights (0.01, 0, 0.01, 0).
    pub fn initial_w(&self) -> Vec<f64> {
        let mut w = vec![0.0; self.dim()];
        for o in self.bounded() {
            w[o] = DEF_LOWER_BOUND;
        }
        w
    }

    /// φ of `placement` on `feat`. Every filter window must lie inside the map (callers clamp).
    pub fn features(&self, feat: &FeatureMap, placement: &[(usize, usize, usize)]) -> SparseVec {
        let (k, fl, side) = (self.k, self.filter_len(), self.side);
        let mut blocks = Vec::with_capacity(3 * NUM_PARTS);
        let mut values = Vec::with_capacity(NUM_PARTS * (fl + 5));
        for (i, &(x, y, m)) in placement.iter().enumerate() {
            blocks.push((((i * k + m) * fl) as u32, fl as u32));
            for dy in 0..side {
                let row = (y + dy) * feat.cols + x;
                values.extend_from_slice(&feat.data[row * FEAT_DIM..(row + side) * FEAT_DIM]);
            }
        }
        values.push(1.0);
        blocks.push((self.bias0() as u32, 1));
        for i in 1..NUM_PARTS {
            let par = PARENT[i].unwrap_or(0);
            let (x, y, m) = placement[i];
            let (px, py, l) = placement[par];
            let a = self.anchors[i][m];
            let dx = (px as f64 + a[0] as f64 - 1.0) - x as f64;
            let dy = (py as f64 + a[1] as f64 - 1.0) - y as f64;
            blocks.push(((self.def0() + ((i - 1) * k + m) * 4) as u32, 4));
            values.extend_from_slice(&[-(dx * dx) as f32, -dx as f32, -(dy * dy) as f32, -dy as f32]);
            blocks.push(((self.bias0() + 1 + ((i - 1) * k + l) * k + m) as u32, 1));
            values.push(1.0);
        }
        SparseVec { blocks, values }
    }

    /// The detector model of parameters `w` (quadratic deformation weights raised to the lower
    /// bound) with score threshold `thresh`. Errors: `CorruptData` when w is not finite.
    pub fn to_model(&self, w: &[f64], thresh: f64) -> Result<Model> {
        let (k, fl) = (self.k, self.filter_len());
        let filters = (0..NUM_PARTS * k)
            .map(|f| Filter {
                rows: self.side,
                cols: self.side,
                w: w[f * fl..(f + 1) * fl].iter().map(|&v| v as f32).collect(),
            })
            .collect();
        let defs = (1..NUM_PARTS)
            .flat_map(|i| (0..k).map(move |m| (i, m)))
            .map(|(i, m)| {
                let o = self.def0() + ((i - 1) * k + m) * 4;
                let b = |v: f64| v.max(DEF_LOWER_BOUND);
                Deformation { w: [b(w[o]), w[o + 1], b(w[o + 2]), w[o + 3]], anchor: self.anchors[i][m] }
            })
            .collect();
        let bias = w[self.bias0()..].to_vec();
        let parts = (0..NUM_PARTS)
            .map(|i| match PARENT[i] {
                None => Part { parent: None, filter: (0..k).collect(), def: vec![], bias: vec![vec![0]] },
                Some(p) => Part {
                    parent: Some(p),
                    filter: (0..k).map(|m| i * k + m).collect(),
                    def: (0..k).map(|m| (i - 1) * k + m).collect(),
                    bias: (0..k).map(|l| (0..k).map(|m| 1 + ((i - 1) * k + l) * k + m).collect()).collect(),
                },
            })
            .collect();
        Model::new(self.sbin, self.interval, thresh, filters, defs, bias, parts, PART_TO_JOINT)
    }

    /// `w` with the bounded coordinates raised to the lower bound (the model's effective w).
    pub fn effective(&self, w: &[f64]) -> Vec<f64> {
        let mut e = w.to_vec();
        for o in self.bounded() {
            e[o] = e[o].max(DEF_LOWER_BOUND);
        }
        e
    }
}

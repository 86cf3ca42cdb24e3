//! The flexible-mixture-of-parts model (Yang & Ramanan): HOG part filters, quadratic deformations,
//! mixture co-occurrence biases and the part tree; validation and the PARSE JSON loader.

use std::path::Path;

use crate::error::{Error, Result};

/// Number of HOG feature channels (Felzenszwalb et al.: 18 + 9 orientations, 4 energies, truncation).
pub const FEAT_DIM: usize = 32;
/// Number of PARSE joints (`part_to_joint`).
pub const NUM_PARSE_JOINTS: usize = 14;
/// PARSE joint names in the data set's own order (see `data/fmp/README.md`).
pub const PARSE_JOINT_NAMES: [&str; NUM_PARSE_JOINTS] =
    ["lank", "lkne", "lhip", "rhip", "rkne", "rank", "lwr", "lelb", "lsho", "rsho", "relb", "rwr", "hbot", "htop"];
/// Largest accepted filter side in cells, mixtures per part and parts (sanity limits for loaders).
pub const MAX_FILTER_CELLS: usize = 64;
/// Largest accepted number of parts in a model.
pub const MAX_PARTS: usize = 256;
/// Largest accepted number of mixtures of one part (so also of rows of a bias matrix).
pub const MAX_MIXTURES: usize = 255;
/// Most filter weights a model may hold in all (2^20; the embedded and the PARSE model hold
/// about 125 000): the detector's work per pyramid cell grows with it, so a model file of
/// millions of distinct weights (which ran for minutes) is refused on load.
pub const MAX_MODEL_WEIGHTS: usize = 1 << 20;
/// Most filters, and most part mixtures (the sum of the parts' mixture counts), a model may
/// hold (the embedded and the PARSE model: 156 each): each costs a response map per pyramid
/// level.
pub const MAX_FILTERS: usize = 1024;
/// Largest magnitude of a filter weight, deformation weight or bias (the trained models' are
/// under 10): scores are sums of these in `f32`, which stay finite within this bound.
pub const MAX_WEIGHT_MAGNITUDE: f64 = 1e6;

/// A linear filter over `rows` x `cols` HOG cells, weights row-major (y, x, feature).
#[derive(Clone, Debug, PartialEq)]
pub struct Filter {
    /// Height in cells.
    pub rows: usize,
    /// Width in cells.
    pub cols: usize,
    /// `rows * cols * FEAT_DIM` weights.
    pub w: Vec<f32>,
}

/// A quadratic deformation: cost `w · (dx², dx, dy², dy)` where (dx, dy) is the child's
/// displacement in cells from its anchor; `anchor` is (ax, ay) in cells, 1-based as in the
/// authors' MATLAB code (the child's top-left cell is at parent + anchor − 1 at rest).
#[derive(Clone, Debug, PartialEq)]
pub struct Deformation {
    /// (dx², dx, dy², dy) weights; dx² and dy² weights must be > 0.
    pub w: [f64; 4],
    /// (ax, ay), 1-based cell offset at the parent's pyramid level.
    pub anchor: [i32; 2],
}

/// One part of the tree: a filter and a deformation per mixture, and the co-occurrence biases
/// with its parent's mixtures.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// Parent part index (`None` for the root, part 0). Parents precede children.
    pub parent: Option<usize>,
    /// Filter index per mixture.
    pub filter: Vec<usize>,
    /// Deformation index per mixture (empty for the root).
    pub def: Vec<usize>,
    /// Bias index `[parent mixture][own mixture]`; for the root a single row of 1 or K entries.
    pub bias: Vec<Vec<usize>>,
}

/// A complete detector model. Build with [`Model::new`] (validates) or a loader.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// HOG cell size in pixels (even, ≥ 2).
    pub sbin: usize,
    /// Pyramid levels per octave.
    pub interval: usize,
    /// Default score threshold of a detection.
    pub thresh: f64,
    /// The filters.
    pub filters: Vec<Filter>,
    /// The deformations.
    pub defs: Vec<Deformation>,
    /// The bias values.
    pub bias: Vec<f64>,
    /// The parts, root first, parents before children.
    pub parts: Vec<Part>,
    /// For each of the 14 PARSE joints, the 0-based part whose box centre gives it.
    pub part_to_joint: [usize; NUM_PARSE_JOINTS],
}

fn corrupt(msg: impl Into<String>) -> Error {
    Error::CorruptData(msg.into())
}

impl Model {
    /// Validates every index, size and weight and returns the model. Errors: `CorruptData`
    /// naming the first inconsistency.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        sbin: usize,
        interval: usize,
        thresh: f64,
        filters: Vec<Filter>,
        defs: Vec<Deformation>,
        bias: Vec<f64>,
        parts: Vec<Part>,
        part_to_joint: [usize; NUM_PARSE_JOINTS],
    ) -> Result<Self> {
        let m = Self { sbin, interval, thresh, filters, defs, bias, parts, part_to_joint };
        m.validate()?;
        Ok(m)
    }

    fn validate(&self) -> Result<()> {
        if self.sbin < 2 || !self.sbin.is_multiple_of(2) || self.sbin > 64 {
            return Err(corrupt(format!("sbin {} must be even and in 2..=64", self.sbin)));
        }
        if self.interval == 0 || self.interval > 100 {
            return Err(corrupt(format!("interval {} must be in 1..=100", self.interval)));
        }
        if !(self.thresh.abs() <= MAX_WEIGHT_MAGNITUDE) {
            return Err(corrupt(format!(
                "threshold {} is beyond ±{MAX_WEIGHT_MAGNITUDE:e} or not finite",
                self.thresh
            )));
        }
        for (k, f) in self.filters.iter().enumerate() {
            if f.rows == 0 || f.cols == 0 || f.rows > MAX_FILTER_CELLS || f.cols > MAX_FILTER_CELLS {
                return Err(corrupt(format!("filter {k} has size {}x{} cells", f.rows, f.cols)));
            }
            if f.w.len() != f.rows * f.cols * FEAT_DIM {
                return Err(corrupt(format!(
                    "filter {k} has {} weights, expected {}",
                    f.w.len(),
                    f.rows * f.cols * FEAT_DIM
                )));
            }
            if f.w.iter().any(|v| !(v.abs() as f64 <= MAX_WEIGHT_MAGNITUDE)) {
                return Err(corrupt(format!("filter {k} has a weight beyond ±{MAX_WEIGHT_MAGNITUDE:e} or not finite")));
            }
        }
        let mixtures: usize = self.parts.iter().map(|p| p.filter.len()).sum();
        if self.filters.len() > MAX_FILTERS || mixtures > MAX_FILTERS {
            return Err(corrupt(format!(
                "{} filters and {mixtures} part mixtures (at most {MAX_FILTERS} each)",
                self.filters.len()
            )));
        }
        let weights: usize = self.filters.iter().map(|f| f.w.len()).sum();
        if weights > MAX_MODEL_WEIGHTS {
            return Err(corrupt(format!("{weights} filter weights (at most {MAX_MODEL_WEIGHTS})")));
        }
        for (k, d) in self.defs.iter().enumerate() {
            if d.w.iter().any(|v| !(v.abs() <= MAX_WEIGHT_MAGNITUDE)) || d.w[0] <= 0.0 || d.w[2] <= 0.0 {
                return Err(corrupt(format!(
                    "deformation {k} weights {:?}: must be within ±{MAX_WEIGHT_MAGNITUDE:e} with dx², dy² > 0",
                    d.w
                )));
            }
            if d.anchor.iter().any(|a| a.abs() > 1000) {
                return Err(corrupt(format!("deformation {k} anchor {:?} is absurd", d.anchor)));
            }
        }
        if self.bias.iter().any(|v| !(v.abs() <= MAX_WEIGHT_MAGNITUDE)) {
            return Err(corrupt(format!("a bias is beyond ±{MAX_WEIGHT_MAGNITUDE:e} or not finite")));
        }
        if self.parts.is_empty() || self.parts.len() > MAX_PARTS {
            return Err(corrupt(format!("{} parts (expected 1..={MAX_PARTS})", self.parts.len())));
        }
        for (i, p) in self.parts.iter().enumerate() {
            let k = p.filter.len();
            if k == 0 || k > MAX_MIXTURES {
                return Err(corrupt(format!("part {i} has {k} mixtures")));
            }
            if let Some(&f) = p.filter.iter().find(|&&f| f >= self.filters.len()) {
                return Err(corrupt(format!("part {i} names filter {f} of {}", self.filters.len())));
            }
            if p.bias.iter().flatten().any(|&b| b >= self.bias.len()) {
                return Err(corrupt(format!("part {i} names a bias beyond {}", self.bias.len())));
            }
            match p.parent {
                None if i != 0 => return Err(corrupt(format!("part {i} has no parent but is not part 0"))),
                None => {
                    if p.bias.len() != 1 || !(p.bias[0].len() == 1 || p.bias[0].len() == k) {
                        return Err(corrupt("the root's bias must be a row of 1 or K entries"));
                    }
                }
                Some(par) => {
                    if par >= i {
                        return Err(corrupt(format!("part {i} has parent {par}: parents must precede children")));
                    }
                    if p.def.len() != k {
                        return Err(corrupt(format!("part {i} has {} deformations for {k} mixtures", p.def.len())));
                    }
                    if let Some(&d) = p.def.iter().find(|&&d| d >= self.defs.len()) {
                        return Err(corrupt(format!("part {i} names deformation {d} of {}", self.defs.len())));
                    }
                    let kp = self.parts[par].filter.len();
                    if p.bias.len() != kp || p.bias.iter().any(|r| r.len() != k) {
                        return Err(corrupt(format!("part {i}: bias matrix must be {kp}x{k}")));
                    }
                }
            }
        }
        if let Some(&j) = self.part_to_joint.iter().find(|&&j| j >= self.parts.len()) {
            return Err(corrupt(format!("part_to_joint names part {j} of {}", self.parts.len())));
        }
        Ok(())
    }

    /// Largest filter size in cells, (rows, cols).
    pub fn max_filter_size(&self) -> (usize, usize) {
        let r = self.filters.iter().map(|f| f.rows).max().unwrap_or(1);
        let c = self.filters.iter().map(|f| f.cols).max().unwrap_or(1);
        (r, c)
    }

    /// Height in cells of the model's figure at rest: the vertical extent of the part boxes when
    /// every part sits at its anchor, the tallest over the layouts that use mixture m for every
    /// part (m = 0..K−1, clamped to each part's mixtures). 29 for the PARSE model; a figure F px
    /// tall is found near cells of F / this many px.
    pub fn rest_height_cells(&self) -> f64 {
        let k = self.parts.iter().map(|p| p.filter.len()).max().unwrap_or(1);
        let mut best = 0i64;
        for mix in 0..k {
            let mut top = vec![0i64; self.parts.len()];
            let (mut y1, mut y2) = (i64::MAX, i64::MIN);
            for (i, p) in self.parts.iter().enumerate() {
                let m = mix.min(p.filter.len() - 1);
                if let (Some(par), Some(&d)) = (p.parent, p.def.get(m)) {
                    top[i] = top[par] + self.defs[d].anchor[1] as i64 - 1;
                }
                y1 = y1.min(top[i]);
                y2 = y2.max(top[i] + self.filters[p.filter[m]].rows as i64);
            }
            best = best.max(y2 - y1);
        }
        best.max(1) as f64
    }

    /// Pyramid padding in cells (x, y) as `getpadding`: largest filter side − 2 (at least 0).
    pub fn padding(&self) -> (usize, usize) {
        let (r, c) = self.max_filter_size();
        (c.saturating_sub(2), r.saturating_sub(2))
    }

    /// Loads the PARSE model JSON (`data/fmp/parse_model.json`, fields in its README). For tests
    /// and benchmarks: never embed or ship that file. Errors: `Io`, `CorruptData`.
    pub fn load_json(path: &Path) -> Result<Self> {
        let bytes = crate::fsutil::read_capped(path, crate::detect::format::MAX_DETECTOR_FILE_BYTES)?;
        Self::from_json(&bytes).map_err(|e| match e {
            Error::CorruptData(m) => corrupt(format!("{}: {m}", path.display())),
            e => e,
        })
    }

    /// Parses the PARSE model JSON from memory. Errors: `CorruptData`.
    pub fn from_json(bytes: &[u8]) -> Result<Self> {
        let j: json::ModelJson =
            crate::strict_json::from_slice(bytes).map_err(|e| corrupt(format!("model JSON: {e}")))?;
        j.into_model()
    }
}

mod json {
    use super::*;
    use serde::Deserialize;

    #[derive(Deserialize)]
    pub struct ModelJson {
        sbin: usize,
        interval: usize,
        thresh: f64,
        parts: Vec<PartJson>,
        filters: Vec<FilterJson>,
        defs: Vec<DefJson>,
        bias: Vec<f64>,
        part_to_joint_1based: std::collections::BTreeMap<String, usize>,
    }
    #[derive(Deserialize)]
    struct PartJson {
        parent: i64,
        filterid: Vec<usize>,
        defid: Vec<usize>,
        biasid: Vec<Vec<usize>>,
    }
    #[derive(Deserialize)]
    struct FilterJson {
        shape: [usize; 3],
        w: Vec<f64>,
    }
    #[derive(Deserialize)]
    struct DefJson {
        w: [f64; 4],
        anchor_1based: [i32; 3],
    }

    impl ModelJson {
        pub fn into_model(self) -> Result<Model> {
            let mut filters = Vec::with_capacity(self.filters.len());
            for (k, f) in self.filters.into_iter().enumerate() {
                if f.shape[2] != FEAT_DIM {
                    return Err(corrupt(format!("filter {k} has {} features, expected {FEAT_DIM}", f.shape[2])));
                }
                filters.push(Filter { rows: f.shape[0], cols: f.shape[1], w: f.w.iter().map(|&v| v as f32).collect() });
            }
            let mut defs = Vec::with_capacity(self.defs.len());
            for (k, d) in self.defs.into_iter().enumerate() {
                if d.anchor_1based[2] != 0 {
                    return Err(corrupt(format!(
                        "deformation {k}: pyramid offset ds = {} is not supported",
                        d.anchor_1based[2]
                    )));
                }
                defs.push(Deformation { w: d.w, anchor: [d.anchor_1based[0], d.anchor_1based[1]] });
            }
            let mut parts = Vec::with_capacity(self.parts.len());
            for (i, p) in self.parts.into_iter().enumerate() {
                let parent = match p.parent {
                    -1 => None,
                    q if q >= 0 => Some(q as usize),
                    q => return Err(corrupt(format!("part {i} has parent {q}"))),
                };
                parts.push(Part { parent, filter: p.filterid, def: p.defid, bias: p.biasid });
            }
            let mut p2j = [0usize; NUM_PARSE_JOINTS];
            for (j, name) in PARSE_JOINT_NAMES.iter().enumerate() {
                let v = *self
                    .part_to_joint_1based
                    .get(*name)
                    .ok_or_else(|| corrupt(format!("part_to_joint_1based lacks joint {name}")))?;
                if v == 0 {
                    return Err(corrupt(format!("part_to_joint_1based[{name}] is 0 (1-based)")));
                }
                p2j[j] = v - 1;
            }
            Model::new(self.sbin, self.interval, self.thresh, filters, defs, self.bias, parts, p2j)
        }
    }
}

/// A tiny valid model for tests (a root and one child with 2 mixtures each, 2x2 filters), also
/// used by the C API's tests (feature `test-fixtures`). Not a detector of anything.
#[cfg(any(test, feature = "test-fixtures"))]
pub fn tiny_model() -> Model {
    let f = |s: f32| Filter {
        rows: 2,
        cols: 2,
        w: (0..2 * 2 * FEAT_DIM).map(|i| s * ((i % 7) as f32 - 3.0) / 10.0).collect(),
    };
    let parts = vec![
        Part { parent: None, filter: vec![0, 1], def: vec![], bias: vec![vec![0]] },
        Part { parent: Some(0), filter: vec![2, 3], def: vec![0, 1], bias: vec![vec![1, 2], vec![3, 4]] },
    ];
    let defs = vec![
        Deformation { w: [0.1, 0.0, 0.1, 0.0], anchor: [1, 3] },
        Deformation { w: [0.05, 0.01, 0.2, -0.01], anchor: [2, 3] },
    ];
    Model::new(
        4,
        5,
        -1.0,
        vec![f(1.0), f(-1.0), f(0.5), f(2.0)],
        defs,
        vec![0.0, 0.1, -0.2, 0.3, 0.0],
        parts,
        [0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1],
    )
    .unwrap()
}

#[cfg(test)]
pub(crate) mod tests {
    pub(crate) use super::tiny_model;
    use super::*;

    #[test]
    fn validation_names_the_problem() {
        let m = tiny_model();
        let mut bad = m.clone();
        bad.parts[1].parent = Some(1);
        assert!(matches!(bad.validate(), Err(Error::CorruptData(s)) if s.contains("parents must precede")));
        let mut bad = m.clone();
        bad.filters[0].w.pop();
        assert!(matches!(bad.validate(), Err(Error::CorruptData(s)) if s.contains("weights")));
        let mut bad = m.clone();
        bad.defs[0].w[0] = 0.0;
        assert!(bad.validate().is_err());
        let mut bad = m.clone();
        bad.parts[1].bias[1].pop();
        assert!(matches!(bad.validate(), Err(Error::CorruptData(s)) if s.contains("bias matrix")));
        let mut bad = m;
        bad.sbin = 3;
        assert!(bad.validate().is_err());
    }

    #[test]
    fn rest_height_spans_the_part_boxes_at_their_anchors() {
        let m = tiny_model();
        // Mixture 0: child top at 0 + 3 − 1 = 2, 2 rows -> 0..4; mixture 1: the same anchor y.
        assert_eq!(m.rest_height_cells(), 4.0);
        let mut up = m.clone();
        up.defs[1].anchor = [2, -4]; // child above the root: top −5, boxes −5..2 -> 7 cells
        assert_eq!(up.rest_height_cells(), 7.0);
    }

    #[test]
    fn json_errors_are_specific() {
        assert!(matches!(Model::from_json(b"{\"sbin\": 4"), Err(Error::CorruptData(s)) if s.contains("model JSON")));
        assert!(matches!(Model::from_json(b"[]"), Err(Error::CorruptData(_))));
    }

    /// Issue 52 finding 10: extreme values that overflow the `f32` scores (a bias of 1e308 gave
    /// score +inf and joints outside the image) and models too large to search in reasonable
    /// time (millions of distinct filter weights) are refused on load.
    #[test]
    fn extreme_values_and_oversized_models_are_refused() {
        let m = tiny_model();
        let refused = |bad: Model, what: &str| {
            let e = bad.validate().unwrap_err().to_string();
            assert!(e.contains(what), "{e}");
        };
        let mut bad = m.clone();
        bad.bias[2] = 1e308;
        refused(bad, "bias is beyond");
        let mut bad = m.clone();
        bad.filters[1].w[5] = 3e38;
        refused(bad, "filter 1 has a weight beyond");
        let mut bad = m.clone();
        bad.defs[1].w[1] = -1e300;
        refused(bad, "deformation 1 weights");
        let mut bad = m.clone();
        bad.thresh = 1e300;
        refused(bad, "threshold");
        let big = Filter { rows: 32, cols: 32, w: vec![0.5; 32 * 32 * FEAT_DIM] };
        let mut bad = m.clone();
        bad.filters.extend(std::iter::repeat_n(big, MAX_MODEL_WEIGHTS / (32 * 32 * FEAT_DIM)));
        refused(bad, "filter weights (at most");
        let mut bad = m.clone();
        bad.filters.extend(std::iter::repeat_n(m.filters[0].clone(), MAX_FILTERS));
        refused(bad, "filters and");
        let mut ok = m;
        ok.bias[2] = MAX_WEIGHT_MAGNITUDE;
        ok.validate().unwrap();
    }
}

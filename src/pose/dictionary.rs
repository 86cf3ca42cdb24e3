//! The basis-pose dictionary of eq. (2): a mean pose μ and an overcomplete set of unit basis
//! poses, concatenated from per-action PCA, plus the average bone lengths l_ij of eq. (3).
//!
//! Poses are 45-vectors (joint-major: x, y, z of joint 0, then joint 1, ...) of normalised poses
//! ([`super::motion::normalize_pose`]): metres of a 1.75 m person, pelvis at the origin, facing
//! +Z. Learning ([`Dictionary::learn`]): every pose of every clip is normalised (frames without a
//! heading are dropped) and, when [`LearnParams::mirror`] is set, its left/right mirror is added.
//! Clips whose names differ only by a `_mirror` suffix form one action. The bone lengths l_ij
//! are the action-weighted mean bone lengths. μ is the mean of the action means (each action
//! weighs the same) with every bone rescaled to its length l_ij (its direction kept, rebuilt
//! outward from the pelvis), so that μ meets eq. (3)'s constraint exactly: a plain average of
//! varied poses has bones up to 40 % too short in Σ l², and a start that far outside the bound
//! forces the first chosen basis to inflate it. For each action `a` the basis gets, in order:
//! the unit vector of (mean_a − μ) and the leading unit principal components of the action's
//! poses about mean_a, as few as reach [`LearnParams::energy`] of its variance, at most
//! [`LearnParams::max_per_action`]. Each component's sign makes its largest-magnitude entry
//! positive. Each basis also has a spread σ_k: the standard deviation of the action's poses
//! along a component, or |mean_a − μ| for the action-mean direction (used by the optional
//! weight prior of [`super::PoseOptions::prior`]). Exemplars (the candidates of the
//! nearest-neighbour starts of [`super::PoseOptions::starts`]): the normalised poses of each
//! action (mirrors included, in clip order) thinned greedily so that no two kept poses of an
//! action are closer than [`LearnParams::exemplar_spacing`] (RMS over the 15 joints).

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use super::motion::{mirror_pose, normalize_pose};
use crate::error::{Error, Result};
use crate::skeleton::{Joints3, BONES, NUM_BONES, NUM_JOINTS};

/// Length of a pose vector (3 × 15).
pub const POSE_DIM: usize = 3 * NUM_JOINTS;

/// Default [`LearnParams::exemplar_spacing`], metres.
pub const DEFAULT_EXEMPLAR_SPACING: f64 = 0.03;

/// Most exemplars a dictionary may hold.
pub const MAX_EXEMPLARS: usize = 65536;

/// Largest magnitude of a mean or exemplar coordinate, bone length or basis spread a dictionary
/// may hold, metres (its poses are of a 1.75 m person): larger values are refused on load, as
/// they overflow the solver's sums (a bone of 1e300 m gave a NaN length excess).
pub const MAX_POSE_VALUE_M: f64 = 100.0;

/// One action's block of consecutive basis columns.
#[derive(Clone, Debug, PartialEq)]
pub struct Action {
    /// Action name (clip name without `_mirror`).
    pub name: String,
    /// First basis column.
    pub first: usize,
    /// Number of basis columns.
    pub count: usize,
}

/// Parameters of [`Dictionary::learn`].
#[derive(Clone, Debug, PartialEq)]
pub struct LearnParams {
    /// Most principal components per action (the action-mean direction is extra), ≥ 1.
    pub max_per_action: usize,
    /// Fraction of an action's variance its components must reach, in (0, 1].
    pub energy: f64,
    /// Add the left/right mirror of every pose.
    pub mirror: bool,
    /// Exemplar spacing, metres (0 = no exemplars): a training pose (per action, mirrors
    /// included, in order) becomes an exemplar for the nearest-neighbour starts of
    /// [`super::PoseOptions::starts`] unless an exemplar already kept for its action lies
    /// within this RMS joint distance.
    pub exemplar_spacing: f64,
}

impl Default for LearnParams {
    fn default() -> Self {
        LearnParams { max_per_action: 6, energy: 0.9, mirror: true, exemplar_spacing: DEFAULT_EXEMPLAR_SPACING }
    }
}

/// The pose dictionary (eq. 2). Immutable once built; share it freely across threads.
#[derive(Clone, Debug, PartialEq)]
pub struct Dictionary {
    /// Mean pose μ, 45 values, metres.
    pub mean: DVector<f64>,
    /// Basis poses, 45 × K, unit columns.
    pub bases: DMatrix<f64>,
    /// Spread σ_k of each basis weight, metres (K values, > 0).
    pub sigma: DVector<f64>,
    /// Average length of each bone of [`BONES`], metres.
    pub bone_lengths: [f64; NUM_BONES],
    /// Column blocks per action, in column order, covering 0..K.
    pub actions: Vec<Action>,
    /// Exemplar training poses, 45 × N (N may be 0), normalised like the training poses
    /// (metres of a 1.75 m person, pelvis at the origin, facing +Z).
    pub exemplars: DMatrix<f64>,
    /// Free text: how the dictionary was made (clips, held-out clips, parameters).
    pub provenance: String,
    /// Derived from `exemplars` on first use by the nearest-neighbour starts.
    pub(crate) frame_cache: super::exemplar::FrameCache,
}

/// Writes a pose as a 45-vector.
pub fn pose_to_vec(x: &Joints3) -> DVector<f64> {
    DVector::from_iterator(POSE_DIM, x.iter().flat_map(|q| q.iter().copied()))
}

/// Reads a 45-vector as a pose (`v` must have at least 45 entries).
pub fn vec_to_pose(v: &[f64]) -> Joints3 {
    let mut x = [[0.0; 3]; NUM_JOINTS];
    for (j, q) in x.iter_mut().enumerate() {
        *q = [v[3 * j], v[3 * j + 1], v[3 * j + 2]];
    }
    x
}

/// The 42 × 45 bone-difference operator D: rows 3b..3b+3 give X_child − X_parent of bone b.
pub fn bone_operator() -> DMatrix<f64> {
    let mut d = DMatrix::zeros(3 * NUM_BONES, POSE_DIM);
    for (b, &(p, c)) in BONES.iter().enumerate() {
        for k in 0..3 {
            d[(3 * b + k, 3 * c + k)] = 1.0;
            d[(3 * b + k, 3 * p + k)] = -1.0;
        }
    }
    d
}

impl Dictionary {
    /// Number of basis poses K.
    pub fn num_bases(&self) -> usize {
        self.bases.ncols()
    }

    /// Σ l_ij² over the bones, m² (the `Σ l²` of eq. 3).
    pub fn sum_sq_lengths(&self) -> f64 {
        self.bone_lengths.iter().map(|l| l * l).sum()
    }

    /// Name of the action basis column `k` belongs to.
    pub fn action_of(&self, k: usize) -> Option<&str> {
        self.actions.iter().find(|a| k >= a.first && k < a.first + a.count).map(|a| a.name.as_str())
    }

    /// Checks internal consistency (sizes, finite values within [`MAX_POSE_VALUE_M`], unit
    /// columns, action blocks).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::CorruptData(format!("pose dictionary: {m}")));
        if self.mean.len() != POSE_DIM || self.bases.nrows() != POSE_DIM || self.bases.ncols() == 0 {
            return bad("wrong dimensions".into());
        }
        if self.exemplars.nrows() != POSE_DIM || self.exemplars.ncols() > MAX_EXEMPLARS {
            return bad("wrong exemplar dimensions".into());
        }
        if self.exemplars.iter().any(|v| !v.is_finite()) {
            return bad("non-finite exemplar value".into());
        }
        if self.sigma.len() != self.bases.ncols() {
            return bad("wrong number of basis spreads".into());
        }
        if self
            .mean
            .iter()
            .chain(self.bases.iter())
            .chain(self.bone_lengths.iter())
            .chain(self.sigma.iter())
            .any(|v| !v.is_finite())
        {
            return bad("non-finite value".into());
        }
        if self.sigma.iter().any(|&s| s <= 0.0) {
            return bad("basis spread not positive".into());
        }
        if self.bone_lengths.iter().any(|&l| l <= 0.0) {
            return bad("bone length not positive".into());
        }
        let extreme = |v: &f64| v.abs() > MAX_POSE_VALUE_M;
        if self.mean.iter().chain(&self.bone_lengths).chain(self.sigma.iter()).chain(self.exemplars.iter()).any(extreme)
        {
            return bad(format!("a pose value, bone length or spread beyond {MAX_POSE_VALUE_M} m"));
        }
        for (k, c) in self.bases.column_iter().enumerate() {
            if (c.norm() - 1.0).abs() > 1e-6 {
                return bad(format!("basis {k} is not unit length"));
            }
        }
        let mut next = 0;
        for a in &self.actions {
            if a.first != next || a.count == 0 {
                return bad(format!("action {} does not continue the column blocks", a.name));
            }
            next += a.count;
        }
        if next != self.num_bases() {
            return bad("action blocks do not cover the bases".into());
        }
        Ok(())
    }

    /// Learns a dictionary from clips `(clip name, frames in any rigid placement and scale)`
    /// (see the module doc). `provenance` is stored as given.
    pub fn learn(clips: &[(String, Vec<Joints3>)], params: &LearnParams, provenance: String) -> Result<Dictionary> {
        if params.max_per_action == 0
            || !(params.energy > 0.0 && params.energy <= 1.0)
            || !(params.exemplar_spacing >= 0.0 && params.exemplar_spacing.is_finite())
        {
            return Err(Error::OutOfRange {
                name: "learn parameters",
                detail: format!(
                    "max_per_action = {} must be ≥ 1, energy = {} in (0, 1], exemplar_spacing = {} finite and ≥ 0",
                    params.max_per_action, params.energy, params.exemplar_spacing
                ),
            });
        }
        // Group clips into actions, keeping first-seen order.
        let mut groups: Vec<(String, Vec<Joints3>)> = Vec::new();
        for (name, frames) in clips {
            let action = name.strip_suffix("_mirror").unwrap_or(name).to_string();
            let mut poses: Vec<Joints3> = frames.iter().filter_map(normalize_pose).collect();
            if params.mirror {
                let m: Vec<Joints3> = poses.iter().map(mirror_pose).collect();
                poses.extend(m);
            }
            match groups.iter_mut().find(|g| g.0 == action) {
                Some(g) => g.1.extend(poses),
                None => groups.push((action, poses)),
            }
        }
        groups.retain(|g| g.1.len() >= 2);
        if groups.is_empty() {
            return Err(Error::CorruptData("no clip has two usable frames to learn from".into()));
        }
        let means: Vec<DVector<f64>> = groups
            .iter()
            .map(|(_, p)| p.iter().map(pose_to_vec).fold(DVector::zeros(POSE_DIM), |a, v| a + v) / p.len() as f64)
            .collect();
        let raw_mean = means.iter().fold(DVector::zeros(POSE_DIM), |a, v| a + v) / means.len() as f64;
        let mut bone_lengths = [0.0; NUM_BONES];
        for (_, poses) in &groups {
            for x in poses {
                for (b, &(p, c)) in BONES.iter().enumerate() {
                    let d: f64 = (0..3).map(|k| (x[c][k] - x[p][k]).powi(2)).sum::<f64>().sqrt();
                    bone_lengths[b] += d / (poses.len() * groups.len()) as f64;
                }
            }
        }
        let mean = with_bone_lengths(&raw_mean, &bone_lengths);
        let mut cols: Vec<DVector<f64>> = Vec::new();
        let mut exemplars: Vec<DVector<f64>> = Vec::new();
        if params.exemplar_spacing > 0.0 {
            let min_sq = NUM_JOINTS as f64 * params.exemplar_spacing * params.exemplar_spacing;
            for (_, poses) in &groups {
                let first = exemplars.len();
                for v in poses.iter().map(pose_to_vec) {
                    if exemplars[first..].iter().all(|e| (e - &v).norm_squared() >= min_sq) {
                        exemplars.push(v);
                    }
                }
            }
        }
        if exemplars.len() > MAX_EXEMPLARS {
            return Err(Error::OutOfRange {
                name: "exemplar_spacing",
                detail: format!("{} exemplars exceed {MAX_EXEMPLARS}", exemplars.len()),
            });
        }
        let exemplars =
            if exemplars.is_empty() { DMatrix::zeros(POSE_DIM, 0) } else { DMatrix::from_columns(&exemplars) };
        let mut sigma: Vec<f64> = Vec::new();
        let mut actions = Vec::new();
        for ((name, poses), m) in groups.iter().zip(&means) {
            let first = cols.len();
            let offset = m - &mean;
            if offset.norm() > 1e-9 {
                cols.push(sign_fixed(offset.normalize()));
                sigma.push(offset.norm());
            }
            let mut cov = DMatrix::<f64>::zeros(POSE_DIM, POSE_DIM);
            for x in poses {
                let d = pose_to_vec(x) - m;
                cov.ger(1.0 / poses.len() as f64, &d, &d, 1.0);
            }
            let eig = SymmetricEigen::new(cov);
            let mut order: Vec<usize> = (0..POSE_DIM).collect();
            order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
            let total: f64 = eig.eigenvalues.iter().map(|v| v.max(0.0)).sum();
            let mut acc = 0.0;
            for &i in order.iter().take(params.max_per_action) {
                let ev = eig.eigenvalues[i].max(0.0);
                if total <= 0.0 || ev <= 1e-12 * total {
                    break;
                }
                cols.push(sign_fixed(eig.eigenvectors.column(i).normalize()));
                sigma.push(ev.sqrt());
                acc += ev;
                if acc >= params.energy * total {
                    break;
                }
            }
            if cols.len() > first {
                actions.push(Action { name: name.clone(), first, count: cols.len() - first });
            }
        }
        let bases = DMatrix::from_columns(&cols);
        let dict = Dictionary {
            mean,
            bases,
            sigma: DVector::from_vec(sigma),
            bone_lengths,
            actions,
            exemplars,
            provenance,
            frame_cache: Default::default(),
        };
        dict.validate()?;
        Ok(dict)
    }
}

/// Joints ordered parents first (breadth-first from the pelvis).
pub(crate) const TREE_ORDER: [usize; NUM_JOINTS] = [8, 1, 9, 12, 0, 2, 5, 10, 13, 3, 6, 11, 14, 4, 7];

/// `pose` with every bone set to `lengths[b]` along its own direction (a zero-length bone
/// keeps its offset), rebuilt from the pelvis outward.
pub(crate) fn with_bone_lengths(pose: &DVector<f64>, lengths: &[f64; NUM_BONES]) -> DVector<f64> {
    let mut out = pose.clone();
    for &c in TREE_ORDER.iter().skip(1) {
        let Some(b) = BONES.iter().position(|&(_, ch)| ch == c) else { continue };
        let p = BONES[b].0;
        let d = nalgebra::Vector3::new(
            pose[3 * c] - pose[3 * p],
            pose[3 * c + 1] - pose[3 * p + 1],
            pose[3 * c + 2] - pose[3 * p + 2],
        );
        let n = d.norm();
        let step = if n > 0.0 { d * (lengths[b] / n) } else { d };
        for k in 0..3 {
            out[3 * c + k] = out[3 * p + k] + step[k];
        }
    }
    out
}

/// Flips `v` so that its largest-magnitude entry is positive (first such entry on ties).
fn sign_fixed(v: DVector<f64>) -> DVector<f64> {
    let i = v.iter().enumerate().fold(0, |best, (i, x)| if x.abs() > v[best].abs() { i } else { best });
    if v[i] < 0.0 {
        -v
    } else {
        v
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A small synthetic dictionary source: two "actions" of a swinging-arm figure.
    pub(crate) fn synthetic_clips() -> Vec<(String, Vec<Joints3>)> {
        let base: Joints3 = [
            [0.0, 1.6, 0.0],
            [0.0, 1.45, 0.0],
            [-0.18, 1.45, 0.0],
            [-0.2, 1.17, 0.0],
            [-0.22, 0.92, 0.05],
            [0.18, 1.45, 0.0],
            [0.2, 1.17, 0.0],
            [0.22, 0.92, 0.05],
            [0.0, 0.95, 0.0],
            [-0.1, 0.9, 0.0],
            [-0.1, 0.5, 0.02],
            [-0.1, 0.08, 0.0],
            [0.1, 0.9, 0.0],
            [0.1, 0.5, 0.02],
            [0.1, 0.08, 0.0],
        ];
        let clip = |phase: f64, amp: f64| -> Vec<Joints3> {
            (0..40)
                .map(|f| {
                    let a = amp * ((f as f64) * 0.3 + phase).sin();
                    let mut x = base;
                    for (j, s) in [(4usize, 1.0), (7, -1.0), (11, -0.5), (14, 0.5), (3, 0.5), (6, -0.5)] {
                        x[j][2] += s * a;
                        x[j][1] += 0.3 * a * a;
                    }
                    x
                })
                .collect()
        };
        vec![("swing".into(), clip(0.0, 0.3)), ("wave".into(), clip(1.0, 0.15)), ("wave_mirror".into(), clip(2.0, 0.2))]
    }

    #[test]
    fn learns_unit_bases_grouped_by_action() {
        let d = Dictionary::learn(&synthetic_clips(), &LearnParams::default(), "test".into()).unwrap();
        assert_eq!(d.actions.iter().map(|a| a.name.as_str()).collect::<Vec<_>>(), ["swing", "wave"]);
        d.validate().unwrap();
        assert!(d.sum_sq_lengths() > 0.5);
        assert_eq!(d.action_of(0), Some("swing"));
        // Exemplars of one action are at least the spacing apart (RMS over the joints), and a
        // finer spacing keeps more.
        let one = Dictionary::learn(&synthetic_clips()[..1], &LearnParams::default(), "test".into()).unwrap();
        let ex = &one.exemplars;
        assert!(ex.ncols() >= 3, "{} exemplars", ex.ncols());
        for a in 0..ex.ncols() {
            for b in 0..a {
                let rms = ((ex.column(a) - ex.column(b)).norm_squared() / NUM_JOINTS as f64).sqrt();
                assert!(rms >= DEFAULT_EXEMPLAR_SPACING, "exemplars {a}, {b}: {rms} m apart");
            }
        }
        let fine = LearnParams { exemplar_spacing: 0.003, ..LearnParams::default() };
        assert!(
            Dictionary::learn(&synthetic_clips(), &fine, "test".into()).unwrap().exemplars.ncols()
                > d.exemplars.ncols()
        );
        let none = LearnParams { exemplar_spacing: 0.0, ..LearnParams::default() };
        assert_eq!(Dictionary::learn(&synthetic_clips(), &none, "test".into()).unwrap().exemplars.ncols(), 0);
        let bad = LearnParams { energy: 0.0, ..LearnParams::default() };
        assert!(Dictionary::learn(&synthetic_clips(), &bad, String::new()).is_err());
        assert!(Dictionary::learn(&[], &LearnParams::default(), String::new()).is_err());
    }
}

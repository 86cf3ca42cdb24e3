//! The production rig as stored in the body model (`.skbm`, docs/formats.md): where each bone's
//! head and tail sit as fixed linear combinations of the canonical joints and body vertices,
//! MakeHuman's bone rolls and T-pose rotations, and skin weights to the 53 bones.

use crate::body::VertexWeights;
use crate::error::{Error, Result};
use crate::skeleton::{Joints3, NUM_JOINTS};

use super::bones::NUM_RIG_BONES;

/// A point as a weighted sum of canonical joints and body vertices: term index `i < 15` is
/// canonical joint `i`, `i ≥ 15` is body vertex `i − 15`. The weights sum to 1 (an affine
/// combination, so the point moves with any rigid motion of its terms).
#[derive(Clone, Debug, PartialEq)]
pub struct PointRegressor {
    /// (term index, weight) pairs.
    pub terms: Vec<(u32, f32)>,
}

impl PointRegressor {
    /// The canonical joint `j` itself.
    pub fn joint(j: usize) -> PointRegressor {
        PointRegressor { terms: vec![(j as u32, 1.0)] }
    }

    /// The point on a body (joints and vertices metres, model frame). Out-of-range terms (see
    /// [`RigData::validate`]) are skipped.
    pub fn eval(&self, joints: &Joints3, vertices: &[[f32; 3]]) -> [f64; 3] {
        let mut p = [0.0; 3];
        for &(i, w) in &self.terms {
            let q = match (i as usize).checked_sub(NUM_JOINTS) {
                None => joints[i as usize],
                Some(v) => match vertices.get(v) {
                    Some(x) => x.map(|c| c as f64),
                    None => continue,
                },
            };
            for c in 0..3 {
                p[c] += w as f64 * q[c];
            }
        }
        p
    }
}

/// MakeHuman's `game_engine` rig fitted to the body model, one entry per [`super::RIG_BONES`].
#[derive(Clone, Debug, PartialEq)]
pub struct RigData {
    /// Where each bone starts.
    pub heads: Vec<PointRegressor>,
    /// Where each bone ends (its Y axis points from head to tail).
    pub tails: Vec<PointRegressor>,
    /// MakeHuman's bone roll, radians (Blender's convention, about the bone's Y axis).
    pub rolls: Vec<f32>,
    /// MakeHuman's T-pose (`poses/game_engine_fk/t-pose.json`): each bone's rotation in its own
    /// rest frame as Euler XYZ angles, radians (zero for bones the T-pose does not move).
    pub tpose: Vec<[f32; 3]>,
    /// Skin weights per body vertex to the 53 bones (≤ 4, sorted by decreasing weight, sum 1).
    pub skin: Vec<VertexWeights>,
}

impl RigData {
    /// Checks counts, term indices (< 15 + `num_vertices`), finiteness, affine regressors (sum
    /// 1 ± 1e-3) and skin weights (bone < 53, weights in [0, 1] summing to 1 ± 1e-4, one entry
    /// per vertex). Errors: [`Error::CorruptData`] saying what is wrong.
    pub fn validate(&self, num_vertices: usize) -> Result<()> {
        let bad = |m: String| Err(Error::CorruptData(format!("rig: {m}")));
        let n = NUM_RIG_BONES;
        if self.heads.len() != n || self.tails.len() != n || self.rolls.len() != n || self.tpose.len() != n {
            return bad(format!(
                "{} heads, {} tails, {} rolls, {} T-pose rotations for {n} bones",
                self.heads.len(),
                self.tails.len(),
                self.rolls.len(),
                self.tpose.len()
            ));
        }
        let limit = NUM_JOINTS + num_vertices;
        for (b, r) in self.heads.iter().chain(&self.tails).enumerate() {
            let sum: f32 = r.terms.iter().map(|t| t.1).sum();
            if r.terms.is_empty()
                || r.terms.iter().any(|&(i, w)| i as usize >= limit || !w.is_finite())
                || (sum - 1.0).abs() > 1e-3
            {
                return bad(format!("bone end {b} is not an affine combination of joints and vertices"));
            }
        }
        if self.rolls.iter().chain(self.tpose.iter().flatten()).any(|x| !x.is_finite()) {
            return bad("a roll or T-pose angle is not finite".into());
        }
        if self.skin.len() != num_vertices {
            return bad(format!("{} skin-weight entries for {num_vertices} vertices", self.skin.len()));
        }
        for (v, w) in self.skin.iter().enumerate() {
            let sum: f32 = w.weights.iter().sum();
            if w.bones.iter().any(|&b| b as usize >= n)
                || w.weights.iter().any(|x| !(0.0..=1.0).contains(x))
                || (sum - 1.0).abs() > 1e-4
            {
                return bad(format!("skin weights of vertex {v} are invalid ({:?}, {:?})", w.bones, w.weights));
            }
        }
        Ok(())
    }
}

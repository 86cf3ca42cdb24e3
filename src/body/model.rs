//! The runtime body model: shared topology, UVs and skin weights, and one PCA shape space per
//! gender with its joint basis and GMM prior.

use crate::error::{Error, Result};
use crate::skeleton::{Joints3, NUM_BONES};

use super::gender::Gender;
use super::gmm::Gmm;

/// Maximum number of bone influences per vertex.
pub const MAX_INFLUENCES: usize = 4;

/// Skin weights of one vertex: up to [`MAX_INFLUENCES`] (bone, weight) pairs sorted by
/// decreasing weight. Bones index [`crate::skeleton::BONES`]; unused slots have bone 0 and
/// weight 0; the weights sum to 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexWeights {
    /// Bone indices (0..14).
    pub bones: [u8; MAX_INFLUENCES],
    /// Weights in [0, 1], summing to 1.
    pub weights: [f32; MAX_INFLUENCES],
}

/// A body in the rest pose (MakeHuman's A-pose): vertex positions and the 15 canonical joints,
/// metres, model frame (+Y up, +Z toward the viewer, the character's right side at −X; the origin
/// is MakeHuman's, near the pelvis, not at the feet).
#[derive(Clone, Debug, PartialEq)]
pub struct RestShape {
    /// Body vertex positions (13380 for the MakeHuman body), in [`BodyModel::faces`]' indexing.
    pub vertices: Vec<[f32; 3]>,
    /// Canonical joints (docs/design.md order).
    pub joints: Joints3,
}

/// One gender's linear shape space: `vertices = mean + Σ_k w_k · basis_k` and
/// `joints = mean_joints + Σ_k w_k · joint_basis_k`. Basis vectors are unit-norm over all
/// 3 × vertices coordinates, so a weight is a displacement in metres along one basis vector.
#[derive(Clone, Debug)]
pub struct ShapeSpace {
    pub(crate) mean: Vec<[f32; 3]>,
    pub(crate) mean_joints: Joints3,
    /// `num_components` blocks of `3 × num_vertices` floats.
    pub(crate) basis: Vec<f32>,
    /// `num_components` blocks of 15 joints.
    pub(crate) joint_basis: Vec<Joints3>,
    pub(crate) variances: Vec<f64>,
    pub(crate) cumulative_energy: Vec<f64>,
    pub(crate) default_dim: usize,
    pub(crate) gmm: Gmm,
}

impl ShapeSpace {
    /// Number of stored principal components (the longest accepted weight vector).
    pub fn num_components(&self) -> usize {
        self.variances.len()
    }

    /// Number of body vertices.
    pub fn num_vertices(&self) -> usize {
        self.mean.len()
    }

    /// The default fitting dimension: the fewest components holding at least 96% of the training
    /// shapes' variance ("energy").
    pub fn default_dim(&self) -> usize {
        self.default_dim
    }

    /// Variance of each component's weight over the training shapes, m².
    pub fn variances(&self) -> &[f64] {
        &self.variances
    }

    /// Fraction of the total training variance held by the first `k + 1` components, per `k`.
    pub fn cumulative_energy(&self) -> &[f64] {
        &self.cumulative_energy
    }

    /// Mean shape vertices, metres, model frame.
    pub fn mean(&self) -> &[[f32; 3]] {
        &self.mean
    }

    /// Mean shape joints, metres, model frame.
    pub fn mean_joints(&self) -> &Joints3 {
        &self.mean_joints
    }

    /// Component `k`'s vertex displacement per unit weight (`3 × num_vertices` floats, x y z per
    /// vertex), or `None` when `k` is out of range.
    pub fn basis_vector(&self, k: usize) -> Option<&[f32]> {
        let n = 3 * self.mean.len();
        self.basis.get(k * n..(k + 1) * n)
    }

    /// Component `k`'s joint displacement per unit weight.
    pub fn joint_basis_vector(&self, k: usize) -> Option<&Joints3> {
        self.joint_basis.get(k)
    }

    /// The GMM prior over the first [`Gmm::dims`] weights (use [`Gmm::marginal`] for fewer).
    pub fn gmm(&self) -> &Gmm {
        &self.gmm
    }

    /// Checks a weight vector: at most [`ShapeSpace::num_components`] entries, all finite.
    pub fn check_weights(&self, weights: &[f64]) -> Result<()> {
        if weights.len() > self.num_components() {
            return Err(Error::OutOfRange {
                name: "shape weight count",
                detail: format!(
                    "got {} weights, the shape space has {} components",
                    weights.len(),
                    self.num_components()
                ),
            });
        }
        for &w in weights {
            crate::error::ensure_finite("shape weight", w)?;
        }
        Ok(())
    }

    /// The rest shape with PCA weights `weights` (metres; missing trailing weights are 0, so an
    /// empty slice gives the mean). Errors: more weights than components, or a non-finite weight.
    pub fn synthesize(&self, weights: &[f64]) -> Result<RestShape> {
        self.check_weights(weights)?;
        let n = self.mean.len();
        let mut acc: Vec<f64> = self.mean.iter().flat_map(|v| v.iter().map(|&c| c as f64)).collect();
        let mut joints = self.mean_joints;
        for (k, &w) in weights.iter().enumerate() {
            if w == 0.0 {
                continue;
            }
            for (a, &b) in acc.iter_mut().zip(&self.basis[k * 3 * n..(k + 1) * 3 * n]) {
                *a += w * b as f64;
            }
            for (j, jb) in joints.iter_mut().zip(&self.joint_basis[k]) {
                for c in 0..3 {
                    j[c] += w * jb[c];
                }
            }
        }
        let vertices = acc.chunks_exact(3).map(|c| [c[0] as f32, c[1] as f32, c[2] as f32]).collect();
        Ok(RestShape { vertices, joints })
    }

    /// Least-squares weights of a shape with the same vertex count: projections of
    /// `vertices − mean` onto the first `dims` basis vectors (orthonormal up to f32 rounding).
    pub fn project(&self, vertices: &[[f32; 3]], dims: usize) -> Result<Vec<f64>> {
        if vertices.len() != self.mean.len() {
            return Err(Error::OutOfRange {
                name: "vertex count",
                detail: format!("got {}, the shape space has {}", vertices.len(), self.mean.len()),
            });
        }
        if dims > self.num_components() {
            return Err(Error::OutOfRange {
                name: "projection dimensions",
                detail: format!("{dims} > {}", self.num_components()),
            });
        }
        let n = 3 * self.mean.len();
        let centred: Vec<f64> =
            vertices.iter().zip(&self.mean).flat_map(|(v, m)| (0..3).map(move |c| v[c] as f64 - m[c] as f64)).collect();
        Ok((0..dims)
            .map(|k| centred.iter().zip(&self.basis[k * n..(k + 1) * n]).map(|(a, &b)| a * b as f64).sum())
            .collect())
    }
}

/// Which shape space a fit or a body uses: one gender's, or the both-sexes space with gender as
/// a continuous weight ([`super::BlendedSpace`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShapeChoice {
    /// The gendered space of the model file.
    Gendered(Gender),
    /// The both-sexes space built at load time from the two gendered ones.
    Blended,
}

impl From<Gender> for ShapeChoice {
    fn from(g: Gender) -> Self {
        ShapeChoice::Gendered(g)
    }
}

impl ShapeChoice {
    /// "female", "male" or "blended".
    pub fn name(self) -> &'static str {
        match self {
            ShapeChoice::Gendered(g) => g.name(),
            ShapeChoice::Blended => "blended",
        }
    }
}

/// The body model: MakeHuman's body topology (quads), UVs, skin weights to the 14 canonical
/// bones, and a female and a male [`ShapeSpace`]. Immutable; `Send + Sync`.
#[derive(Clone, Debug)]
pub struct BodyModel {
    pub(crate) faces: Vec<[u32; 4]>,
    pub(crate) face_uvs: Vec<[u32; 4]>,
    pub(crate) uvs: Vec<[f32; 2]>,
    pub(crate) skin: Vec<VertexWeights>,
    pub(crate) spaces: [ShapeSpace; 2],
    /// MakeHuman's production rig fitted to the model ([`crate::body::rig`]).
    pub(crate) rig: crate::body::rig::RigData,
    /// The fit proxy, built on first use ([`BodyModel::fit_proxy`]).
    pub(crate) proxy: super::proxy::ProxyCell,
    /// The both-sexes space, built on first use ([`BodyModel::blended`]).
    pub(crate) blend: super::blend::BlendCell,
}

impl BodyModel {
    /// Decodes the model compiled into the library (`assets/body_model.skbm`).
    pub fn embedded() -> Result<BodyModel> {
        BodyModel::from_bytes(super::EMBEDDED_MODEL)
    }

    /// The shape space of `gender`.
    pub fn space(&self, gender: Gender) -> &ShapeSpace {
        &self.spaces[gender.index()]
    }

    /// The shape space of `choice` (the blended one is built on first use).
    pub fn shape_space(&self, choice: ShapeChoice) -> Result<&ShapeSpace> {
        match choice {
            ShapeChoice::Gendered(g) => Ok(self.space(g)),
            ShapeChoice::Blended => Ok(self.blended()?.space()),
        }
    }

    /// Number of body vertices (13380).
    pub fn num_vertices(&self) -> usize {
        self.skin.len()
    }

    /// Quad faces, counter-clockwise seen from outside, indices into the vertices (13378 quads).
    pub fn faces(&self) -> &[[u32; 4]] {
        &self.faces
    }

    /// Per-corner UV indices of each face, into [`BodyModel::uvs`] (MakeHuman's texture layout).
    pub fn face_uvs(&self) -> &[[u32; 4]] {
        &self.face_uvs
    }

    /// Texture coordinates (u, v), v up as in OBJ.
    pub fn uvs(&self) -> &[[f32; 2]] {
        &self.uvs
    }

    /// Each quad (a, b, c, d) split into triangles (a, b, c) and (a, c, d), same winding.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        self.faces.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect()
    }

    /// Skin weights per vertex (≤ 4 influences over the 14 canonical bones, summing to 1).
    pub fn skin_weights(&self) -> &[VertexWeights] {
        &self.skin
    }

    /// The production rig: MakeHuman's `game_engine` skeleton placed by regressors on the
    /// canonical joints and body vertices, its rolls, T-pose and skin weights ([`crate::body::rig`]).
    pub fn rig(&self) -> &crate::body::rig::RigData {
        &self.rig
    }

    /// Checks cross-references: face and UV indices in range, skin weights valid, both shape
    /// spaces with the same vertex count, the rig valid. Used by the loader and the builder.
    pub(crate) fn validate(&self) -> Result<()> {
        let nv = self.skin.len();
        let bad = |m: String| Err(Error::CorruptData(m));
        self.rig.validate(nv)?;
        for s in &self.spaces {
            if s.mean.len() != nv {
                return bad(format!("shape space has {} vertices, skin weights {}", s.mean.len(), nv));
            }
            if s.default_dim == 0 || s.default_dim > s.num_components() {
                return bad(format!("default dimension {} not in 1..={}", s.default_dim, s.num_components()));
            }
            if s.gmm.dims() > s.num_components() {
                return bad(format!("GMM has {} dimensions, shape space only {}", s.gmm.dims(), s.num_components()));
            }
        }
        if let Some((f, _)) = self.faces.iter().enumerate().find(|(_, q)| q.iter().any(|&i| i as usize >= nv)) {
            return bad(format!("face {f} references a vertex >= {nv}"));
        }
        if self.face_uvs.len() != self.faces.len() {
            return bad(format!("{} UV faces for {} faces", self.face_uvs.len(), self.faces.len()));
        }
        let nt = self.uvs.len();
        if let Some((f, _)) = self.face_uvs.iter().enumerate().find(|(_, q)| q.iter().any(|&i| i as usize >= nt)) {
            return bad(format!("UV face {f} references a texture coordinate >= {nt}"));
        }
        for (v, w) in self.skin.iter().enumerate() {
            let sum: f32 = w.weights.iter().sum();
            if w.bones.iter().any(|&b| b as usize >= NUM_BONES)
                || w.weights.iter().any(|x| !(0.0..=1.0).contains(x))
                || (sum - 1.0).abs() > 1e-4
            {
                return bad(format!(
                    "skin weights of vertex {v} are invalid (bones {:?}, weights {:?})",
                    w.bones, w.weights
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::format::tests::tiny_model;
    use super::*;

    #[test]
    fn synthesize_adds_weighted_basis_and_joint_basis() {
        let m = tiny_model();
        let s = m.space(Gender::Male);
        let r = s.synthesize(&[0.5, 2.0]).unwrap();
        assert_eq!(r.vertices[0], [0.0, 0.5, 2.0]);
        assert_eq!(r.vertices[1], [1.0, 0.0, 0.0]);
        assert_eq!(r.joints[3], [0.5, 1.0, 0.5]);
        assert_eq!(s.synthesize(&[]).unwrap().vertices, s.mean());
        let w = s.project(&r.vertices, 2).unwrap();
        assert!((w[0] - 0.5).abs() < 1e-6 && (w[1] - 2.0).abs() < 1e-6, "{w:?}");
    }

    #[test]
    fn synthesize_rejects_wrong_length_and_non_finite_weights() {
        let m = tiny_model();
        let s = m.space(Gender::Female);
        assert!(matches!(s.synthesize(&[0.0; 3]), Err(Error::OutOfRange { name: "shape weight count", .. })));
        assert!(matches!(s.synthesize(&[f64::INFINITY]), Err(Error::NonFinite { name: "shape weight", .. })));
        assert!(s.project(&[[0.0; 3]; 3], 1).is_err());
    }

    #[test]
    fn triangulation_keeps_winding() {
        assert_eq!(tiny_model().triangles(), vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn embedded_model_has_the_makehuman_body() {
        let m = BodyModel::embedded().unwrap();
        assert_eq!((m.num_vertices(), m.faces().len()), (13380, 13378));
        for g in Gender::ALL {
            let s = m.space(g);
            assert!(s.num_components() >= 10 && s.gmm().num_components() == 30 && s.gmm().dims() == 10);
            let e = s.cumulative_energy();
            assert!(e[s.default_dim() - 1] >= 0.96 && (s.default_dim() == 1 || e[s.default_dim() - 2] < 0.96));
            let shape = s.synthesize(&[]).unwrap();
            // Head above neck above pelvis above knees above ankles; right side at -x.
            let j = shape.joints;
            assert!(j[0][1] > j[1][1] && j[1][1] > j[8][1] && j[8][1] > j[10][1] && j[10][1] > j[11][1]);
            assert!(j[2][0] < 0.0 && j[5][0] > 0.0 && j[9][0] < 0.0 && j[12][0] > 0.0);
            let (lo, hi) = shape.vertices.iter().fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v[1]), hi.max(v[1])));
            assert!((1.5..2.0).contains(&(hi - lo)), "mean height {} m", hi - lo);
        }
        let influences = m.skin_weights().iter().map(|w| w.weights.iter().filter(|&&x| x > 0.0).count()).max();
        assert!(influences.unwrap_or(0) <= MAX_INFLUENCES);
    }
}

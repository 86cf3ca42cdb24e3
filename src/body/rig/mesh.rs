//! A rigged mesh in plain arrays: the data the shape model produces and posing, skinning,
//! rasterising and export consume. Frame: metres, +Y up, +Z toward the viewer, the character's
//! right at −X; the rest (bind) pose is the shape model's (MakeHuman's A-pose).

use crate::body::{BodyModel, Gender, RestShape};
use crate::error::{Error, Result};
use crate::skeleton::{Joints3, NUM_BONES};

pub use crate::body::model::VertexWeights;

impl VertexWeights {
    /// The `(bone, weight)` pairs with non-zero weight.
    pub fn influences(&self) -> impl Iterator<Item = (usize, f32)> + '_ {
        self.bones.iter().zip(self.weights).filter(|&(_, w)| w != 0.0).map(|(&b, w)| (b as usize, w))
    }
}

/// Texture coordinates indexed per face corner (MakeHuman's UVs are not per vertex).
#[derive(Clone, Debug, PartialEq)]
pub struct FaceUvs {
    /// UV coordinates, (u, v) with v up (OBJ/MakeHuman convention).
    pub coords: Vec<[f32; 2]>,
    /// For each quad, the index into `coords` of each of its four corners.
    pub quads: Vec<[u32; 4]>,
}

/// A mesh with its skeleton and skin weights in the rest pose. Owns its data.
#[derive(Clone, Debug, PartialEq)]
pub struct RiggedMesh {
    /// Rest vertex positions, metres, model frame.
    pub vertices: Vec<[f32; 3]>,
    /// Faces as quads of vertex indices, counter-clockwise seen from outside. A triangle is
    /// stored as a quad whose last index repeats its third.
    pub quads: Vec<[u32; 4]>,
    /// Optional per-corner texture coordinates (same number of quads as `quads`).
    pub uvs: Option<FaceUvs>,
    /// Rest joints, metres, model frame.
    pub joints: Joints3,
    /// Skin weights, one entry per vertex.
    pub weights: Vec<VertexWeights>,
}

/// Extent of vertices along +Y (the model frame's up axis), metres; 0 for no vertices.
pub fn y_extent(vertices: &[[f32; 3]]) -> f64 {
    if vertices.is_empty() {
        return 0.0;
    }
    let (lo, hi) = vertices.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| (lo.min(v[1]), hi.max(v[1])));
    (hi - lo) as f64
}

/// Scales `vertices` and `joints` (metres) uniformly about the pelvis joint so that their
/// [`y_extent`] becomes `height`. The pelvis is the skeleton's root, which non-standard
/// proportions (longer legs, a longer torso) leave in place, so scaling about it keeps the
/// body's placement. Errors: `height` not finite or ≤ 0, or a flat or empty vertex set
/// ([`Error::OutOfRange`]).
pub fn scale_to_height(vertices: &mut [[f32; 3]], joints: &mut Joints3, height: f64) -> Result<()> {
    let now = y_extent(vertices);
    if !(height.is_finite() && height > 0.0 && now.is_finite() && now > 1e-9) {
        return Err(Error::OutOfRange {
            name: "height",
            detail: format!("cannot scale a body {now} m tall to {height} m"),
        });
    }
    let k = height / now;
    let o = joints[crate::skeleton::joint::PELVIS];
    for v in vertices.iter_mut() {
        *v = std::array::from_fn(|c| (o[c] + (v[c] as f64 - o[c]) * k) as f32);
    }
    for j in joints.iter_mut() {
        *j = std::array::from_fn(|c| o[c] + (j[c] - o[c]) * k);
    }
    Ok(())
}

impl RiggedMesh {
    /// Rest height: the vertices' extent along +Y, metres ([`y_extent`]).
    pub fn height(&self) -> f64 {
        y_extent(&self.vertices)
    }

    /// The mesh (vertices and joints) scaled uniformly about its pelvis joint
    /// ([`scale_to_height`]) so that its [`height`](Self::height) is `height` metres; faces, UVs
    /// and skin weights are unchanged. Errors: [`scale_to_height`]'s.
    pub fn scaled_to_height(&self, height: f64) -> Result<RiggedMesh> {
        let mut out = self.clone();
        scale_to_height(&mut out.vertices, &mut out.joints, height)?;
        Ok(out)
    }

    /// Checks sizes, index ranges, finiteness and weights (bone < 14, weight >= 0, sum 1 ± 1e-3).
    pub fn validate(&self) -> Result<()> {
        let n = self.vertices.len();
        let corrupt = |msg: String| Err(Error::CorruptData(msg));
        if n == 0 || self.quads.is_empty() {
            return corrupt(format!("mesh has {n} vertices and {} faces", self.quads.len()));
        }
        if u32::try_from(n).is_err() {
            return corrupt(format!("mesh has {n} vertices, more than u32 indices address"));
        }
        if self.weights.len() != n {
            return corrupt(format!("{} skin-weight entries for {n} vertices", self.weights.len()));
        }
        if let Some(i) = self.vertices.iter().position(|v| v.iter().any(|c| !c.is_finite())) {
            return corrupt(format!("vertex {i} is not finite"));
        }
        if self.joints.iter().flatten().any(|c| !c.is_finite()) {
            return corrupt("rest joints are not finite".into());
        }
        if let Some(f) = self.quads.iter().position(|q| q.iter().any(|&i| i as usize >= n)) {
            return corrupt(format!("face {f} indexes a vertex >= {n}"));
        }
        for (i, w) in self.weights.iter().enumerate() {
            let bad_bone = w.influences().any(|(b, _)| b >= NUM_BONES);
            let sum: f32 = w.weights.iter().sum();
            if bad_bone || w.weights.iter().any(|&x| !(x >= 0.0)) || (sum - 1.0).abs() > 1e-3 {
                return corrupt(format!("skin weights of vertex {i} are invalid: {w:?}"));
            }
        }
        if let Some(uv) = &self.uvs {
            if uv.quads.len() != self.quads.len() {
                return corrupt(format!("{} UV faces for {} faces", uv.quads.len(), self.quads.len()));
            }
            let m = uv.coords.len();
            if uv.quads.iter().any(|q| q.iter().any(|&i| i as usize >= m)) {
                return corrupt(format!("a UV face indexes a coordinate >= {m}"));
            }
        }
        Ok(())
    }

    /// The body of `gender` with PCA weights `shape` (see [`crate::body::ShapeSpace::synthesize`]) from
    /// `model`, in the rest pose, with MakeHuman's UVs and the model's skin weights.
    pub fn from_model(model: &BodyModel, gender: Gender, shape: &[f64]) -> Result<RiggedMesh> {
        Ok(RiggedMesh::from_rest(model, &model.space(gender).synthesize(shape)?))
    }

    /// A rest shape of `model` with the model's topology, UVs and skin weights (copied).
    pub fn from_rest(model: &BodyModel, rest: &RestShape) -> RiggedMesh {
        RiggedMesh {
            vertices: rest.vertices.clone(),
            quads: model.faces().to_vec(),
            uvs: Some(FaceUvs { coords: model.uvs().to_vec(), quads: model.face_uvs().to_vec() }),
            joints: rest.joints,
            weights: model.skin_weights().to_vec(),
        }
    }

    /// Triangles of the quads (each quad split along its 0–2 diagonal; repeated-corner quads
    /// give one triangle).
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        quads_to_triangles(&self.quads)
    }
}

/// Splits quads into triangles along the 0–2 diagonal; a quad whose last corner repeats its
/// third (or first) is one triangle.
pub fn quads_to_triangles(quads: &[[u32; 4]]) -> Vec<[u32; 3]> {
    let mut out = Vec::with_capacity(quads.len() * 2);
    for q in quads {
        out.push([q[0], q[1], q[2]]);
        if q[3] != q[2] && q[3] != q[0] {
            out.push([q[0], q[2], q[3]]);
        }
    }
    out
}

/// Area-weighted unit vertex normals of a quad mesh (each quad as two triangles, see
/// [`quads_to_triangles`]); a vertex with no non-degenerate face gets +Y. Indices must be in
/// range (see [`RiggedMesh::validate`]); out-of-range faces are skipped.
pub fn vertex_normals(vertices: &[[f32; 3]], quads: &[[u32; 4]]) -> Vec<[f32; 3]> {
    let mut acc = vec![[0.0f64; 3]; vertices.len()];
    let n = vertices.len();
    for t in quads_to_triangles(quads) {
        if t.iter().any(|&i| i as usize >= n) {
            continue;
        }
        let p = t.map(|i| vertices[i as usize].map(|c| c as f64));
        let (e1, e2) = ([0, 1, 2].map(|k| p[1][k] - p[0][k]), [0, 1, 2].map(|k| p[2][k] - p[0][k]));
        let c = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
        for &i in &t {
            for k in 0..3 {
                acc[i as usize][k] += c[k];
            }
        }
    }
    acc.iter()
        .map(|a| {
            let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            if l > 1e-20 {
                a.map(|c| (c / l) as f32)
            } else {
                [0.0, 1.0, 0.0]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::ik::{solve, IkOptions};
    use crate::body::procedural::random_pose;
    use crate::body::skin::{skin, SkinMethod};
    use crate::camera::WeakPerspective;
    use crate::raster::Rasterizer;
    use rand::SeedableRng;

    /// The embedded MakeHuman body poses, skins and rasterises: single-bone vertices follow
    /// their bone exactly and the silhouette is non-empty.
    #[test]
    fn embedded_body_poses_skins_and_rasterises() {
        let model = BodyModel::embedded().unwrap();
        let mesh = RiggedMesh::from_model(&model, Gender::Female, &[]).unwrap();
        mesh.validate().unwrap();
        assert_eq!((mesh.vertices.len(), mesh.quads.len()), (13380, 13378));
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let target = random_pose(&mesh.joints, &mut rng, 0.1);
        let pose = solve(&mesh.joints, &target, &IkOptions { retarget: true }).unwrap();
        for method in [SkinMethod::Linear, SkinMethod::DualQuaternion] {
            let posed = skin(&mesh.vertices, &mesh.weights, &pose, method).unwrap();
            assert!(posed.iter().flatten().all(|c| c.is_finite()));
            let cam = WeakPerspective { sx: 100.0, sy: 100.0, r: nalgebra::Matrix3::identity(), t: [128.0, 128.0] };
            let stats = Rasterizer::new().rasterize(&posed, &mesh.triangles(), &cam, 256, 256, true).unwrap();
            assert!(stats.covered > 1000, "{method:?}: {} px", stats.covered);
        }
    }

    #[test]
    fn scaling_to_a_height_scales_about_the_pelvis() {
        let model = BodyModel::embedded().unwrap();
        let mesh = RiggedMesh::from_model(&model, Gender::Male, &[]).unwrap();
        let h = mesh.height();
        assert!(h > 1.5 && h < 2.0, "{h}");
        let s = mesh.scaled_to_height(1.5 * h).unwrap();
        assert!((s.height() - 1.5 * h).abs() < 1e-5);
        // Every offset from the pelvis is multiplied by 1.5, joints included; the pelvis stays.
        let (head, pelvis) = (crate::skeleton::joint::HEAD, crate::skeleton::joint::PELVIS);
        let o = mesh.joints[pelvis];
        assert_eq!(s.joints[pelvis], o);
        assert!((s.joints[head][1] - o[1] - 1.5 * (mesh.joints[head][1] - o[1])).abs() < 1e-12);
        for i in [0, 7, 9000] {
            for c in 0..3 {
                assert!((s.vertices[i][c] as f64 - o[c] - 1.5 * (mesh.vertices[i][c] as f64 - o[c])).abs() < 1e-5);
            }
        }
        assert_eq!((s.quads.len(), s.weights.len()), (mesh.quads.len(), mesh.weights.len()));
        assert!(matches!(mesh.scaled_to_height(0.0), Err(Error::OutOfRange { name: "height", .. })));
        assert!(mesh.scaled_to_height(f64::NAN).is_err());
    }
}

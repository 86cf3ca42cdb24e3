//! A rigged mesh in plain arrays: the data the shape model produces and posing, skinning,
//! rasterising and export consume. Frame: metres, +Y up, +Z toward the viewer, the character's
//! right at −X; the rest (bind) pose is the shape model's (MakeHuman's A-pose).

use crate::error::{Error, Result};
use crate::skeleton::{Joints3, NUM_BONES};

/// Up to four bone influences of one vertex: `(bone, weight)` with `bone` an index into
/// [`crate::skeleton::BONES`]. Unused slots have weight 0. Weights of a vertex sum to 1.
pub type VertexWeights = [(u8, f32); 4];

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

impl RiggedMesh {
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
            let bad_bone = w.iter().any(|&(b, x)| x != 0.0 && b as usize >= NUM_BONES);
            let sum: f32 = w.iter().map(|&(_, x)| x).sum();
            if bad_bone || w.iter().any(|&(_, x)| !(x >= 0.0)) || (sum - 1.0).abs() > 1e-3 {
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

//! Shape keys (blend shapes) of a fitted body (issue 49): one per shape dimension of the fit,
//! each the vertex displacement that adds one standard deviation of that principal component to
//! the body, so an artist can adjust the body after the fit. The exported base mesh is the
//! fitted body itself and every key's value is 0: the default look is the fit's, a key at 1
//! adds one standard deviation of its component, −1 takes one away.

use nalgebra::{UnitQuaternion, Vector3};

use crate::body::VertexWeights;
use crate::error::{Error, Result};

/// One shape key: a name and a displacement per vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeKey {
    /// The key's name (`shape_01`, `shape_02`, …: principal component 1, 2, … of the body's
    /// shape space).
    pub name: String,
    /// Displacement of each vertex at value 1, metres (in the frame of the mesh it belongs to).
    pub deltas: Vec<[f32; 3]>,
}

/// The name of the key of principal component `k` (0-based): `shape_01` for `k` = 0.
pub fn key_name(k: usize) -> String {
    format!("shape_{:02}", k + 1)
}

impl ShapeKey {
    /// Checks the key against a mesh of `vertices` vertices: one finite displacement per vertex.
    /// Errors: [`Error::OutOfRange`] (`"shape key"`) for a count mismatch, [`Error::NonFinite`].
    pub fn check(&self, vertices: usize) -> Result<()> {
        if self.deltas.len() != vertices {
            return Err(Error::OutOfRange {
                name: "shape key",
                detail: format!("{}: {} displacements for {vertices} vertices", self.name, self.deltas.len()),
            });
        }
        match self.deltas.iter().flatten().find(|c| !c.is_finite()) {
            Some(&c) => Err(Error::NonFinite { name: "shape key displacement", value: c as f64 }),
            None => Ok(()),
        }
    }

    /// The key carried through a linear blend skinning with `skin` and per-bone global
    /// `rotations` (rest → posed): skinning is affine in a vertex's position, so a displacement
    /// `d` of the rest becomes `Σ_b w_b Q_b d` of the posed mesh, exactly.
    pub fn skinned(&self, skin: &[VertexWeights], rotations: &[UnitQuaternion<f64>]) -> ShapeKey {
        let deltas = self
            .deltas
            .iter()
            .zip(skin)
            .map(|(d, w)| {
                let d = Vector3::new(d[0] as f64, d[1] as f64, d[2] as f64);
                let mut out = Vector3::zeros();
                for (b, x) in w.influences() {
                    if let Some(q) = rotations.get(b) {
                        out += (q * d) * x as f64;
                    }
                }
                [out.x as f32, out.y as f32, out.z as f32]
            })
            .collect();
        ShapeKey { name: self.name.clone(), deltas }
    }
}

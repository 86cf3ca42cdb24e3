//! The fit-only proxy body: a deterministic decimation of the body mesh ([`super::decimate`],
//! on the average of the two genders' mean shapes) whose vertices are a subset of the body's, so
//! its PCA rows, joint basis and skin weights are plain subsets of the model's. The shape fit
//! synthesises, skins and rasterises only these vertices, several times cheaper than the full
//! mesh, for a silhouette that stays within about a pixel of the full one at the fit's raster
//! resolution (tested in `tests/fit_proxy.rs`). Built once per model on first use (about
//! 0.1–0.25 s)
//! ([`BodyModel::fit_proxy`]).

use std::sync::OnceLock;

use super::decimate::decimate;
use super::model::{BodyModel, ShapeChoice, ShapeSpace, VertexWeights};
use super::Gender;
use crate::error::Result;
use crate::skeleton::Joints3;

/// Vertices kept by the proxy of [`BodyModel::fit_proxy`] (of 13380 in the MakeHuman body).
pub const PROXY_VERTICES: usize = 2500;

/// One gender's shape space restricted to the proxy's vertices.
#[derive(Clone, Debug)]
pub struct ProxySpace {
    mean: Vec<[f32; 3]>,
    /// `num_components` blocks of `3 × kept` floats.
    basis: Vec<f32>,
    mean_joints: Joints3,
    joint_basis: Vec<Joints3>,
}

impl ProxySpace {
    fn new(space: &ShapeSpace, kept: &[u32]) -> Self {
        let n = space.num_vertices();
        let basis = (0..space.num_components())
            .flat_map(|k| {
                kept.iter().flat_map(move |&i| {
                    space.basis[k * 3 * n + 3 * i as usize..k * 3 * n + 3 * i as usize + 3].iter().copied()
                })
            })
            .collect();
        Self {
            mean: kept.iter().map(|&i| space.mean[i as usize]).collect(),
            basis,
            mean_joints: space.mean_joints,
            joint_basis: space.joint_basis.clone(),
        }
    }

    /// Number of proxy vertices.
    pub fn num_vertices(&self) -> usize {
        self.mean.len()
    }

    /// The proxy's rest vertices (metres, into `out`, resized) and the canonical joints of the
    /// shape with PCA weights `weights`: the same as [`ShapeSpace::synthesize`] restricted to
    /// the kept vertices (up to f32 rounding). Errors as `synthesize` (too many weights, a
    /// non-finite weight).
    pub fn synthesize_into(&self, space: &ShapeSpace, weights: &[f64], out: &mut Vec<[f32; 3]>) -> Result<Joints3> {
        space.check_weights(weights)?;
        let m = self.mean.len();
        out.clear();
        out.extend_from_slice(&self.mean);
        let mut joints = self.mean_joints;
        for (k, &w) in weights.iter().enumerate() {
            if w == 0.0 {
                continue;
            }
            let wf = w as f32;
            for (o, b) in out.as_flattened_mut().iter_mut().zip(&self.basis[k * 3 * m..(k + 1) * 3 * m]) {
                *o += wf * b;
            }
            for (j, jb) in joints.iter_mut().zip(&self.joint_basis[k]) {
                for c in 0..3 {
                    j[c] += w * jb[c];
                }
            }
        }
        Ok(joints)
    }
}

/// The decimated body used by the shape fit. Immutable; `Send + Sync`.
#[derive(Clone, Debug)]
pub struct FitProxy {
    kept: Vec<u32>,
    triangles: Vec<[u32; 3]>,
    skin: Vec<VertexWeights>,
    spaces: [ProxySpace; 2],
    /// The blended space restricted to the kept vertices, built on first use.
    blended: OnceLock<ProxySpace>,
}

impl FitProxy {
    /// Decimates `model`'s body to at most `target_vertices` vertices (see the module docs).
    /// Errors: a target of 0.
    pub fn new(model: &BodyModel, target_vertices: usize) -> Result<Self> {
        let (f, m) = (model.space(Gender::Female).mean(), model.space(Gender::Male).mean());
        let average: Vec<[f32; 3]> =
            f.iter().zip(m).map(|(a, b)| std::array::from_fn(|c| 0.5 * (a[c] + b[c]))).collect();
        let d = decimate(&average, &model.triangles(), target_vertices)?;
        Ok(Self {
            skin: d.kept.iter().map(|&i| model.skin[i as usize]).collect(),
            spaces: [
                ProxySpace::new(model.space(Gender::Female), &d.kept),
                ProxySpace::new(model.space(Gender::Male), &d.kept),
            ],
            kept: d.kept,
            triangles: d.triangles,
            blended: OnceLock::new(),
        })
    }

    /// Indices of the proxy's vertices in the body mesh, ascending.
    pub fn kept(&self) -> &[u32] {
        &self.kept
    }

    /// Triangles over the proxy's vertices (indices into [`FitProxy::kept`]), counter-clockwise
    /// seen from outside like the body's faces.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Skin weights of the proxy's vertices (the body's, subset).
    pub fn skin_weights(&self) -> &[VertexWeights] {
        &self.skin
    }

    /// The shape space of `gender` restricted to the proxy's vertices.
    pub fn space(&self, gender: Gender) -> &ProxySpace {
        &self.spaces[gender.index()]
    }

    /// The shape space of `choice` restricted to the proxy's vertices; `model` must be the
    /// model this proxy was built from (the blended space is taken from it on first use).
    pub fn shape_space(&self, model: &BodyModel, choice: ShapeChoice) -> Result<&ProxySpace> {
        match choice {
            ShapeChoice::Gendered(g) => Ok(self.space(g)),
            ShapeChoice::Blended => {
                if let Some(p) = self.blended.get() {
                    return Ok(p);
                }
                let built = ProxySpace::new(model.blended()?.space(), &self.kept);
                Ok(self.blended.get_or_init(|| built))
            }
        }
    }
}

/// Lazily built [`FitProxy`] of a model (cloning a model clones a built proxy).
#[derive(Clone, Debug, Default)]
pub(crate) struct ProxyCell(OnceLock<FitProxy>);

impl BodyModel {
    /// The model's fit proxy with [`PROXY_VERTICES`] vertices, built on first use (a fraction
    /// of a second) and then shared. Thread-safe.
    pub fn fit_proxy(&self) -> Result<&FitProxy> {
        if let Some(p) = self.proxy.0.get() {
            return Ok(p);
        }
        let built = FitProxy::new(self, PROXY_VERTICES)?;
        Ok(self.proxy.0.get_or_init(|| built))
    }
}

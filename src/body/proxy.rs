//! The fit-only proxy body: a deterministic decimation of the body mesh ([`super::decimate`],
//! on the average of the two genders' mean shapes) whose vertices are a subset of the body's, so
//! its PCA rows, joint basis and skin weights are plain subsets of the model's. The shape fit
//! synthesises, skins and rasterises only these vertices, several times cheaper than the full
//! mesh, for a silhouette within about a pixel (at most 2 px) of the full one at the fit's raster
//! resolution (tested in `tests/fit_proxy.rs`). Made once per model on first use
//! ([`BodyModel::fit_proxy`]): for the embedded model the decimation's result is read from a
//! precomputed table (`assets/fit_proxy.bin`, [`FitProxy::to_table`]), used only when
//! the fingerprint of the decimation's input (target, average mean shape, triangles) matches.

use std::sync::OnceLock;

use super::decimate::decimate;
use super::model::{BodyModel, ShapeChoice, ShapeSpace, VertexWeights};
use super::Gender;
use crate::error::Result;
use crate::skeleton::Joints3;

/// Vertices kept by the proxy of [`BodyModel::fit_proxy`] (of 13380 in the MakeHuman body).
pub const PROXY_VERTICES: usize = 1300;

/// The embedded model's proxy at [`PROXY_VERTICES`], precomputed ([`FitProxy::to_table`]; the
/// test suite checks it is today's decimation byte for byte).
static EMBEDDED_TABLE: &[u8] = include_bytes!("../../assets/fit_proxy.bin");

/// First bytes of a proxy table.
const TABLE_MAGIC: &[u8; 8] = b"SKBPRXY1";

/// The decimation's input: the average of the two genders' mean shapes, and the body's
/// triangles.
struct DecimationInput {
    average: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
}

impl DecimationInput {
    fn of(model: &BodyModel) -> Self {
        let (f, m) = (model.space(Gender::Female).mean(), model.space(Gender::Male).mean());
        let average = f.iter().zip(m).map(|(a, b)| std::array::from_fn(|c| 0.5 * (a[c] + b[c]))).collect();
        Self { average, triangles: model.triangles() }
    }

    /// 64-bit FNV-1a fingerprint of this input decimated to `target` vertices (the target, the
    /// positions' f32 bits, the triangles).
    fn fingerprint(&self, target: usize) -> u64 {
        let words = [target as u64, self.average.len() as u64, self.triangles.len() as u64]
            .into_iter()
            .chain(self.average.iter().flatten().map(|c| c.to_bits() as u64))
            .chain(self.triangles.iter().flatten().map(|&i| i as u64));
        words.fold(0xcbf2_9ce4_8422_2325u64, |h, w| {
            w.to_le_bytes().iter().fold(h, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
        })
    }
}

/// Reads little-endian u32s from `bytes` at `*at`, advancing it; `None` past the end.
fn read_u32s(bytes: &[u8], at: &mut usize, n: usize) -> Option<Vec<u32>> {
    let end = at.checked_add(n.checked_mul(4)?)?;
    let chunk = bytes.get(*at..end)?;
    *at = end;
    Some(chunk.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect())
}

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
        Self::decimated(model, &DecimationInput::of(model), target_vertices)
    }

    fn decimated(model: &BodyModel, input: &DecimationInput, target_vertices: usize) -> Result<Self> {
        let d = decimate(&input.average, &input.triangles, target_vertices)?;
        Ok(Self::from_parts(model, d.kept, d.triangles))
    }

    fn from_parts(model: &BodyModel, kept: Vec<u32>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            skin: kept.iter().map(|&i| model.skin[i as usize]).collect(),
            spaces: [
                ProxySpace::new(model.space(Gender::Female), &kept),
                ProxySpace::new(model.space(Gender::Male), &kept),
            ],
            kept,
            triangles,
            blended: OnceLock::new(),
        }
    }

    /// This proxy as a table (a new buffer) that [`BodyModel::fit_proxy`] reads instead of
    /// decimating `model` again at `target_vertices` (`model` and the target must be those it
    /// was built from): the magic `SKBPRXY1`, the decimation input's fingerprint (u64), then
    /// the number of kept vertices and of triangles, the kept indices and the triangles' indices
    /// (u32 each, all little-endian).
    pub fn to_table(&self, model: &BodyModel, target_vertices: usize) -> Vec<u8> {
        let mut out = TABLE_MAGIC.to_vec();
        out.extend_from_slice(&DecimationInput::of(model).fingerprint(target_vertices).to_le_bytes());
        for n in [self.kept.len(), self.triangles.len()] {
            out.extend_from_slice(&(n as u32).to_le_bytes());
        }
        for &i in self.kept.iter().chain(self.triangles.iter().flatten()) {
            out.extend_from_slice(&i.to_le_bytes());
        }
        out
    }

    /// The proxy of `model` (decimation input `input`) at `target_vertices` from `table`
    /// ([`FitProxy::to_table`]); `None` when the table is for another model or target, or is
    /// malformed (then decimate).
    fn from_table(model: &BodyModel, input: &DecimationInput, target_vertices: usize, table: &[u8]) -> Option<Self> {
        let rest = table.strip_prefix(TABLE_MAGIC)?;
        let stored = u64::from_le_bytes(rest.get(..8)?.try_into().ok()?);
        if stored != input.fingerprint(target_vertices) {
            return None;
        }
        let mut at = 8;
        let counts = read_u32s(rest, &mut at, 2)?;
        let kept = read_u32s(rest, &mut at, counts[0] as usize)?;
        let flat = read_u32s(rest, &mut at, 3 * counts[1] as usize)?;
        let ascending = kept.windows(2).all(|w| w[0] < w[1]);
        let in_range = kept.last().is_some_and(|&i| (i as usize) < model.num_vertices())
            && flat.iter().all(|&i| (i as usize) < kept.len());
        if at != rest.len() || !ascending || !in_range {
            return None;
        }
        Some(Self::from_parts(model, kept, flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()))
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
    /// The model's fit proxy with [`PROXY_VERTICES`] vertices, made on first use (read from
    /// the precomputed table for the embedded model, else decimated in a fraction of a second)
    /// and then shared. Thread-safe.
    pub fn fit_proxy(&self) -> Result<&FitProxy> {
        if let Some(p) = self.proxy.0.get() {
            return Ok(p);
        }
        let input = DecimationInput::of(self);
        let built = match FitProxy::from_table(self, &input, PROXY_VERTICES, EMBEDDED_TABLE) {
            Some(p) => p,
            None => FitProxy::decimated(self, &input, PROXY_VERTICES)?,
        };
        Ok(self.proxy.0.get_or_init(|| built))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table reads back as the proxy it was written from, and only for its own model and
    /// target; truncated, extended or out-of-range tables are refused (the caller decimates).
    #[test]
    fn a_table_reads_back_only_for_its_model_and_target_and_when_well_formed() {
        let model = BodyModel::embedded().unwrap();
        let target = 300;
        let proxy = FitProxy::new(&model, target).unwrap();
        let table = proxy.to_table(&model, target);
        let input = DecimationInput::of(&model);
        let read = FitProxy::from_table(&model, &input, target, &table).unwrap();
        assert_eq!(
            (read.kept(), read.triangles(), read.skin_weights()),
            (proxy.kept(), proxy.triangles(), proxy.skin_weights())
        );
        assert!(FitProxy::from_table(&model, &input, target + 1, &table).is_none());
        assert!(FitProxy::from_table(&model, &input, target, &table[..table.len() - 4]).is_none());
        assert!(FitProxy::from_table(&model, &input, target, &[&table[..], &[0; 4]].concat()).is_none());
        assert!(FitProxy::from_table(&model, &input, target, &table[1..]).is_none());
        assert!(FitProxy::from_table(&model, &input, target, &[]).is_none());
        let mut bad = table.clone();
        let last = bad.len() - 4;
        bad[last..].copy_from_slice(&(proxy.kept().len() as u32).to_le_bytes());
        assert!(
            FitProxy::from_table(&model, &input, target, &bad).is_none(),
            "a triangle index past the kept vertices"
        );
        let mut other = model.clone();
        other.skin[0] = other.skin[1];
        assert!(
            FitProxy::from_table(&other, &DecimationInput::of(&other), target, &table).is_some(),
            "skin weights are not the decimation's input"
        );
    }
}

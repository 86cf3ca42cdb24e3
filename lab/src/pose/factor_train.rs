//! Training of the learned factor prior ([`sketchbody::pose::factor_prior`]): training poses (normalised,
//! retargeted mocap frames, left/right mirrored at random) with random group factors (a share
//! with the reference proportions, the rest head ×U(1, 1.8) and each other group ×U(0.75,
//! 1.35), the ranges of the stylised benchmark), seen by random weak-perspective cameras (yaw
//! U(±30°) or |yaw| U(60°, 90°), pitch U(±10°), 500-px figures) with Gaussian 2-D noise of a
//! random σ in [0, `max_noise_px`]; two small networks ([`sketchbody::pose::mlp`]) from the standardised
//! inputs, trained by Adam: one to the standardised log factors, one to the joints' depths
//! (camera frame, relative to the pelvis, over the figure's 2-D scale); the factors' predictive
//! spread and the depths' figures from the last [`TrainParams::spread_share`] of the samples,
//! left out of both fits. Deterministic for a seed.

use std::path::PathBuf;

use nalgebra::{DMatrix, Matrix3, Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

use super::learn::{clip_matches, motion_files, retarget_frames};
use super::metrics::LIMB_BONES;
use crate::pose::mlp_train::{self as mlp, MlpParams};
use sketchbody::error::{Error, Result};
use sketchbody::pose::bend_prior::BendPrior;
use sketchbody::pose::factor_prior::{group_lengths, inputs, standardise, FactorPrior, FORMAT, NUM_INPUTS, VERSION};
use sketchbody::pose::figure::{BodyFactors, BONE_GROUP, NUM_GROUPS};
use sketchbody::pose::mlp::Mlp;
use sketchbody::pose::motion::{mirror_pose, normalize_pose, read_motion_csv, REF_STATURE};
use sketchbody::skeleton::{joint, Joints2, Joints3, BONES, NUM_BONES, NUM_JOINTS};

/// Parameters of [`train`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrainParams {
    /// Seed of the poses, cameras, factors and noise.
    pub seed: u64,
    /// Number of projected samples.
    pub samples: usize,
    /// Width of the network's two hidden layers.
    pub hidden: usize,
    /// Passes of the training over the samples.
    pub epochs: usize,
    /// Share of samples with the reference proportions (all factors 1).
    pub standard_share: f64,
    /// Largest 2-D noise σ, px on a 500-px figure.
    pub max_noise_px: f64,
    /// Share of samples left out of the fit to measure the predictive spread.
    pub spread_share: f64,
}

impl Default for TrainParams {
    fn default() -> Self {
        TrainParams {
            seed: 1,
            samples: 200_000,
            hidden: 128,
            epochs: 20,
            standard_share: 0.25,
            max_noise_px: 5.0,
            spread_share: 0.1,
        }
    }
}

/// One training sample: the raw inputs, the targets `ln(s k_g / s₂)` and the joints' depths
/// toward the camera relative to the pelvis, `s Δz / s₂`.
struct Sample {
    x: [f64; NUM_INPUTS],
    t: [f64; NUM_GROUPS],
    d: [f64; NUM_JOINTS],
}

fn sample<R: Rng>(rng: &mut R, frames: &[Joints3], lengths: &[f64; NUM_BONES], p: &TrainParams) -> Option<Sample> {
    let normal = Normal::new(0.0, 1.0).ok()?;
    let mut f = frames[rng.random_range(0..frames.len())];
    if rng.random_bool(0.5) {
        f = mirror_pose(&f);
    }
    let mut k = [1.0; NUM_GROUPS];
    if !rng.random_bool(p.standard_share.clamp(0.0, 1.0)) {
        k[0] = rng.random_range(1.0..=1.8);
        for v in k.iter_mut().skip(1) {
            *v = rng.random_range(0.75..=1.35);
        }
    }
    let x3 = BodyFactors { k }.apply(&f);
    let yaw = if rng.random_bool(0.5) {
        rng.random_range(-30.0f64..=30.0)
    } else {
        let y = rng.random_range(60.0f64..=90.0);
        if rng.random_bool(0.5) {
            y
        } else {
            -y
        }
    };
    let pitch = rng.random_range(-10.0f64..=10.0);
    let r: Matrix3<f64> = *(Rotation3::from_axis_angle(&Vector3::x_axis(), pitch.to_radians())
        * Rotation3::from_axis_angle(&Vector3::y_axis(), yaw.to_radians()))
    .matrix();
    let s = 500.0 / REF_STATURE;
    let sigma = rng.random_range(0.0..=p.max_noise_px.max(0.0));
    let mut j = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
    for (q, x) in j.xy.iter_mut().zip(&x3) {
        let y = r * Vector3::from(*x);
        *q = [s * y.x + sigma * normal.sample(rng), -s * y.y + sigma * normal.sample(rng)];
    }
    let (s2, x) = inputs(&j, lengths)?;
    // The group's true length relative to the reference lengths.
    let mut true_len = [0.0; NUM_GROUPS];
    for (b, &(pa, c)) in BONES.iter().enumerate() {
        true_len[BONE_GROUP[b]] += (Vector3::from(x3[c]) - Vector3::from(x3[pa])).norm();
    }
    let refl = group_lengths(lengths);
    let t = std::array::from_fn(|g| (s * true_len[g] / refl[g] / s2).ln());
    let pelvis = (r * Vector3::from(x3[joint::PELVIS])).z;
    let d = std::array::from_fn(|k| s * ((r * Vector3::from(x3[k])).z - pelvis) / s2);
    if t.iter().chain(&x).chain(&d).all(|v: &f64| v.is_finite()) {
        Some(Sample { x, t, d })
    } else {
        None
    }
}

/// Depth difference (metres at the figure's 2-D scale) from which a limb's depth order counts.
const ORDER_MIN_DEPTH: f64 = 0.05;

/// Mean and spread (floored at 1e-6) of each target `get` returns, over `samples`.
fn target_stats<const N: usize>(samples: &[Sample], get: impl Fn(&Sample) -> [f64; N]) -> ([f64; N], [f64; N]) {
    let n = samples.len() as f64;
    let mean: [f64; N] = std::array::from_fn(|k| samples.iter().map(|s| get(s)[k]).sum::<f64>() / n);
    let sd = std::array::from_fn(|k| {
        (samples.iter().map(|s| (get(s)[k] - mean[k]).powi(2)).sum::<f64>() / n).sqrt().max(1e-6)
    });
    (mean, sd)
}

/// Folds the targets' standardisation (`mean`, `sd` per output) into the last layer, so that
/// the network outputs the targets' own units.
fn unstandardise_outputs(net: &mut Mlp, mean: &[f64], sd: &[f64]) {
    if let Some(last) = net.layers.last_mut() {
        for (o, (m, s)) in mean.iter().zip(sd).enumerate().take(last.outputs) {
            for w in &mut last.weights[o * last.inputs..(o + 1) * last.inputs] {
                *w = (*w as f64 * s) as f32;
            }
            last.bias[o] = (last.bias[o] as f64 * s + m) as f32;
        }
    }
}

/// Smallest number of samples [`train`] accepts.
pub const MIN_SAMPLES: usize = 200;

/// Trains the prior on `frames` (normalised training poses) for the reference bone lengths
/// `lengths` (module doc); `provenance` is stored with the fit's figures appended; `progress`
/// is called after each epoch with its number (the depth network's epochs follow the factor
/// network's) and the mean training loss (standardised targets). Errors: [`Error::OutOfRange`]
/// for no frames, fewer than [`MIN_SAMPLES`] samples or bad network parameters,
/// [`Error::Degenerate`] when too few samples are usable or the training diverges.
pub fn train(
    frames: &[Joints3],
    lengths: &[f64; NUM_BONES],
    p: &TrainParams,
    provenance: &str,
    progress: impl FnMut(usize, f64),
) -> Result<FactorPrior> {
    if frames.is_empty() {
        return Err(Error::OutOfRange { name: "frames", detail: "no training frames".into() });
    }
    let held = ((p.samples as f64) * p.spread_share.clamp(0.0, 0.5)).round() as usize;
    if p.samples < MIN_SAMPLES || held == 0 {
        return Err(Error::OutOfRange {
            name: "samples",
            detail: format!("{} (at least {MIN_SAMPLES} with a non-empty spread share)", p.samples),
        });
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(p.seed);
    let mut data = Vec::with_capacity(p.samples);
    let mut tries = 0;
    while data.len() < p.samples && tries < 4 * p.samples {
        tries += 1;
        if let Some(s) = sample(&mut rng, frames, lengths, p) {
            data.push(s);
        }
    }
    if data.len() < p.samples {
        return Err(Error::Degenerate("factor prior: too few usable training samples".into()));
    }
    let (fit, test) = data.split_at(p.samples - held);
    let n = fit.len() as f64;
    let mut mean = [0.0; NUM_INPUTS];
    for s in fit {
        for i in 0..NUM_INPUTS {
            mean[i] += s.x[i] / n;
        }
    }
    let mut scale = [0.0; NUM_INPUTS];
    for s in fit {
        for i in 0..NUM_INPUTS {
            scale[i] += (s.x[i] - mean[i]).powi(2) / n;
        }
    }
    let scale = scale.map(|v| v.sqrt().max(1e-6));
    let (mean_t, sd_t) = target_stats(fit, |f| f.t);
    let x = DMatrix::from_fn(NUM_INPUTS, fit.len(), |i, c| standardise(fit[c].x[i], mean[i], scale[i]) as f32);
    let t = DMatrix::from_fn(NUM_GROUPS, fit.len(), |g, c| ((fit[c].t[g] - mean_t[g]) / sd_t[g]) as f32);
    let net_params = MlpParams { hidden: p.hidden, epochs: p.epochs, seed: p.seed, ..MlpParams::default() };
    let mut progress = progress;
    let mut network = mlp::train(&x, &t, &net_params, &mut progress)?;
    unstandardise_outputs(&mut network, &mean_t, &sd_t);
    let (mean_d, sd_d) = target_stats(fit, |f| f.d);
    let d = DMatrix::from_fn(NUM_JOINTS, fit.len(), |k, c| ((fit[c].d[k] - mean_d[k]) / sd_d[k]) as f32);
    let mut depth_network = mlp::train(&x, &d, &net_params, |e, l| progress(p.epochs + e, l))?;
    unstandardise_outputs(&mut depth_network, &mean_d, &sd_d);
    // Predictive spread on the samples left out.
    let mut sq = [0.0; NUM_GROUPS];
    let mut sq_const = [0.0; NUM_GROUPS];
    let (mut sq_depth, mut order_right, mut order_total) = (0.0, 0usize, 0usize);
    for s in test {
        let z: Vec<f64> = (0..NUM_INPUTS).map(|i| standardise(s.x[i], mean[i], scale[i])).collect();
        let shape = || Error::Degenerate("factor prior: network shape".into());
        let y = network.forward(&z).ok_or_else(shape)?;
        for g in 0..NUM_GROUPS {
            sq[g] += (y[g] - s.t[g]).powi(2);
            sq_const[g] += (mean_t[g] - s.t[g]).powi(2);
        }
        let dz = depth_network.forward(&z).ok_or_else(shape)?;
        sq_depth += dz.iter().zip(&s.d).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        for (a, b) in LIMB_BONES.map(|b| BONES[b]) {
            let truth = s.d[b] - s.d[a];
            if truth.abs() > ORDER_MIN_DEPTH {
                order_total += 1;
                order_right += usize::from((dz[b] - dz[a]).signum() == truth.signum());
            }
        }
    }
    let m = test.len() as f64;
    let sd: Vec<f64> = sq.iter().map(|v| (v / m).sqrt().max(1e-3)).collect();
    let base: Vec<f64> = sq_const.iter().map(|v| (v / m).sqrt()).collect();
    let depth_rms = (sq_depth / (m * NUM_JOINTS as f64)).sqrt();
    let fmt = |v: &[f64]| v.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>().join(", ");
    let provenance = format!(
        "{provenance}\nparams: seed={} samples={} hidden={} epochs={} standard_share={} max_noise_px={} \
         spread_share={}\nleft-out RMS of ln factor by group (head, torso, shoulders, arms, hips, legs): {} \
         (constant: {}); left-out joint depths: RMS {depth_rms:.4} (m at the figure's 2-D scale), the depth order \
         of limbs (upper arms, forearms, thighs, shins) pointing more than {ORDER_MIN_DEPTH} m toward or away from the viewer right on {order_right} of \
         {order_total}; bend prior of the knees and elbows counted on the {} training frames",
        p.seed,
        p.samples,
        p.hidden,
        p.epochs,
        p.standard_share,
        p.max_noise_px,
        p.spread_share,
        fmt(&sd),
        fmt(&base),
        frames.len()
    );
    let prior = FactorPrior {
        format: FORMAT.into(),
        version: VERSION,
        provenance,
        lengths: lengths.to_vec(),
        mean: mean.to_vec(),
        scale: scale.to_vec(),
        network,
        depth_network,
        sd,
        bend: Some(BendPrior::learn(frames)),
    };
    // Round-trip through the checks of the file format.
    FactorPrior::from_json(&prior.to_json())
}

/// Trains the prior as `sketchbody-lab train-factor-prior` does: the clips of the `mocap` folders
/// of motion tables not matching `held_out` ([`clip_matches`]), retargeted onto `skeletons`
/// (the body model's mean skeletons for the library's prior) and normalised, for the reference
/// lengths `lengths` (named `lengths_of` in the provenance). The provenance records the folder
/// names (not their paths, so that the asset does not depend on where the data lives), the
/// clips, the held-out names and the licences of the library's data; `progress` as in
/// [`train`]. Errors: reading the clips, and those of [`train`].
pub fn train_from_mocap(
    mocap: &[PathBuf],
    held_out: &[String],
    skeletons: &[(String, Joints3)],
    lengths: &[f64; NUM_BONES],
    lengths_of: &str,
    p: &TrainParams,
    progress: impl FnMut(usize, f64),
) -> Result<FactorPrior> {
    let (mut frames, mut clips) = (Vec::new(), Vec::new());
    for dir in mocap {
        for f in motion_files(dir)? {
            let name = f.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            if held_out.iter().any(|h| clip_matches(h, &name)) {
                continue;
            }
            frames.extend(retarget_frames(&name, read_motion_csv(&f)?, skeletons)?.iter().filter_map(normalize_pose));
            clips.push(name);
        }
    }
    let folders: Vec<String> =
        mocap.iter().map(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()).collect();
    let provenance = format!(
        "sketchbody-lab train-factor-prior, motion folders {} (../shared/data/mocap/<folder> for the library's prior), \
         bone lengths of {lengths_of}, deterministic. Data: DeepMimic clips (MIT licence) and CMU Graphics Lab \
         clips (mocap.cs.cmu.edu, created with funding from NSF EIA-0196217), retargeted onto {} and normalised \
         to 1.75 m; the file holds network weights only, no motion data.\nclips ({}, {} frames): {}\nheld_out: {}",
        folders.join(", "),
        if skeletons.is_empty() {
            "nothing (their own skeletons)".to_string()
        } else {
            skeletons.iter().map(|s| s.0.as_str()).collect::<Vec<_>>().join(", ")
        },
        clips.len(),
        frames.len(),
        clips.join(","),
        held_out.join(",")
    );
    train(&frames, lengths, p, &provenance, progress)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sketchbody::pose::dict_io;
    use sketchbody::pose::dictionary::vec_to_pose;
    use sketchbody::pose::figure::{estimate_factors, estimate_factors_with_prior};

    /// Training poses for the tests: every 40th exemplar of the embedded dictionary.
    fn poses() -> (Vec<Joints3>, [f64; NUM_BONES]) {
        let d = dict_io::embedded().unwrap();
        let frames = d.exemplars.column_iter().step_by(40).map(|c| vec_to_pose(c.as_slice())).collect();
        (frames, d.bone_lengths)
    }

    #[test]
    fn training_is_deterministic_and_checks_its_input() {
        let (frames, lengths) = poses();
        let p = TrainParams { samples: 2000, hidden: 16, epochs: 3, ..TrainParams::default() };
        let mut epochs = Vec::new();
        let a = train(&frames, &lengths, &p, "test", |e, _| epochs.push(e)).unwrap();
        assert_eq!(epochs, [1, 2, 3, 4, 5, 6]);
        let b = train(&frames, &lengths, &p, "test", |_, _| ()).unwrap();
        assert_eq!(a.to_json(), b.to_json());
        let c = train(&frames, &lengths, &TrainParams { seed: 2, ..p }, "test", |_, _| ()).unwrap();
        assert_ne!(a.network, c.network);
        assert!(a.provenance.starts_with("test\nparams: seed=1"));
        assert!(matches!(train(&[], &lengths, &p, "t", |_, _| ()), Err(Error::OutOfRange { name: "frames", .. })));
        let few = TrainParams { samples: 100, ..p };
        assert!(matches!(
            train(&frames, &lengths, &few, "t", |_, _| ()),
            Err(Error::OutOfRange { name: "samples", .. })
        ));
    }

    /// On stylised figures (frontal and side views, exact joints) the factor estimate under the
    /// embedded learned prior recovers the group factors (up to the common scale the image
    /// cannot show) better than under the fixed prior, both given the true first estimate (an
    /// oracle for the bound, which the pose step's first estimate is not); the learned
    /// prediction alone comes close to that oracle bound.
    #[test]
    fn the_learned_prior_recovers_stylised_factors_better_than_the_bound() {
        let prior = FactorPrior::embedded().unwrap();
        let (frames, lengths) = poses();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let s = 500.0 / REF_STATURE;
        let (mut err_learned, mut err_bound, mut err_both) = (0.0, 0.0, 0.0);
        for i in 0..200 {
            let f = frames[(i * 37) % frames.len()];
            let mut k = [1.0; NUM_GROUPS];
            k[0] = rng.random_range(1.0..=1.8);
            for v in k.iter_mut().skip(1) {
                *v = rng.random_range(0.75..=1.35);
            }
            let yaw: f64 = if i % 2 == 0 { rng.random_range(-30.0..=30.0) } else { rng.random_range(60.0..=90.0) };
            let r: Matrix3<f64> = *Rotation3::from_axis_angle(&Vector3::y_axis(), yaw.to_radians()).matrix();
            let x3 = BodyFactors { k }.apply(&f);
            let mut j = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
            for (q, x) in j.xy.iter_mut().zip(&x3) {
                let y = r * Vector3::from(*x);
                *q = [s * y.x + 250.0, -s * y.y + 300.0];
            }
            // The true effective factors relative to the reference lengths, as logs.
            let mut len = [0.0; NUM_GROUPS];
            for (b, &(p, c)) in BONES.iter().enumerate() {
                len[BONE_GROUP[b]] += (Vector3::from(x3[c]) - Vector3::from(x3[p])).norm();
            }
            let refl = group_lengths(&lengths);
            let truth: [f64; NUM_GROUPS] = std::array::from_fn(|g| (len[g] / refl[g]).ln());
            let pred = prior.predict(&j, &lengths).unwrap();
            let learned: [f64; NUM_GROUPS] = std::array::from_fn(|g| pred.log_scale[g] - s.ln());
            let bound = estimate_factors(&j, &lengths, &f, &r, s, s).k.map(f64::ln);
            let gauss: [(f64, f64); NUM_GROUPS] = std::array::from_fn(|g| (learned[g], pred.sd[g]));
            let both = estimate_factors_with_prior(&j, &lengths, &f, &r, s, s, Some(&gauss)).k.map(f64::ln);
            // RMS over the groups after removing the common offset.
            let rms = |e: &[f64; NUM_GROUPS]| {
                let d: Vec<f64> = (0..NUM_GROUPS).map(|g| e[g] - truth[g]).collect();
                let m = d.iter().sum::<f64>() / NUM_GROUPS as f64;
                (d.iter().map(|v| (v - m).powi(2)).sum::<f64>() / NUM_GROUPS as f64).sqrt()
            };
            err_learned += rms(&learned) / 200.0;
            err_bound += rms(&bound) / 200.0;
            err_both += rms(&both) / 200.0;
        }
        eprintln!("learned alone {err_learned:.3}, fixed prior {err_bound:.3}, learned prior {err_both:.3}");
        assert!(err_both < 0.9 * err_bound, "learned prior {err_both:.3}, fixed prior {err_bound:.3}");
        assert!(err_learned < 1.2 * err_bound && err_learned < 0.08, "learned alone {err_learned:.3}");
    }
}

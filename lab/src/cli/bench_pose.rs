//! `sketchbody-lab bench-pose`: accuracy and speed of the 3-D pose step on held-out motion clips
//! (docs/benchmarks.md, "3-D pose"). Ground-truth 2-D joints come from normalised held-out
//! poses (1.75 m person) seen by weak-perspective cameras with yaw ~ U(±30°), pitch ~ U(±10°),
//! sx = sy = 500 px / 1.75 m, plus Gaussian noise σ per coordinate. Errors are in mm.

use std::path::PathBuf;
use std::time::Instant;

use nalgebra::{Matrix3, Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use sketchbody::body::BodyModel;
use sketchbody::camera::WeakPerspective;
use sketchbody::pose::factor_prior::FactorPrior;
use sketchbody::pose::motion::{normalize_pose, read_motion_csv, REF_STATURE};
use sketchbody::pose::options::{kappa_from_paper, RotationTarget, PAPER_ALPHA, PAPER_KAPPA};
use sketchbody::pose::{dict_io, estimate_pose, Dictionary, PoseOptions};
use sketchbody::skeleton::{Joints2, Joints3, NUM_JOINTS};
use sketchbody_lab::pose::factor_train::TrainParams;
use sketchbody_lab::pose::learn::{body_model_skeletons, held_out_of, motion_files, retarget_frames, retarget_of};
use sketchbody_lab::pose::metrics::{mpjpe, pa_mpjpe};

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab bench-pose`.
#[derive(clap::Args)]
pub struct Args {
    /// Folder of motion tables holding the held-out clips (../shared/data/mocap/deepmimic).
    #[arg(long)]
    mocap: PathBuf,
    /// Dictionary file (default: the embedded one).
    #[arg(long)]
    dictionary: Option<PathBuf>,
    /// Clips to measure on (comma-separated; with `--suite` also `SS_*`, a whole CMU subject);
    /// default: the dictionary's held-out clips (with `--suite`, also the library's list).
    #[arg(long, value_delimiter = ',')]
    clips: Option<Vec<String>>,
    /// Frames per clip (evenly spaced).
    #[arg(long, default_value_t = 60)]
    frames: usize,
    /// Seed of the cameras and the noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Noise levels σ in pixels (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "0,2,5")]
    sigma: Vec<f64>,
    /// Override κ of configuration (d).
    #[arg(long)]
    kappa: Option<f64>,
    /// Override α of configuration (d).
    #[arg(long)]
    alpha: Option<f64>,
    /// Override what α pulls toward in configuration (d) (level or identity).
    #[arg(long)]
    alpha_target: Option<String>,
    /// Independent sx and sy in configuration (d).
    #[arg(long)]
    free_scales: bool,
    /// Override max bases of configuration (d).
    #[arg(long)]
    max_bases: Option<usize>,
    /// Override the tolerance (px) of configuration (d).
    #[arg(long)]
    tolerance: Option<f64>,
    /// Override the weight prior (m) of configuration (d).
    #[arg(long)]
    prior: Option<f64>,
    /// Override the nearest-neighbour starts of configuration (d).
    #[arg(long)]
    starts: Option<usize>,
    /// Override the limb candidates of configuration (d).
    #[arg(long)]
    limb_candidates: Option<usize>,
    /// Override the blend temperature (px² per joint) of configuration (d).
    #[arg(long)]
    blend: Option<f64>,
    /// Override the free-joint refinement's 2-D joint noise (m; 0 = off) of configuration (d).
    #[arg(long)]
    joint_noise: Option<f64>,
    /// Keep the dictionary's proportions in configuration (d) (no factor estimate).
    #[arg(long)]
    fixed_proportions: bool,
    /// Switch off the standing prior in configuration (d).
    #[arg(long)]
    no_standing_prior: bool,
    /// Switch off the knee limits in configuration (d).
    #[arg(long)]
    no_knee_limits: bool,
    /// The fixed factor prior instead of the learned one in configuration (d).
    #[arg(long)]
    no_factor_prior: bool,
    /// Weight of the learned joints' depths in configuration (d) (default: the library's; 0 =
    /// off).
    #[arg(long)]
    depth_prior: Option<f64>,
    /// Spread (m) of the free-joint step's pull toward the learned depths in configuration (d)
    /// (default: the library's; 0 = off).
    #[arg(long)]
    learned_depth_sd: Option<f64>,
    /// Relative spread of each bone's length in the free-joint step in configuration (d)
    /// (default: the library's; 0 = lengths kept).
    #[arg(long)]
    bone_length_sd: Option<f64>,
    /// Spread (m) of the free-joint step's pull of the limb joints' depths in configuration (d)
    /// (default: the library's; 0 = that of the other joints).
    #[arg(long)]
    limb_depth_sd: Option<f64>,
    /// Weight of the learned bend prior in configuration (d) (default: the library's; 0 = off).
    #[arg(long)]
    bend_prior: Option<f64>,
    /// Straight limbs on (`on`) or off (`off`) in configuration (d) (default: the library's).
    #[arg(long)]
    straight_limbs: Option<String>,
    /// With `--suite`: this learned prior file (factors and depths) instead of the embedded one
    /// (e.g. one trained without a validation split; `train-factor-prior`).
    #[arg(long)]
    factor_prior: Option<PathBuf>,
    /// Run configuration (d) only.
    #[arg(long)]
    only_default: bool,
    /// Measure on a synthetic-sketch dataset's ground-truth 2-D joints instead (make-dataset
    /// output; configuration (d) only; `--mocap` resolves each sample's source frame).
    #[arg(long)]
    dataset: Option<PathBuf>,
    /// Ground truth in the clips' own joint convention even when the dictionary was learned
    /// retargeted onto the body model's skeletons (by default the held-out frames are
    /// retargeted the same way as the dictionary's training frames).
    #[arg(long)]
    source_skeleton: bool,
    /// The held-out suite instead (held-out DeepMimic clips and, with `--cmu`, held-out CMU
    /// subjects; standard and stylised proportions; near-frontal and side views; each `--sigma`;
    /// configuration (d) only; `bench_pose_suite`).
    #[arg(long)]
    suite: bool,
    /// With `--suite`: the CMU folder (../shared/data/mocap/cmu).
    #[arg(long)]
    cmu: Option<PathBuf>,
    /// With `--suite`: the `cmu_more` folder (../shared/data/mocap/cmu_more), measured per
    /// action category (actions the shipped models never saw).
    #[arg(long)]
    cmu_more: Option<PathBuf>,
    /// With `--suite`: cases per set (evenly spaced over its held-out frames).
    #[arg(long, default_value_t = 360)]
    cases: usize,
    /// With `--suite` and `--cmu-more`: leave-one-category-out validation instead
    /// (`bench_pose_loco`): per action category, the dictionary and the learned priors are
    /// retrained without it (on DeepMimic, CMU and the other categories) and it is scored.
    #[arg(long)]
    loco: bool,
    /// With `--loco`: only these categories (comma-separated names; default: all eight).
    #[arg(long, value_delimiter = ',')]
    loco_categories: Vec<String>,
    /// With `--loco`: projected samples each fold's learned priors train on.
    #[arg(long, default_value_t = TrainParams::default().samples)]
    loco_samples: usize,
    /// With `--loco`: training passes of each fold's learned priors.
    #[arg(long, default_value_t = TrainParams::default().epochs)]
    loco_epochs: usize,
    /// With `--dataset`: only the first N samples.
    #[arg(long)]
    first: Option<usize>,
    /// With `--suite`: write one CSV line per case (set, proportions, view, σ, case, whether
    /// the 2-D joints look standing, the eight limb errors, the estimated and true factors).
    #[arg(long)]
    dump: Option<PathBuf>,
}

/// CPU time of the calling thread, seconds (CLOCK_THREAD_CPUTIME_ID).
pub(crate) fn thread_cpu_s() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `ts` is a valid, writable timespec for the duration of the call.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + 1e-9 * ts.tv_nsec as f64
}

struct Sample {
    gt: Joints3,
    cam: WeakPerspective,
    noise: [[f64; 2]; NUM_JOINTS],
}

fn load(a: &Args, dict: &Dictionary) -> Result<(Vec<String>, Vec<Sample>, &'static str), CliError> {
    // Whole-subject entries (`06_*`) name CMU clips, measured by `--suite`.
    let clips: Vec<String> =
        a.clips.clone().unwrap_or_else(|| held_out_of(dict).into_iter().filter(|c| !c.ends_with('*')).collect());
    if clips.is_empty() {
        return Err(CliError("bench-pose: no clips (the dictionary records none held out; give --clips)".into()));
    }
    let files = motion_files(&a.mocap)?;
    let skeletons = if a.source_skeleton || retarget_of(dict).is_empty() {
        Vec::new()
    } else {
        body_model_skeletons(&BodyModel::embedded()?)
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(a.seed);
    let normal = Normal::new(0.0, 1.0).map_err(|e| CliError(e.to_string()))?;
    let scale = 500.0 / REF_STATURE;
    let mut samples = Vec::new();
    for name in &clips {
        let f = files
            .iter()
            .find(|f| f.file_stem().is_some_and(|s| s.to_string_lossy() == name.as_str()))
            .ok_or_else(|| CliError(format!("bench-pose: clip {name} not found in {}", a.mocap.display())))?;
        let frames: Vec<Joints3> =
            retarget_frames(name, read_motion_csv(f)?, &skeletons)?.iter().filter_map(normalize_pose).collect();
        let n = a.frames.min(frames.len()).max(1);
        for i in 0..n {
            let gt = frames[i * frames.len() / n];
            let yaw = rng.random_range(-30.0f64..=30.0).to_radians();
            let pitch = rng.random_range(-10.0f64..=10.0).to_radians();
            let r: Matrix3<f64> = *(Rotation3::from_axis_angle(&Vector3::x_axis(), pitch)
                * Rotation3::from_axis_angle(&Vector3::y_axis(), yaw))
            .matrix();
            let cam = WeakPerspective { sx: scale, sy: scale, r, t: [256.0, 300.0] };
            let noise = std::array::from_fn(|_| [normal.sample(&mut rng), normal.sample(&mut rng)]);
            samples.push(Sample { gt, cam, noise });
        }
    }
    Ok((
        clips,
        samples,
        if skeletons.is_empty() { "the clips' own" } else { "body model (female/male mean, alternating frames)" },
    ))
}

/// Camera rotation errors in degrees: the geodesic angle of `r_est · r_gtᵀ`, and the tilt — the
/// angle between the images of the model's up axis (+Y) under both rotations (insensitive to a
/// turn about the body's vertical, i.e. to how the two model frames define the heading).
pub(crate) fn rotation_errors(r_est: &Matrix3<f64>, r_gt: &Matrix3<f64>) -> (f64, f64) {
    let d = r_est * r_gt.transpose();
    let geo = ((d.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
    let (ue, ug) = (r_est.column(1).into_owned(), r_gt.column(1).into_owned());
    let tilt = (ue.dot(&ug) / (ue.norm() * ug.norm())).clamp(-1.0, 1.0).acos().to_degrees();
    (geo, tilt)
}

/// Mean and 95th percentile (nearest rank) of `v` (sorted in place); NaN when empty.
pub(crate) fn mean_p95(v: &mut [f64]) -> (f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    v.sort_by(f64::total_cmp);
    (v.iter().sum::<f64>() / v.len() as f64, v[((v.len() as f64 * 0.95).ceil() as usize).clamp(1, v.len()) - 1])
}

fn in_camera(x: &Joints3, r: &Matrix3<f64>) -> Joints3 {
    std::array::from_fn(|j| {
        let p = r * Vector3::new(x[j][0], x[j][1], x[j][2]);
        [p.x, p.y, p.z]
    })
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let dict = match &a.dictionary {
        Some(p) => dict_io::read(p)?,
        None => dict_io::embedded()?,
    };
    let def = PoseOptions::default();
    let ours = PoseOptions {
        kappa: a.kappa.unwrap_or(def.kappa),
        alpha: a.alpha.unwrap_or(def.alpha),
        alpha_target: a.alpha_target.as_deref().map(RotationTarget::parse).transpose()?.unwrap_or(def.alpha_target),
        equal_scales: def.equal_scales && !a.free_scales,
        max_bases: a.max_bases.unwrap_or(def.max_bases),
        tolerance: a.tolerance.unwrap_or(def.tolerance),
        prior: a.prior.unwrap_or(def.prior),
        starts: a.starts.unwrap_or(def.starts),
        limb_candidates: a.limb_candidates.unwrap_or(def.limb_candidates),
        blend: a.blend.unwrap_or(def.blend),
        joint_noise: a.joint_noise.unwrap_or(def.joint_noise),
        proportions: def.proportions && !a.fixed_proportions,
        standing_prior: def.standing_prior && !a.no_standing_prior,
        knee_limits: def.knee_limits && !a.no_knee_limits,
        factor_prior: def.factor_prior && !a.no_factor_prior,
        depth_prior: a.depth_prior.unwrap_or(def.depth_prior),
        learned_depth_sd: a.learned_depth_sd.unwrap_or(def.learned_depth_sd),
        bone_length_sd: a.bone_length_sd.unwrap_or(def.bone_length_sd),
        limb_depth_sd: a.limb_depth_sd.unwrap_or(def.limb_depth_sd),
        bend_prior: a.bend_prior.unwrap_or(def.bend_prior),
        straight_limbs: match a.straight_limbs.as_deref() {
            None => def.straight_limbs,
            Some("on") => true,
            Some("off") => false,
            Some(o) => return Err(CliError(format!("--straight-limbs {o:?}: expected on or off"))),
        },
        ..def
    };
    if a.suite {
        let suite = crate::bench_pose_suite::Suite {
            mocap: &a.mocap,
            cmu: a.cmu.as_ref(),
            cmu_more: a.cmu_more.as_ref(),
            clips: a.clips.as_deref(),
            cases: a.cases,
            sigmas: &a.sigma,
            seed: a.seed,
            dump: a.dump.as_deref(),
            factor_prior: a.factor_prior.as_deref().map(FactorPrior::read).transpose()?,
        };
        if a.loco {
            let train = TrainParams { samples: a.loco_samples, epochs: a.loco_epochs, ..TrainParams::default() };
            return crate::bench_pose_loco::run(&ours, &suite, &a.loco_categories, &train);
        }
        return crate::bench_pose_suite::run(&dict, &ours, &suite);
    }
    if let Some(ds) = &a.dataset {
        return crate::bench_pose_dataset::run(ds, &a.mocap, &dict, &ours, a.first);
    }
    let (clips, samples, convention) = load(&a, &dict)?;
    let paper_kappa = kappa_from_paper(PAPER_KAPPA, dict.sum_sq_lengths());
    // (a)–(c): the paper's pursuit from the mean pose (≤ 10 bases, 0.5 px), no prior, no
    // exemplar starts, α toward the identity, independent sx and sy — spelled out so that changes of the library default do not move them.
    let paper = PoseOptions {
        kappa: paper_kappa,
        alpha: PAPER_ALPHA,
        alpha_target: RotationTarget::Identity,
        equal_scales: false,
        max_bases: 10,
        tolerance: 0.5,
        refine: true,
        prior: 0.0,
        starts: 0,
        limb_candidates: 0,
        blend: 0.0,
        joint_noise: 0.0,
        proportions: false,
        standing_prior: false,
        knee_limits: false,
        factor_prior: false,
        depth_prior: 0.0,
        learned_depth_sd: 0.0,
        bone_length_sd: 0.0,
        limb_depth_sd: 0.0,
        bend_prior: 0.0,
        straight_limbs: false,
    };
    let configs = [
        ("(a) mean pose, camera fitted", PoseOptions { max_bases: 0, alpha: 0.0, refine: false, ..paper }),
        ("(b) kappa=0 (equality), alpha=0", PoseOptions { kappa: 0.0, alpha: 0.0, ..paper }),
        ("(c) paper: kappa=8 CMU, alpha=0.8", PoseOptions { kappa: paper_kappa, alpha: PAPER_ALPHA, ..paper }),
        ("(d) default", ours),
    ];
    println!(
        "bench-pose: {} bases in {} actions, {} exemplars; clips {}; {} poses; seed {}",
        dict.num_bases(),
        dict.actions.len(),
        dict.exemplars.ncols(),
        clips.join(","),
        samples.len(),
        a.seed
    );
    println!("ground-truth joint convention: {convention} skeleton");
    println!("cameras yaw U(-30,30) deg, pitch U(-10,10) deg, figure 500 px tall; errors in mm for a 1.75 m person");
    println!("paper kappa=8 (CMU units^2) -> relative kappa {paper_kappa:.5}; default {:?}", ours);
    println!(
        "{:<36} {:>6} {:>10} {:>10} {:>8} {:>9} {:>9} {:>8} {:>8} {:>8} {:>8} {:>6} {:>8}",
        "config",
        "sigma",
        "MPJPE",
        "PA-MPJPE",
        "failed",
        "ms/pose",
        "cpu ms",
        "bases",
        "rms px",
        "rot deg",
        "rot p95",
        "tilt",
        "tilt p95"
    );
    let skip = if a.only_default { 3 } else { 0 };
    for (name, opts) in configs.iter().skip(skip) {
        for &sigma in &a.sigma {
            let (mut e1, mut e2, mut n, mut failed, mut nb, mut rms) = (0.0, 0.0, 0usize, 0usize, 0usize, 0.0);
            let (mut rots, mut tilts) = (Vec::new(), Vec::new());
            let t0 = Instant::now();
            let c0 = thread_cpu_s();
            for s in &samples {
                let mut j2 = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
                for p in 0..NUM_JOINTS {
                    let q = s.cam.project(&Vector3::new(s.gt[p][0], s.gt[p][1], s.gt[p][2]));
                    j2.xy[p] = [q[0] + sigma * s.noise[p][0], q[1] + sigma * s.noise[p][1]];
                }
                match estimate_pose(&dict, &j2, opts) {
                    Ok(est) => {
                        e1 += mpjpe(&in_camera(&est.joints, &est.camera.r), &in_camera(&s.gt, &s.cam.r));
                        e2 += pa_mpjpe(&est.joints, &s.gt);
                        nb += est.bases.len();
                        rms += est.rms;
                        let (re, te) = rotation_errors(&est.camera.r, &s.cam.r);
                        rots.push(re);
                        tilts.push(te);
                        n += 1;
                    }
                    Err(_) => failed += 1,
                }
            }
            let ms = t0.elapsed().as_secs_f64() * 1e3 / samples.len() as f64;
            let cpu_ms = (thread_cpu_s() - c0) * 1e3 / samples.len() as f64;
            let d = n.max(1) as f64;
            let ((rm, rp), (tm, tp)) = (mean_p95(&mut rots), mean_p95(&mut tilts));
            println!(
                "{:<36} {:>6.1} {:>10.1} {:>10.1} {:>8} {:>9.3} {:>9.3} {:>8.2} {:>8.2} {:>8.1} {:>8.1} {:>6.1} {:>8.1}",
                name, sigma, 1e3 * e1 / d, 1e3 * e2 / d, failed, ms, cpu_ms, nb as f64 / d, rms / d, rm, rp, tm, tp
            );
        }
    }
    Ok(())
}

//! `sketchbody-lab bench-pose --suite`: the 3-D pose step on held-out real motion (docs/benchmarks.md,
//! "3-D pose"), by set (held-out DeepMimic clips; held-out CMU subjects), proportions (standard:
//! the body model's skeletons; stylised: head ×U(1, 1.8) and each of torso, shoulders, arms, hips
//! and legs ×U(0.75, 1.35), bone directions unchanged), view (near-frontal: yaw U(±30°); side:
//! |yaw| U(60°, 90°); pitch U(±10°) for both) and 2-D noise σ. Scores: PA-MPJPE (mm, after a
//! similarity alignment), limb direction error (upper arm, forearm, thigh, shin after the same
//! alignment: mean degrees and % of limbs > 30° off), torso lean error (pelvis→neck, each pose
//! in its own camera frame, degrees), knee and elbow bend errors (degrees), the extra bend of
//! knees and elbows straight in the truth (bend < 15°: mean estimated − true, degrees), share of
//! estimates flagged implausible, CPU ms per call.
//!
//! With `--cmu-more`, one more set per action category of `../shared/data/mocap/cmu_more`
//! ([`CATEGORIES`]; every clip of it: neither the dictionary nor the learned priors were trained
//! on that folder, so each category is an action they have not seen), and a row over all of them.

use std::io::Write;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use sketchbody::body::BodyModel;
use sketchbody::camera::WeakPerspective;
use sketchbody::pose::factor_prior::FactorPrior;
use sketchbody::pose::figure::{BodyFactors, GROUP_NAMES, NUM_GROUPS};
use sketchbody::pose::motion::{normalize_pose, read_motion_csv, REF_STATURE};
use sketchbody::pose::plausibility::standing_in_image;
use sketchbody::pose::{estimate_pose, estimate_pose_with_factor_prior, Dictionary, PoseOptions};
use sketchbody::skeleton::{Joints2, Joints3, NUM_JOINTS};
use sketchbody_lab::pose::learn::{
    body_model_skeletons, clip_matches, default_held_out, held_out_of, motion_files, retarget_frames,
};
use sketchbody_lab::pose::metrics::{
    hinge_bends_deg, hinge_depth_angles_deg, limb_direction_errors, pa_mpjpe, torso_lean_error_deg, HingeScores,
};

use crate::bench_pose::thread_cpu_s;
use sketchbody_cli::CliError;

/// One held-out set: its name and its normalised frames (body-model skeletons).
pub(crate) struct Set {
    pub(crate) name: String,
    pub(crate) clips: Vec<String>,
    pub(crate) frames: Vec<Joints3>,
    /// One of `--cmu-more`'s action categories (summed into its "all" row).
    pub(crate) category: bool,
}

/// The action categories of `cmu_more` (its README): set name and clip-name prefix.
pub const CATEGORIES: [(&str, &str); 8] = [
    ("referee", "hmp_basketball_signal_"),
    ("traffic", "hmp_directing_traffic_"),
    ("soccer", "hmp_soccer_"),
    ("walks", "hmp_walking_extra_"),
    ("windows", "hmp_washwindow_"),
    ("mj_walk", "131_"),
    ("breakdance", "85_"),
    ("karate", "135_"),
];

/// The clips of `dirs` that `keep` accepts (by file stem), retargeted onto `skeletons` and
/// normalised, `cases` evenly spaced.
pub(crate) fn load_set(
    name: &str,
    dirs: &[PathBuf],
    keep: &dyn Fn(&str) -> bool,
    skeletons: &[(String, Joints3)],
    cases: usize,
) -> Result<Set, CliError> {
    let mut clips = Vec::new();
    let mut all = Vec::new();
    for dir in dirs {
        for f in motion_files(dir)? {
            let stem = f.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            if !keep(&stem) {
                continue;
            }
            all.extend(retarget_frames(&stem, read_motion_csv(&f)?, skeletons)?.iter().filter_map(normalize_pose));
            clips.push(stem);
        }
    }
    if all.is_empty() {
        let d = dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ");
        return Err(CliError(format!("bench-pose --suite: no clips of set {name} in {d}")));
    }
    let n = cases.min(all.len()).max(1);
    let frames = (0..n).map(|i| all[i * all.len() / n]).collect();
    Ok(Set { name: name.to_string(), clips, frames, category: false })
}

/// One set per [`CATEGORIES`] entry from the sub-folders of `root` (`cmu_more`).
fn category_sets(root: &Path, skeletons: &[(String, Joints3)], cases: usize) -> Result<Vec<Set>, CliError> {
    let io = |e: std::io::Error| CliError(format!("bench-pose --cmu-more {}: {e}", root.display()));
    let mut dirs: Vec<PathBuf> =
        std::fs::read_dir(root).map_err(io)?.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.is_dir()).collect();
    dirs.sort();
    CATEGORIES
        .iter()
        .map(|(name, prefix)| {
            let set = load_set(name, &dirs, &|stem: &str| stem.starts_with(prefix), skeletons, cases)?;
            Ok(Set { category: true, ..set })
        })
        .collect()
}

/// Random stylised factors (module doc).
pub(crate) fn stylised<R: Rng>(rng: &mut R) -> BodyFactors {
    let mut k = [1.0; NUM_GROUPS];
    k[0] = rng.random_range(1.0..=1.8);
    for v in k.iter_mut().skip(1) {
        *v = rng.random_range(0.75..=1.35);
    }
    BodyFactors { k }
}

pub(crate) fn camera<R: Rng>(rng: &mut R, side: bool) -> WeakPerspective {
    let yaw = if side {
        let y = rng.random_range(60.0f64..=90.0);
        if rng.random_bool(0.5) {
            y
        } else {
            -y
        }
    } else {
        rng.random_range(-30.0f64..=30.0)
    };
    let pitch = rng.random_range(-10.0f64..=10.0).to_radians();
    let r: Matrix3<f64> = *(Rotation3::from_axis_angle(&Vector3::x_axis(), pitch)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), yaw.to_radians()))
    .matrix();
    let scale = 500.0 / REF_STATURE;
    WeakPerspective { sx: scale, sy: scale, r, t: [256.0, 300.0] }
}

/// Sums over the cases of one row of the table.
#[derive(Clone, Copy, Default)]
pub(crate) struct Scores {
    pa: f64,
    limb: f64,
    over: usize,
    lean: f64,
    hinges: HingeScores,
    n: usize,
    calls: usize,
    failed: usize,
    implausible: usize,
    cpu: f64,
    /// Limb direction error of the best of the alternatives (an oracle), summed like `limb`.
    best_of: f64,
    /// Limb direction error of the alternative with the lowest score.
    lowest: f64,
    /// Alternatives per estimate, summed.
    alts: usize,
}

impl Scores {
    pub(crate) fn merge(&mut self, o: &Scores) {
        self.pa += o.pa;
        self.limb += o.limb;
        self.over += o.over;
        self.lean += o.lean;
        self.hinges.merge(&o.hinges);
        self.n += o.n;
        self.calls += o.calls;
        self.failed += o.failed;
        self.implausible += o.implausible;
        self.cpu += o.cpu;
        self.best_of += o.best_of;
        self.lowest += o.lowest;
        self.alts += o.alts;
    }

    fn print(&self, set: &str, props: &str, view: &str, sigma: f64) {
        let d = self.n.max(1) as f64;
        println!(
            "{:<10} {:<9} {:<7} {:>5.1} {:>8.1} {:>8.2} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>9.1} {:>9.1} {:>6} {:>7.2} {:>8.2} {:>8.2} {:>5.1}",
            set,
            props,
            view,
            sigma,
            1e3 * self.pa / d,
            self.limb / d,
            100.0 * self.over as f64 / (8.0 * d),
            self.lean / d,
            self.hinges.knee_deg(),
            self.hinges.elbow_deg(),
            self.hinges.straight_extra_deg(),
            100.0 * self.implausible as f64 / d,
            self.failed,
            1e3 * self.cpu / self.calls.max(1) as f64,
            self.best_of / d,
            self.lowest / d,
            self.alts as f64 / d
        );
    }
}

/// Mean of one estimate's limb direction errors.
fn sc_limb_of(errs: &[f64; 8]) -> f64 {
    errs.iter().sum::<f64>() / errs.len() as f64
}

fn dump_err(e: std::io::Error) -> CliError {
    CliError(format!("bench-pose --dump: {e}"))
}

/// What the suite measures on.
pub struct Suite<'a> {
    /// The DeepMimic folder.
    pub mocap: &'a Path,
    /// The CMU folder.
    pub cmu: Option<&'a PathBuf>,
    /// The `cmu_more` folder: one set per action category ([`CATEGORIES`]).
    pub cmu_more: Option<&'a PathBuf>,
    /// Clips to measure on (names, or `SS_*` for a CMU subject) instead of the dictionary's
    /// held-out clips and the library's list (a validation split learned without them).
    pub clips: Option<&'a [String]>,
    /// Cases per set.
    pub cases: usize,
    /// Noise levels, px.
    pub sigmas: &'a [f64],
    /// Seed of the cameras, proportions and noise.
    pub seed: u64,
    /// Per-case CSV output.
    pub dump: Option<&'a Path>,
    /// Learned priors (factors and depths) replacing the embedded ones, each used as
    /// `PoseOptions::factor_prior` and `PoseOptions::depth_prior` say.
    pub factor_prior: Option<FactorPrior>,
}

/// The sets of the suite, in their order (the order fixes each set's random stream): the
/// held-out DeepMimic clips, the held-out CMU subjects, one set per `cmu_more` category.
pub(crate) fn suite_sets(dict: &Dictionary, suite: &Suite) -> Result<Vec<Set>, CliError> {
    let entries = match suite.clips {
        Some(c) => c.to_vec(),
        None => {
            let mut e = held_out_of(dict);
            e.extend(default_held_out());
            e
        }
    };
    let skeletons = body_model_skeletons(&BodyModel::embedded()?);
    let held_out = |stem: &str| entries.iter().any(|e| clip_matches(e, stem));
    let mut sets = vec![load_set("deepmimic", &[suite.mocap.to_path_buf()], &held_out, &skeletons, suite.cases)?];
    if let Some(c) = suite.cmu {
        sets.push(load_set("cmu", std::slice::from_ref(c), &held_out, &skeletons, suite.cases)?);
    }
    if let Some(c) = suite.cmu_more {
        sets.extend(category_sets(c, &skeletons, suite.cases)?);
    }
    Ok(sets)
}

/// Prints the table's header line.
pub(crate) fn print_header() {
    println!(
        "{:<10} {:<9} {:<7} {:>5} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>9} {:>9} {:>6} {:>7} {:>8} {:>8} {:>5}",
        "set",
        "props",
        "view",
        "sigma",
        "PA-MPJPE",
        "limb deg",
        "limb>30%",
        "lean deg",
        "knee deg",
        "elbow dg",
        "straight+",
        "implaus %",
        "failed",
        "cpu ms",
        "best-of",
        "lowest",
        "alts"
    );
}

/// The summed scores of the category sets by (proportions, view, σ) index.
pub(crate) type CategoryScores = std::collections::BTreeMap<(usize, usize, usize), Scores>;

/// Prints one row per entry of `scores`, named `name`.
pub(crate) fn print_category_rows(name: &str, scores: &CategoryScores, sigmas: &[f64]) {
    for ((pi, vi, ni), sc) in scores {
        sc.print(name, ["standard", "stylised"][*pi], ["frontal", "side"][*vi], sigmas[*ni]);
    }
}

/// Runs the suite with options `opts` (see [`Suite`]).
pub fn run(dict: &Dictionary, opts: &PoseOptions, suite: &Suite) -> Result<(), CliError> {
    let mut dump = match suite.dump {
        Some(p) => {
            let mut f = std::io::BufWriter::new(std::fs::File::create(p).map_err(dump_err)?);
            writeln!(
                f,
                "set,props,view,sigma,case,standing_2d,{},{},{},{},{},{}",
                (0..8).map(|i| format!("limb{i}")).collect::<Vec<_>>().join(","),
                GROUP_NAMES.map(|g| format!("est_{g}")).join(","),
                GROUP_NAMES.map(|g| format!("true_{g}")).join(","),
                (0..4).map(|i| format!("est_bend{i}")).collect::<Vec<_>>().join(","),
                (0..4).map(|i| format!("true_bend{i}")).collect::<Vec<_>>().join(","),
                (0..4).map(|i| format!("true_depth_deg{i}")).collect::<Vec<_>>().join(",")
            )
            .map_err(dump_err)?;
            Some(f)
        }
        None => None,
    };
    let sets = suite_sets(dict, suite)?;
    println!(
        "bench-pose --suite: {} bases in {} actions, {} exemplars; seed {}; options {opts:?}",
        dict.num_bases(),
        dict.actions.len(),
        dict.exemplars.ncols(),
        suite.seed
    );
    for s in &sets {
        println!("set {}: {} cases from {} clips ({})", s.name, s.frames.len(), s.clips.len(), s.clips.join(","));
    }
    print_header();
    let indexed: Vec<(usize, &Set)> = sets.iter().enumerate().collect();
    let all_categories = score_sets(
        dict,
        opts,
        &indexed,
        suite,
        suite.factor_prior.as_ref(),
        dump.as_mut().map(|d| d as &mut dyn Write),
    )?;
    print_category_rows("categories", &all_categories, suite.sigmas);
    if let Some(mut out) = dump {
        out.flush().map_err(dump_err)?;
    }
    Ok(())
}

/// Scores each (index, set) of `sets` (the index fixes the set's random stream, as in
/// [`suite_sets`]'s order) with `dict` and the learned priors `prior` (`None`: the embedded
/// ones), printing one row per set, proportions, view and σ; returns the category sets' sums.
pub(crate) fn score_sets(
    dict: &Dictionary,
    opts: &PoseOptions,
    sets: &[(usize, &Set)],
    suite: &Suite,
    prior: Option<&FactorPrior>,
    mut dump: Option<&mut dyn Write>,
) -> Result<CategoryScores, CliError> {
    let (sigmas, seed) = (suite.sigmas, suite.seed);
    let normal = Normal::new(0.0, 1.0).map_err(|e| CliError(e.to_string()))?;
    let mut all_categories = CategoryScores::new();
    for &(si, set) in sets {
        for (pi, props) in ["standard", "stylised"].iter().enumerate() {
            for (vi, view) in ["frontal", "side"].iter().enumerate() {
                // One stream per (set, proportions, view): the same cases for every sigma.
                let stream = seed.wrapping_mul(1000).wrapping_add((100 * si + 10 * pi + vi) as u64);
                for (ni, &sigma) in sigmas.iter().enumerate() {
                    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(stream);
                    let mut sc = Scores::default();
                    for (case, f) in set.frames.iter().enumerate() {
                        let factors = stylised(&mut rng);
                        let gt = if pi == 1 { factors.apply(f) } else { *f };
                        let cam = camera(&mut rng, vi == 1);
                        let mut j2 = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
                        for p in 0..NUM_JOINTS {
                            let q = cam.project(&Vector3::from(gt[p]));
                            let (a, b) = (normal.sample(&mut rng), normal.sample(&mut rng));
                            j2.xy[p] = [q[0] + sigma * a, q[1] + sigma * b];
                        }
                        let c0 = thread_cpu_s();
                        let res = match prior {
                            Some(p) => estimate_pose_with_factor_prior(dict, &j2, opts, None, Some(p)),
                            None => estimate_pose(dict, &j2, opts),
                        };
                        sc.cpu += thread_cpu_s() - c0;
                        sc.calls += 1;
                        let Ok(est) = res else {
                            sc.failed += 1;
                            continue;
                        };
                        let Some(errs) = limb_direction_errors(&est.joints, &gt) else {
                            sc.failed += 1;
                            continue;
                        };
                        if let Some(out) = dump.as_deref_mut() {
                            let truth = if pi == 1 { factors } else { BodyFactors::default() };
                            let vis = [true; NUM_JOINTS];
                            writeln!(
                                out,
                                "{},{props},{view},{sigma},{case},{},{},{},{},{},{},{}",
                                set.name,
                                u8::from(standing_in_image(&j2.xy, &vis)),
                                errs.iter().map(|e| format!("{e:.2}")).collect::<Vec<_>>().join(","),
                                est.factors.k.map(|k| format!("{k:.3}")).join(","),
                                truth.k.map(|k| format!("{k:.3}")).join(","),
                                hinge_bends_deg(&est.joints).map(|b| format!("{b:.1}")).join(","),
                                hinge_bends_deg(&gt).map(|b| format!("{b:.1}")).join(","),
                                hinge_depth_angles_deg(&gt, &cam.r).map(|b| format!("{b:.1}")).join(",")
                            )
                            .map_err(dump_err)?;
                        }
                        sc.pa += pa_mpjpe(&est.joints, &gt);
                        sc.limb += errs.iter().sum::<f64>() / errs.len() as f64;
                        sc.over += errs.iter().filter(|e| **e > 30.0).count();
                        sc.lean += torso_lean_error_deg(&est.joints, &est.camera.r, &gt, &cam.r);
                        sc.hinges.add(&est.joints, &gt);
                        sc.implausible += usize::from(!est.plausible);
                        // The alternatives: the best one's limb error (an oracle) and the
                        // lowest-scored one's.
                        let mean = |x: &Joints3| {
                            limb_direction_errors(x, &gt).map_or(f64::NAN, |e| e.iter().sum::<f64>() / e.len() as f64)
                        };
                        let alt_errs: Vec<f64> = est.alternatives.iter().map(|a| mean(&a.joints)).collect();
                        let first = sc_limb_of(&errs);
                        sc.best_of += alt_errs.iter().copied().fold(first, f64::min);
                        sc.lowest += est
                            .alternatives
                            .iter()
                            .zip(&alt_errs)
                            .min_by(|a, b| a.0.score.total_cmp(&b.0.score))
                            .map_or(first, |(_, e)| *e);
                        sc.alts += est.alternatives.len();
                        sc.n += 1;
                    }
                    sc.print(&set.name, props, view, sigma);
                    if set.category {
                        all_categories.entry((pi, vi, ni)).or_default().merge(&sc);
                    }
                }
            }
        }
    }
    Ok(all_categories)
}

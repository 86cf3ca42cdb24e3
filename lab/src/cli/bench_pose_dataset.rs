//! `sketchbody-lab bench-pose --dataset DIR`: the pose step alone on a synthetic-sketch dataset's
//! ground-truth 2-D joints (docs/benchmarks.md, "3-D pose", "On the pipeline's sketches").
//! Each sample's `joints2d` (joints outside the image marked missing) go through
//! `estimate_pose`; the estimate is compared with `joints3d` in the camera frame with the
//! metrics of `sketchbody-lab eval` (the estimate scaled about its pelvis to the reference's total
//! bone length; mm of the reference body), and the camera rotation with the true one.
//!
//! Rows: "solver" (the estimate itself); "+ IK mean skeleton" (the gender's mean rest joints
//! posed to the estimate by IK, as the pipeline does before the shape fit); "+ IK true skeleton"
//! (the sample's own proportioned rest joints, i.e. perfect bone lengths); "truth on mean
//! skeleton" (the true pose's bone directions on the mean skeleton: the floor the shape fit
//! starts from); "mocap source" (the normalised mocap frame the sample was retargeted from, in
//! the true camera: how far the dictionary's joint convention is from the rig's for a perfect
//! pose). Groups: all samples, standard proportions, non-standard proportions.

use std::path::Path;

use nalgebra::{Matrix3, Vector3};
use sketchbody::body::ik::{self, IkOptions};
use sketchbody::body::{BodyModel, Gender};
use sketchbody::pose::motion::{normalize_pose, read_motion_csv};
use sketchbody::pose::{estimate_pose, Dictionary, PoseOptions};
use sketchbody::render::sketch::truth::GroundTruth;
use sketchbody::render::sketch::Proportions;
use sketchbody::skeleton::{joint, Joints2, Joints3, BONES, NUM_JOINTS};
use sketchbody_lab::eval::metrics::{mpjpe, pa_mpjpe, scale_to_reference};
use sketchbody_lab::eval::score::dataset_samples;

use crate::bench_pose::{mean_p95, rotation_errors};
use sketchbody_cli::CliError;

const ROWS: [&str; 5] =
    ["solver", "+ IK mean skeleton", "+ IK true skeleton", "truth on mean skeleton", "mocap source"];

/// Sums of one row over a group of samples.
#[derive(Default, Clone)]
struct Acc {
    n: usize,
    mpjpe: f64,
    pa: f64,
    rot: Vec<f64>,
    tilt: Vec<f64>,
}

impl Acc {
    fn add(&mut self, m: f64, p: f64, rot: f64, tilt: f64) {
        self.n += 1;
        self.mpjpe += m;
        self.pa += p;
        self.rot.push(rot);
        self.tilt.push(tilt);
    }
}

fn rot(r: &Matrix3<f64>, x: &[[f64; 3]]) -> Vec<[f64; 3]> {
    x.iter().map(|p| (r * Vector3::from(*p)).into()).collect()
}

fn joints3(v: &[[f64; 3]], what: &str) -> Result<Joints3, CliError> {
    v.try_into().map_err(|_| CliError(format!("{what}: {} joints, expected {NUM_JOINTS}", v.len())))
}

/// Camera-frame errors (mm of the reference body) of `est` seen by `r_est` against the truth.
fn errors(
    truth: &GroundTruth,
    r_gt: &Matrix3<f64>,
    est: &Joints3,
    r_est: &Matrix3<f64>,
) -> Result<(f64, f64), CliError> {
    let a = rot(r_gt, &truth.joints3d);
    let b = scale_to_reference(&a, &rot(r_est, est), &BONES, joint::PELVIS)?;
    Ok((1000.0 * mpjpe(&a, &b, joint::PELVIS)?, 1000.0 * pa_mpjpe(&a, &b)?))
}

/// The normalised mocap frame named by `pose_source` (`mocap:CLIP:FRAME`), if any.
fn mocap_source(mocap: &Path, src: &str, cache: &mut Vec<(String, Vec<Joints3>)>) -> Result<Option<Joints3>, CliError> {
    let mut it = src.split(':');
    let (Some("mocap"), Some(clip), Some(frame)) = (it.next(), it.next(), it.next()) else { return Ok(None) };
    let frame: usize = frame.parse().map_err(|_| CliError(format!("pose_source {src}: bad frame")))?;
    if !cache.iter().any(|(c, _)| c == clip) {
        cache.push((clip.to_string(), read_motion_csv(&mocap.join(format!("{clip}.csv")))?));
    }
    let frames =
        &cache.iter().find(|(c, _)| c == clip).map(|(_, f)| f).ok_or_else(|| CliError("unreachable".into()))?;
    Ok(frames.get(frame).and_then(normalize_pose))
}

/// Runs the dataset mode of bench-pose with the solver options `opts`.
pub fn run(
    dataset: &Path,
    mocap: &Path,
    dict: &Dictionary,
    opts: &PoseOptions,
    first: Option<usize>,
) -> Result<(), CliError> {
    let model = BodyModel::embedded()?;
    let mut stems = dataset_samples(dataset)?;
    stems.truncate(first.unwrap_or(usize::MAX));
    if stems.is_empty() {
        return Err(CliError(format!("{}: no samples", dataset.display())));
    }
    // [group][row]; groups: all, standard proportions, non-standard.
    let mut acc = vec![vec![Acc::default(); ROWS.len()]; 3];
    let (mut failed, mut cpu) = (0usize, 0.0);
    let mut cache = Vec::new();
    for stem in &stems {
        let jp = dataset.join(format!("{stem}.json"));
        let text = std::fs::read_to_string(&jp).map_err(|e| CliError(format!("{}: {e}", jp.display())))?;
        let truth = GroundTruth::from_json(&text, &jp.display().to_string())?;
        let r_gt = truth.camera.to_camera()?.r;
        let mut j2 = Joints2 { xy: [[0.0; 2]; NUM_JOINTS], visible: [true; NUM_JOINTS] };
        for k in 0..NUM_JOINTS {
            j2.xy[k] = truth.joints2d[k];
            let [x, y] = j2.xy[k];
            j2.visible[k] = (0.0..=truth.width as f64).contains(&x) && (0.0..=truth.height as f64).contains(&y);
        }
        let group = if truth.style.proportions == Proportions::default() { 1 } else { 2 };
        let c0 = crate::bench_pose::thread_cpu_s();
        let est = estimate_pose(dict, &j2, opts);
        cpu += crate::bench_pose::thread_cpu_s() - c0;
        let Ok(est) = est else {
            failed += 1;
            continue;
        };
        let gender = Gender::parse(&truth.gender)?;
        let mean = model.space(gender).mean_joints();
        let own = joints3(&truth.rest_joints3d, "rest_joints3d")?;
        let gt = joints3(&truth.joints3d, "joints3d")?;
        let r_est = est.camera.r;
        let (re, te) = rotation_errors(&r_est, &r_gt);
        let no = IkOptions { retarget: false };
        let mut rows: Vec<(Joints3, Matrix3<f64>, f64, f64)> = vec![
            (est.joints, r_est, re, te),
            (ik::solve(mean, &est.joints, &no)?.joints, r_est, re, te),
            (ik::solve(&own, &est.joints, &no)?.joints, r_est, re, te),
            (ik::solve(mean, &gt, &no)?.joints, r_gt, 0.0, 0.0),
        ];
        if let Some(src) = mocap_source(mocap, &truth.pose_source, &mut cache)? {
            rows.push((src, r_gt, 0.0, 0.0));
        }
        for (k, (x, r, re, te)) in rows.iter().enumerate() {
            let (m, p) = errors(&truth, &r_gt, x, r)?;
            for g in [0, group] {
                acc[g][k].add(m, p, *re, *te);
            }
        }
    }
    println!(
        "bench-pose --dataset {}: {} samples ({} standard proportions, {} non-standard), {} failed; solver {:.3} ms CPU per pose",
        dataset.display(),
        stems.len(),
        acc[1][0].n,
        acc[2][0].n,
        failed,
        1e3 * cpu / stems.len() as f64
    );
    println!("options {opts:?}");
    println!("errors in mm of the reference body (eval's metrics); rotation: geodesic angle of R_est R_gt^T, tilt: angle between R_est y and R_gt y (deg)");
    println!(
        "{:<14} {:<24} {:>5} {:>8} {:>9} {:>9} {:>8} {:>9} {:>8}",
        "group", "row", "n", "MPJPE", "PA-MPJPE", "rot mean", "rot p95", "tilt mean", "tilt p95"
    );
    for (g, name) in ["all", "standard", "non-standard"].iter().enumerate() {
        for (k, row) in ROWS.iter().enumerate() {
            let a = &acc[g][k];
            if a.n == 0 {
                continue;
            }
            let d = a.n as f64;
            let ((rm, rp), (tm, tp)) = (mean_p95(&mut a.rot.clone()), mean_p95(&mut a.tilt.clone()));
            println!(
                "{:<14} {:<24} {:>5} {:>8.1} {:>9.1} {:>9.1} {:>8.1} {:>9.1} {:>8.1}",
                name,
                row,
                a.n,
                a.mpjpe / d,
                a.pa / d,
                rm,
                rp,
                tm,
                tp
            );
        }
    }
    Ok(())
}

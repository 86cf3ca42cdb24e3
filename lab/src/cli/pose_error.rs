//! `sketchbody-lab pose-error DATASET RESULTS`: the 3-D pose step's error on a results folder of
//! `run-dataset`: for every sample whose STEM.json holds `pose_joints3d` (the pose the fit was
//! posed to), the mean limb direction error (degrees, after the similarity alignment onto the
//! true `joints3d`: [`limb_direction_errors`]) and PA-MPJPE (millimetres of the true body), then
//! the means over the samples and the share of limbs more than 30° off.

use std::path::PathBuf;

use sketchbody::render::sketch::truth::GroundTruth;
use sketchbody::skeleton::{Joints3, NUM_JOINTS};
use sketchbody_lab::eval::score::dataset_samples;
use sketchbody_lab::pose::metrics::{limb_direction_errors, pa_mpjpe};

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab pose-error`.
#[derive(clap::Args)]
pub struct Args {
    /// Dataset folder (the ground truth).
    dataset: PathBuf,
    /// Results folder of run-dataset.
    results: PathBuf,
}

/// `key` of a results JSON as 15 joints; `None` when absent.
fn joints_of(v: &serde_json::Value, key: &str, what: &str) -> Result<Option<Joints3>, CliError> {
    let Some(x) = v.get(key) else { return Ok(None) };
    let list: Vec<[f64; 3]> = serde_json::from_value(x.clone()).map_err(|e| CliError(format!("{what}: {key}: {e}")))?;
    let joints: Joints3 =
        list.try_into().map_err(|_| CliError(format!("{what}: {key} must hold {NUM_JOINTS} joints")))?;
    Ok(Some(joints))
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let (mut limb, mut pa, mut over, mut limbs, mut n) = (0.0, 0.0, 0usize, 0usize, 0usize);
    for stem in dataset_samples(&a.dataset)? {
        let rp = a.results.join(format!("{stem}.json"));
        if !rp.is_file() {
            continue;
        }
        let text = std::fs::read_to_string(&rp).map_err(|e| CliError(format!("{}: {e}", rp.display())))?;
        let v: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| CliError(format!("{}: {e}", rp.display())))?;
        let Some(est) = joints_of(&v, "pose_joints3d", &rp.display().to_string())? else { continue };
        let tp = a.dataset.join(format!("{stem}.json"));
        let truth_text = std::fs::read_to_string(&tp).map_err(|e| CliError(format!("{}: {e}", tp.display())))?;
        let truth = GroundTruth::from_json(&truth_text, &tp.display().to_string())?;
        let gt: Joints3 = truth
            .joints3d
            .as_slice()
            .try_into()
            .map_err(|_| CliError(format!("{}: joints3d must hold {NUM_JOINTS} joints", tp.display())))?;
        let Some(errs) = limb_direction_errors(&est, &gt) else { continue };
        limb += errs.iter().sum::<f64>() / errs.len() as f64;
        over += errs.iter().filter(|e| **e > 30.0).count();
        limbs += errs.len();
        pa += 1000.0 * pa_mpjpe(&est, &gt) / truth.height_m * 1.75;
        n += 1;
    }
    if n == 0 {
        return Err(CliError(format!("{}: no results with pose_joints3d", a.results.display())));
    }
    println!(
        "{}: {n} samples; limb direction error {:.2}°, limbs > 30° off {:.1}%, PA-MPJPE {:.1} mm (of a 1.75 m body)",
        a.results.display(),
        limb / n as f64,
        100.0 * over as f64 / limbs as f64,
        pa / n as f64
    );
    Ok(())
}

//! `sketchbody calibrate-height --train DS=RESULTS … [--test DS=RESULTS …] [--shipped]`:
//! fits the height calibration (`sketchbody::fit::HeightCalibration`: ln true height against
//! the fitted body's ln height and gender value, least squares) to `run-dataset` results
//! (`fit_height_m` and `gender_value` of each `STEM.json`, the true `height_m` of the dataset's
//! `STEM.json`), prints the Rust constant to ship, and for every set the RMS error of ln height
//! before and after calibration. `--shipped` evaluates the shipped calibration instead.

use std::path::{Path, PathBuf};

use sketchbody::eval::score::dataset_samples;
use sketchbody::fit::HeightCalibration;

use crate::train_gender::Sets;
use crate::CliError;

/// Arguments of `sketchbody calibrate-height`.
#[derive(clap::Args)]
pub struct Args {
    /// The calibration's training and test sets (any gender mode but `--mean-shape`).
    #[command(flatten)]
    sets: Sets,
    /// Report the shipped calibration's error on the --test sets instead of fitting one.
    #[arg(long, conflicts_with = "train")]
    shipped: bool,
    /// Use only the first N samples of each set.
    #[arg(long)]
    first: Option<usize>,
}

/// `(fitted height m, gender value, true height m)` of every sample of `dataset` with a results
/// file.
fn load(dataset: &Path, results: &Path, first: Option<usize>) -> Result<Vec<(f64, f64, f64)>, CliError> {
    let read = |p: PathBuf| -> Result<serde_json::Value, CliError> {
        let text = std::fs::read_to_string(&p).map_err(|e| CliError(format!("{}: {e}", p.display())))?;
        serde_json::from_str(&text).map_err(|e| CliError(format!("{}: {e}", p.display())))
    };
    let mut out = Vec::new();
    for stem in dataset_samples(dataset)?.iter().take(first.unwrap_or(usize::MAX)) {
        let rp = results.join(format!("{stem}.json"));
        if !rp.is_file() {
            continue;
        }
        let (truth, r) = (read(dataset.join(format!("{stem}.json")))?, read(rp.clone())?);
        let number = |v: &serde_json::Value, key: &str, p: &Path| {
            v[key].as_f64().ok_or_else(|| CliError(format!("{}: no number {key:?}", p.display())))
        };
        if r["score"].is_null() {
            return Err(CliError(format!("{}: mean-shape results have no fitted height", rp.display())));
        }
        let fit = number(&r, "fit_height_m", &rp)
            .map_err(|e| CliError(format!("{} (run-dataset of this version writes fit_height_m)", e.0)))?;
        out.push((fit, number(&r, "gender_value", &rp)?, number(&truth, "height_m", &dataset.join(stem))?));
    }
    if out.is_empty() {
        return Err(CliError(format!("{}: no results of {}", results.display(), dataset.display())));
    }
    Ok(out)
}

/// RMS of ln(height / true height) before (the fitted heights) and after `c`.
fn rms(c: &HeightCalibration, samples: &[(f64, f64, f64)]) -> Result<(f64, f64), CliError> {
    let (mut before, mut after) = (0.0, 0.0);
    for &(fit, g, truth) in samples {
        before += (fit / truth).ln().powi(2);
        after += (c.calibrated(fit, g).map_err(|e| CliError(e.to_string()))? / truth).ln().powi(2);
    }
    let n = samples.len() as f64;
    Ok(((before / n).sqrt(), (after / n).sqrt()))
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let c = if a.shipped {
        if a.sets.test.is_empty() {
            return Err(CliError("--shipped needs at least one --test DATASET=RESULTS".into()));
        }
        HeightCalibration::SHIPPED
    } else {
        if a.sets.train.is_empty() {
            return Err(CliError("give --train DATASET=RESULTS (or --shipped with --test)".into()));
        }
        let mut samples = Vec::new();
        for (d, r) in &a.sets.train {
            samples.extend(load(d, r, a.first)?);
        }
        let c = HeightCalibration::train(&samples).map_err(|e| CliError(e.to_string()))?;
        let (before, after) = rms(&c, &samples)?;
        println!("training: {} samples, RMS ln height {before:.4} fitted -> {after:.4} calibrated", samples.len());
        println!("HeightCalibration {{ intercept: {:.6}, slope: {:.6}, male: {:.6} }}", c.intercept, c.slope, c.male);
        c
    };
    for (d, r) in &a.sets.test {
        let samples = load(d, r, a.first)?;
        let (before, after) = rms(&c, &samples)?;
        println!(
            "test {}: {} samples, RMS ln height {before:.4} fitted -> {after:.4} calibrated",
            d.display(),
            samples.len()
        );
    }
    Ok(())
}

//! `sketchbody eval DATASET RESULTS [--compare OTHER]`: AED (rest, posed), MPJPE, PA-MPJPE and
//! PCK of a results folder against a synthetic-sketch dataset; a per-sample CSV and a summary
//! table (side by side with `--compare`). Layouts: docs/dataset.md.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use sketchbody::eval::score::{Summary, METRICS, METRIC_DECIMALS};
use sketchbody::eval::{score_dataset, SampleScore};
use sketchbody::fsutil::write_atomic;

use crate::CliError;

/// Arguments of `sketchbody eval`.
#[derive(clap::Args)]
pub struct Args {
    /// Dataset folder (from make-dataset).
    dataset: PathBuf,
    /// Results folder to score.
    results: PathBuf,
    /// A second results folder, shown side by side.
    #[arg(long)]
    compare: Option<PathBuf>,
    /// Per-sample CSV (default: RESULTS/eval.csv).
    #[arg(long)]
    csv: Option<PathBuf>,
}

fn fmt(v: f64, k: usize) -> String {
    if v.is_nan() {
        "-".into()
    } else {
        format!("{v:.*}", METRIC_DECIMALS[k])
    }
}

fn csv_rows(label: &str, scores: &[SampleScore], out: &mut String) {
    for s in scores {
        let vals: Vec<String> = s.values().iter().map(|v| v.map_or(String::new(), |x| format!("{x:.6}"))).collect();
        let _ = writeln!(out, "{},{},{}", s.sample, label, vals.join(","));
    }
}

fn score(dataset: &Path, results: &Path) -> Result<(Vec<SampleScore>, Summary), CliError> {
    let (scores, n) = score_dataset(dataset, results)?;
    let summary = Summary::new(&scores, n);
    Ok((scores, summary))
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let (sa, suma) = score(&a.dataset, &a.results)?;
    let other = a.compare.as_deref().map(|o| score(&a.dataset, o)).transpose()?;
    let mut csv = format!("sample,results,{}\n", METRICS.join(","));
    csv_rows(&a.results.display().to_string(), &sa, &mut csv);
    if let (Some(o), Some((sb, _))) = (&a.compare, &other) {
        csv_rows(&o.display().to_string(), sb, &mut csv);
    }
    let csv_path = a.csv.clone().unwrap_or_else(|| a.results.join("eval.csv"));
    write_atomic(&csv_path, csv.as_bytes())?;
    println!("dataset {}: {} samples; per-sample CSV {}", a.dataset.display(), suma.samples, csv_path.display());
    println!("AED as a fraction of the reference height; MPJPE in mm of the reference body; PCK normaliser: longer side of the GT 2-D joint box");
    match &other {
        None => {
            println!("| metric | {} | n |", a.results.display());
            println!("|---|---:|---:|");
            for (k, m) in METRICS.iter().enumerate() {
                let (v, n) = suma.metrics[k];
                println!("| {m} | {} | {n} |", fmt(v, k));
            }
        }
        Some((_, sumb)) => {
            let b = a.compare.as_ref().map(|p| p.display().to_string()).unwrap_or_default();
            println!("| metric | {} | n | {b} | n | difference (B − A) |", a.results.display());
            println!("|---|---:|---:|---:|---:|---:|");
            for (k, m) in METRICS.iter().enumerate() {
                let ((va, na), (vb, nb)) = (suma.metrics[k], sumb.metrics[k]);
                println!("| {m} | {} | {na} | {} | {nb} | {} |", fmt(va, k), fmt(vb, k), fmt(vb - va, k));
            }
        }
    }
    Ok(())
}

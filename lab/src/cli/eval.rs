//! `sketchbody-lab eval DATASET RESULTS [--compare OTHER]`: AED (rest, posed), MPJPE, PA-MPJPE and
//! PCK of a results folder against a synthetic-sketch dataset; a per-sample CSV and a summary
//! table (side by side with `--compare`). Layouts: docs/dataset.md.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use sketchbody::fsutil::write_atomic;
use sketchbody_lab::eval::by_style::{gender_confusion, shape_by_style, STYLE_METRICS};
use sketchbody_lab::eval::score::{Summary, METRICS, METRIC_DECIMALS};
use sketchbody_lab::eval::{score_dataset, SampleScore};

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab eval`.
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
    /// Also print the rest and posed AED per style group (eval-detector's groups plus the true
    /// genders) and the confusion table of the results' gender against the truth.
    #[arg(long)]
    by_style: bool,
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
    if a.by_style {
        print_by_style(&a, &sa, other.as_ref().map(|(sb, _)| sb.as_slice()))?;
    }
    Ok(())
}

fn print_by_style(a: &Args, sa: &[SampleScore], sb: Option<&[SampleScore]>) -> Result<(), CliError> {
    let ra = shape_by_style(&a.dataset, sa)?;
    let rb = sb.map(|s| shape_by_style(&a.dataset, s)).transpose()?;
    let cols = STYLE_METRICS.join(" | ");
    println!();
    match &rb {
        None => {
            println!("| style group | n | {cols} |");
            println!("|---|---:|---:|---:|---:|---:|");
        }
        Some(_) => {
            println!("| style group | n | A: {cols} | B: {cols} | B/A centred |");
            println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
        }
    }
    for (k, row) in ra.iter().enumerate() {
        let f = |m: &[f64; 4]| {
            m.iter().map(|v| if v.is_nan() { "-".into() } else { format!("{v:.4}") }).collect::<Vec<_>>()
        };
        let mut line = format!("| {} | {} | {}", row.name, row.n, f(&row.means).join(" | "));
        if let Some(rb) = &rb {
            let b = &rb[k];
            let _ = write!(line, " | {} | {:.3}", f(&b.means).join(" | "), b.means[1] / row.means[1]);
        }
        println!("{line} |");
    }
    for (dir, scores) in [(Some(a.results.as_path()), Some(sa)), (a.compare.as_deref(), sb)] {
        let (Some(dir), Some(scores)) = (dir, scores) else { continue };
        if let Some(t) = gender_confusion(&a.dataset, dir, scores)? {
            let right = t[0][0] + t[1][1];
            let total = right + t[0][1] + t[1][0];
            println!(
                "gender of {} (rows true, columns estimated): female -> female {}, female -> male {}, male -> female {}, male -> male {}; {right}/{total} right",
                dir.display(),
                t[0][0],
                t[0][1],
                t[1][0],
                t[1][1]
            );
        }
    }
    Ok(())
}

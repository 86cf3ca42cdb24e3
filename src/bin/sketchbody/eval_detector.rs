//! `sketchbody eval-detector [--model M] [--baseline B]`: PCK@0.1 and @0.2 of detector models on
//! held-out synthetic sketches (`eval::detector`: another seed, a hair style never used in
//! training), with the detection time per image.

use std::path::PathBuf;
use std::time::Instant;

use rayon::prelude::*;
use sketchbody::detect::{DetectOptions, Model};
use sketchbody::eval::detector::{held_out_request, score_sketch, SketchScore};

use crate::render_sketch::{parse_size, renderer};
use crate::train_detector::parse_hair;
use crate::CliError;

/// Arguments of `sketchbody eval-detector`.
#[derive(clap::Args)]
pub struct Args {
    /// Detector model (.skbd or PARSE JSON); the embedded model when omitted.
    #[arg(long)]
    model: Option<PathBuf>,
    /// Further models to compare (e.g. ../shared/data/fmp/parse_model.json).
    #[arg(long)]
    baseline: Vec<PathBuf>,
    /// Number of held-out sketches.
    #[arg(long, default_value_t = 300)]
    n: usize,
    /// Seed of the held-out set (training uses 1 by default).
    #[arg(long, default_value_t = 2)]
    seed: u64,
    /// Image size: N or WxH.
    #[arg(long, default_value = "512")]
    size: String,
    /// Hair style forced on every sketch (none, short, long, spiky, bun, ponytail; keep = random).
    #[arg(long, default_value = "ponytail")]
    hair: String,
    /// Smallest pyramid cell searched, px (0 = all).
    #[arg(long, default_value_t = 0.0)]
    min_cell: f64,
    /// Largest pyramid cell searched, px.
    #[arg(long, default_value_t = f64::INFINITY)]
    max_cell: f64,
    /// Folder of mocap clips (default as in render-sketch).
    #[arg(long)]
    mocap: Option<PathBuf>,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let (w, _) = parse_size(&a.size)?;
    let hair = parse_hair(&a.hair)?;
    if a.n == 0 {
        return Err(CliError("--n must be ≥ 1".into()));
    }
    let mut names = vec![a.model.as_ref().map_or("embedded".to_string(), |p| p.display().to_string())];
    let mut models = vec![match &a.model {
        Some(p) => Model::load_any(p)?,
        None => Model::embedded()?,
    }];
    for b in &a.baseline {
        models.push(Model::load_any(b)?);
        names.push(b.display().to_string());
    }
    let r = renderer(a.mocap.as_deref())?;
    let options = DetectOptions { threshold: Some(-1e9), min_cell_px: a.min_cell, max_cell_px: a.max_cell, ..DetectOptions::default() };
    let alphas = [0.1, 0.2];
    let refs: Vec<&Model> = models.iter().collect();
    let t0 = Instant::now();
    let per: Vec<Vec<SketchScore>> = (0..a.n as u64)
        .into_par_iter()
        .map(|i| score_sketch(&r, &held_out_request(a.seed, i, w, hair), &refs, &options, &alphas))
        .collect::<Result<_, _>>()?;
    let el = t0.elapsed().as_secs_f64();
    println!(
        "held-out sketches: {} of seed {}, {w}x{w}, hair {}, cells {}..{} px; {:.1} s for all models",
        a.n, a.seed, a.hair, a.min_cell, a.max_cell, el
    );
    for (k, name) in names.iter().enumerate() {
        let mean = |j: usize| per.iter().map(|s| s[k].pck[j]).sum::<f64>() / per.len() as f64;
        let ms = 1e3 * per.iter().map(|s| s[k].seconds).sum::<f64>() / per.len() as f64;
        println!("{name}: PCK@0.1 {:.3}  PCK@0.2 {:.3}  mean detect {ms:.0} ms (wall, {} threads shared by the evaluation)", mean(0), mean(1), rayon::current_num_threads());
    }
    Ok(())
}

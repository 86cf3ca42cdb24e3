//! `sketchbody-lab eval-detector [--model M] [--baseline B]`: PCK@0.1 and @0.2 of detector models on
//! held-out synthetic sketches (`eval::detector`: another seed, a hair style never used in
//! training), with the detection time per image.

use std::path::PathBuf;
use std::time::Instant;

use rayon::prelude::*;
use sketchbody::detect::calibration::Calibration;
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::{DetectOptions, Model};
use sketchbody_lab::eval::detector::{held_out_request, score_sketch, style_breakdown, SketchResult};

use crate::render_sketch::{parse_size, renderer};
use crate::train_detector::parse_hair;
use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab eval-detector`.
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
    /// Scales searched (default: the product's default search, as `sketchbody detect`).
    #[command(flatten)]
    search: sketchbody_cli::search_args::SearchArgs,
    /// Folder of mocap clips (default as in render-sketch).
    #[arg(long)]
    mocap: Option<PathBuf>,
    /// Also print PCK per rendering choice (hatching, costume, clutter, camera yaw, ...) for
    /// every model, and the first model's margin over each baseline.
    #[arg(long)]
    by_style: bool,
    /// The backends' proxy benchmark instead of the models' PCK: comma-separated sets from
    /// synthetic (the held-out sketches above), back, profile (the same renderer's back views
    /// and profiles, yaw 180° ± 20° and ±(70°..110°)), art (painted in art styles), faceless
    /// (hair none), dataset:DIR (every sketch of a rendered dataset folder, e.g. the Blender
    /// set), parse (PARSE test photos 101-305), xdog, pencil, flat (those photos
    /// stylised), negatives (blank, text and clutter pages); prints PCK, the no-figure rate and
    /// time per set for fmp, blazepose, auto (also without averaging the joints the backends
    /// agree on, by confidence alone and per limb) and the strict variants; for auto with and
    /// without the facing's labelling rule the gross-failure rate (≥ 4 joints beyond 0.2 of the
    /// figure's size), the left/right-swap rate and the facing's accuracy; and the reliability
    /// table of the calibrated confidences.
    #[arg(long)]
    sets: Option<String>,
    /// The PARSE folder for `--sets`.
    #[arg(long, default_value = "../shared/data/parse")]
    parse: PathBuf,
    /// A facing model JSON for `--sets` (as `fit-facing` writes it) instead of the embedded one.
    #[arg(long)]
    facing_model: Option<PathBuf>,
    /// With `--sets`: also list each sketch whose facing is misread or whose answer is a
    /// left/right swap, with the facing's probabilities and features.
    #[arg(long)]
    facing_cases: bool,
    /// With `--sets`: write one CSV row per image with a figure (facing features and
    /// probabilities, `auto`'s answer with and without the labelling rule and its PCK@0.2) to
    /// this file, for choosing a labelling rule offline.
    #[arg(long)]
    facing_dump: Option<PathBuf>,
    /// A calibration JSON for `--sets` (as `calibrate-detector` writes it) instead of the
    /// embedded one.
    #[arg(long)]
    calibration: Option<PathBuf>,
    /// Further calibration JSONs for `--sets` (repeatable): each adds an `auto` row per set
    /// (PCK, no-figure rate) scored on the same detections, so calibrations are compared
    /// without running the backends again.
    #[arg(long)]
    compare_calibration: Vec<PathBuf>,
    /// The sketch model `--sets` runs as the fmp backend (and inside auto) instead of the
    /// embedded one (.skbd or PARSE JSON), e.g. a retraining candidate.
    #[arg(long)]
    fmp_model: Option<PathBuf>,
    /// The BlazePose landmark network `--sets` runs as the blazepose backend (and inside auto)
    /// instead of the embedded one: an ONNX file with the asset's interface (a 1×256×256×3
    /// input, the 195-value landmark output and the 1-value pose flag), e.g. a fine-tuning
    /// candidate.
    #[arg(long)]
    landmark_model: Option<PathBuf>,
    /// PARSE photos of the `--sets` PARSE sets, A-B within 1-305: the test split 101-305 for the
    /// benchmark; a part of 1-100 (e.g. 81-100) to choose between candidates on photos no
    /// training used.
    #[arg(long, default_value = "101-305", value_parser = parse_range)]
    parse_range: (usize, usize),
}

/// Reads a calibration JSON written by `calibrate-detector`.
fn read_calibration(p: &std::path::Path) -> Result<Calibration, CliError> {
    let text = std::fs::read_to_string(p).map_err(|e| CliError(format!("{}: {e}", p.display())))?;
    Ok(Calibration::from_json(&text)?)
}

/// Largest landmark model file read by `--landmark-model` (the asset is 12.8 MB).
const MAX_LANDMARK_MODEL_BYTES: u64 = 256 << 20;

/// Reads and optimises a BlazePose landmark network from the ONNX file at `path`
/// (`--landmark-model` of `eval-detector` and `calibrate-detector`).
pub fn read_landmark_model(path: &std::path::Path) -> Result<LandmarkNet, CliError> {
    let bytes = sketchbody::fsutil::read_capped(path, MAX_LANDMARK_MODEL_BYTES)?;
    LandmarkNet::from_onnx(&bytes).map_err(|e| CliError(format!("{}: {e}", path.display())))
}

/// Parses "A-B" with 1 ≤ A ≤ B ≤ 305.
fn parse_range(s: &str) -> Result<(usize, usize), String> {
    let (a, b) = s.split_once('-').ok_or_else(|| format!("`{s}` is not A-B"))?;
    let (a, b): (usize, usize) = (
        a.trim().parse().map_err(|_| format!("`{a}` is not a photo number"))?,
        b.trim().parse().map_err(|_| format!("`{b}` is not a photo number"))?,
    );
    if (1..=b).contains(&a) && b <= 305 {
        Ok((a, b))
    } else {
        Err(format!("{a}-{b} is not a range within 1-305"))
    }
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let (w, _) = parse_size(&a.size)?;
    let hair = parse_hair(&a.hair)?;
    if a.n == 0 {
        return Err(CliError("--n must be ≥ 1".into()));
    }
    if let Some(sets) = &a.sets {
        let specs = crate::eval_backends::benchmark_sets(sets, a.n, a.seed, w, hair, a.parse_range)?;
        let model = match &a.fmp_model {
            Some(p) => Model::load_any(p)?,
            None => Model::embedded()?,
        };
        let cal = match &a.calibration {
            Some(p) => read_calibration(p)?,
            None => Calibration::embedded()?.clone(),
        };
        let others: Vec<(String, Calibration)> = a
            .compare_calibration
            .iter()
            .map(|p| Ok((p.display().to_string(), read_calibration(p)?)))
            .collect::<Result<_, CliError>>()?;
        let net = match &a.landmark_model {
            Some(p) => read_landmark_model(p)?,
            None => LandmarkNet::embedded()?,
        };
        let facing = match &a.facing_model {
            Some(p) => {
                let text = std::fs::read_to_string(p).map_err(|e| CliError(format!("{}: {e}", p.display())))?;
                Some(sketchbody::detect::facing::FacingModel::from_json(&text)?)
            }
            None => None,
        };
        return crate::eval_backends::run_sets(
            &specs,
            crate::eval_backends::FacingEval { model: facing, cases: a.facing_cases, dump: a.facing_dump.clone() },
            &renderer(a.mocap.as_deref())?,
            &a.parse,
            &cal,
            &others,
            &model,
            &net,
        );
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
    let options = DetectOptions { threshold: Some(-1e9), ..a.search.options() };
    let alphas = [0.1, 0.2];
    let refs: Vec<&Model> = models.iter().collect();
    let t0 = Instant::now();
    let per: Vec<SketchResult> = (0..a.n as u64)
        .into_par_iter()
        .map(|i| score_sketch(&r, &held_out_request(a.seed, i, w, hair), &refs, &options, &alphas))
        .collect::<Result<_, _>>()?;
    let el = t0.elapsed().as_secs_f64();
    println!(
        "held-out sketches: {} of seed {}, {w}x{w}, hair {}, {}; {:.1} s for all models",
        a.n,
        a.seed,
        a.hair,
        a.search.describe(),
        el
    );
    println!("drawn figure height / shorter side: {}", spread(per.iter().map(|p| p.figure_fraction).collect()));
    for (k, name) in names.iter().enumerate() {
        let mean = |j: usize| per.iter().map(|s| s.scores[k].pck[j]).sum::<f64>() / per.len() as f64;
        let ms = 1e3 * per.iter().map(|s| s.scores[k].seconds).sum::<f64>() / per.len() as f64;
        println!(
            "{name}: PCK@0.1 {:.3}  PCK@0.2 {:.3}  mean detect {ms:.0} ms (wall, {} threads shared by the evaluation)",
            mean(0),
            mean(1),
            rayon::current_num_threads()
        );
        // The scale of the best detection where it is right (PCK@0.2 ≥ 0.8), as the figure
        // height its level is tuned to over the shorter side: what the search range must cover.
        let right: Vec<f64> =
            per.iter().filter(|s| s.scores[k].pck[1] >= 0.8).filter_map(|s| s.scores[k].found_fraction).collect();
        println!(
            "  found at (cell × rest height / shorter side) where PCK@0.2 ≥ 0.8 ({} sketches): {}",
            right.len(),
            spread(right)
        );
    }
    if a.by_style {
        print_breakdown(&per, &names)?;
    }
    Ok(())
}

/// The `--by-style` table: one row per style group, PCK@0.1 / @0.2 of each model, and the
/// first model's margin over the others at both alphas.
fn print_breakdown(per: &[SketchResult], names: &[String]) -> Result<(), CliError> {
    println!("PCK@0.1 / PCK@0.2 by rendering choice (models in the order above: {}):", names.join(", "));
    for g in style_breakdown(per)? {
        if g.n == 0 {
            println!("  {:<20} {:>4}", g.name, 0);
            continue;
        }
        let cells: Vec<String> = g.mean_pck.iter().map(|p| format!("{:.3} / {:.3}", p[0], p[1])).collect();
        let margins: Vec<String> = g.mean_pck[1..]
            .iter()
            .map(|p| format!("{:+.3} / {:+.3}", g.mean_pck[0][0] - p[0], g.mean_pck[0][1] - p[1]))
            .collect();
        let margin = if margins.is_empty() { String::new() } else { format!("   margin {}", margins.join(", ")) };
        println!("  {:<20} {:>4}   {}{margin}", g.name, g.n, cells.join("   "));
    }
    Ok(())
}

/// "min a, 1% b, 5% c, median d, max e" of `v` (nearest-rank percentiles; "none" when empty).
fn spread(mut v: Vec<f64>) -> String {
    if v.is_empty() {
        return "none".into();
    }
    v.sort_by(f64::total_cmp);
    let q = |p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    format!("min {:.3}, 1% {:.3}, 5% {:.3}, median {:.3}, max {:.3}", v[0], q(0.01), q(0.05), q(0.5), v[v.len() - 1])
}

//! `sketchbody-lab train-detector --out assets/detector.skbd`: trains a flexible-mixture-of-parts
//! detector on synthetic concept sketches (`detect::train`) and writes it in the `.skbd` format
//! (temporary file, then renamed). Progress goes to stderr, one line per stage.

use std::path::PathBuf;

use sketchbody::render::sketch::Hair;
use sketchbody_lab::detect::train::mine::SearchRange;
use sketchbody_lab::detect::train::parse_positives::ParseSource;
use sketchbody_lab::detect::train::{train, TrainOptions};

use crate::render_sketch::renderer;
use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab train-detector`.
#[derive(clap::Args)]
pub struct Args {
    /// Output model (.skbd).
    #[arg(long)]
    out: PathBuf,
    /// Sketches rendered for positives (each also mirrored).
    #[arg(long, default_value_t = 100)]
    positives: usize,
    /// Negative pages (no figure).
    #[arg(long, default_value_t = 50)]
    negatives: usize,
    /// Mixtures per part.
    #[arg(long, default_value_t = 4)]
    mixtures: usize,
    /// Hard-negative mining rounds.
    #[arg(long, default_value_t = 3)]
    rounds: usize,
    /// Training seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// SVM C.
    #[arg(long, default_value_t = 0.01)]
    c: f64,
    /// Image side of the rendered training images, px.
    #[arg(long, default_value_t = 512)]
    size: usize,
    /// Hair style held out of training: none, short, long, spiky, bun, ponytail, or "keep" to
    /// use every style.
    #[arg(long, default_value = "ponytail")]
    hold_out_hair: String,
    /// Fraction of the positives drawn as capsule mannequins around the same joints (0..=1).
    #[arg(long, default_value_t = 0.0, value_parser = sketchbody_cli::ranges::real(0.0, 1.0, false))]
    mannequins: f64,
    /// Fraction of the positives rendered in a random art style (flat, cel, screen tone,
    /// watercolour, thick ink, masses, chibi/heroic, textured paper); with --mannequins at most
    /// 1 in all.
    #[arg(long, default_value_t = 0.0, value_parser = sketchbody_cli::ranges::real(0.0, 1.0, false))]
    art_styles: f64,
    /// PARSE folder (images/, labels.csv): add its training photos 1..=--parse-last through the
    /// drawing-like training filters (sobel, charcoal, marker) as positives.
    #[arg(long)]
    parse_positives: Option<PathBuf>,
    /// Last PARSE photo used with --parse-positives (1..=100; 101-305 are the test split).
    #[arg(long, default_value_t = 80, value_parser = sketchbody_cli::ranges::count(1..=100))]
    parse_last: usize,
    /// Filtered copies of each PARSE photo (1..=8).
    #[arg(long, default_value_t = 2, value_parser = sketchbody_cli::ranges::count(1..=8))]
    parse_variants: usize,
    /// Coordinate-descent passes per solve, at most (1..=100000).
    #[arg(long, default_value_t = 60, value_parser = sketchbody_cli::ranges::count(1..=100_000))]
    max_passes: usize,
    /// Smallest and largest cell searched when mining negatives, px.
    #[arg(long, default_value_t = 4.0)]
    min_cell: f64,
    /// Largest cell searched when mining negatives, px.
    #[arg(long, default_value_t = 20.0)]
    max_cell: f64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Folder of mocap clips (default as in render-sketch).
    #[arg(long)]
    mocap: Option<PathBuf>,
}

/// Parses a hair style name (`keep` = hold nothing out).
pub fn parse_hair(s: &str) -> Result<Option<Hair>, CliError> {
    Ok(Some(match s {
        "keep" => return Ok(None),
        "none" => Hair::None,
        "short" => Hair::Short,
        "long" => Hair::Long,
        "spiky" => Hair::Spiky,
        "bun" => Hair::Bun,
        "ponytail" => Hair::Ponytail,
        _ => {
            return Err(CliError(format!(
                "--hold-out-hair {s:?}: expected none, short, long, spiky, bun, ponytail or keep"
            )))
        }
    }))
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    if a.out.extension().is_none_or(|e| e != "skbd") {
        return Err(CliError(format!("--out {}: must end in .skbd", a.out.display())));
    }
    if a.art_styles + a.mannequins > 1.0 {
        return Err(CliError(format!(
            "--art-styles {} with --mannequins {}: together at most 1",
            a.art_styles, a.mannequins
        )));
    }
    let o = TrainOptions {
        seed: a.seed,
        positives: a.positives,
        negatives: a.negatives,
        mixtures: a.mixtures,
        rounds: a.rounds,
        c: a.c,
        image_size: a.size,
        held_out_hair: parse_hair(&a.hold_out_hair)?,
        mannequins: a.mannequins,
        art_styles: a.art_styles,
        parse: a.parse_positives.map(|dir| ParseSource { dir, last: a.parse_last, variants: a.parse_variants }),
        max_passes: a.max_passes,
        search: SearchRange { min_cell_px: a.min_cell, max_cell_px: a.max_cell },
        ..TrainOptions::default()
    };
    let r = renderer(a.mocap.as_deref())?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.unwrap_or(0))
        .build()
        .map_err(|e| CliError(format!("thread pool: {e}")))?;
    let t0 = std::time::Instant::now();
    let t = pool.install(|| train(&r, &o, &mut |line| eprintln!("{line}")))?;
    t.model.save(&a.out)?;
    let ps = &t.positive_scores;
    let mean = ps.iter().sum::<f64>() / ps.len().max(1) as f64;
    println!(
        "{}: {} parts x {} mixtures, {} positives ({} sketches skipped), mean positive score {mean:.3}, threshold {:.3}, {:.1} s on {} threads",
        a.out.display(),
        t.model.parts.len(),
        a.mixtures,
        t.counts.0,
        t.counts.1,
        t.model.thresh,
        t0.elapsed().as_secs_f64(),
        pool.current_num_threads()
    );
    Ok(())
}

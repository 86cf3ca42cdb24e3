//! `sketchbody-lab eval-detector --sets ...`: the detector backends (fmp, blazepose, auto, and the
//! strict variants) on the real-drawing proxy benchmark: held-out rendered sketches, the PARSE
//! *test* photos (101–305) plain and through stylisations never used in training, and pages
//! without a figure; PCK@0.1 / @0.2, the no-figure rate and time per set and backend, and the
//! reliability table of `auto`'s calibrated confidence.

use std::path::Path;

use sketchbody::detect::calibration::Calibration;
use sketchbody::detect::facing::Facing;
use sketchbody::detect::facing::FacingModel;
use sketchbody::detect::figure::{Backend, FigureOptions, Fusion};
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::Model;
use sketchbody::pipeline::figure::decide;
use sketchbody::render::sketch::{Hair, SketchRenderer};
use sketchbody_lab::eval::backends::{
    expected_calibration_error, is_swap, reliability, score_set, Sample, GROSS_JOINTS,
};
use sketchbody_lab::eval::facing::{dump_rows, misread, DUMP_HEADER};
use sketchbody_lab::render::photo_npr::PhotoNpr;
use sketchbody_lab::render::stylise::{NegativePage, Stylisation};

use crate::backend_sets::{gather_set, SetContext, SetSpec, View};
use sketchbody_cli::CliError;

/// The set names `--sets` takes.
pub const SET_NAMES: &str = "synthetic, back (back views), profile, art (art styles), faceless (no hair), dataset:DIR (every sketch of a rendered dataset folder, e.g. the Blender set), parse, xdog, pencil, flat, negatives, and the training filters npr-sobel, npr-charcoal, npr-marker";

/// The facing model of a benchmark run and its diagnostics.
#[derive(Clone, Debug, Default)]
pub struct FacingEval {
    /// Replaces the embedded facing model (`None`: the embedded one).
    pub model: Option<FacingModel>,
    /// Print each sketch whose facing is misread ([`misread`]) or whose answer is a left/right
    /// swap, with its probabilities and features.
    pub cases: bool,
    /// Write one CSV row per image with a figure here ([`dump_rows`]).
    pub dump: Option<std::path::PathBuf>,
}

/// Prints the sketches of `samples` whose facing `model` misreads and those `auto` (with
/// `options`) answers with a left/right swap.
fn print_facing_cases(
    samples: &[Sample],
    model: &FacingModel,
    cal: &Calibration,
    options: &FigureOptions,
) -> Result<(), CliError> {
    let name = |f: Facing| f.name();
    for m in misread(samples, model) {
        let p = m.probabilities;
        let x: Vec<String> = m.features[1..].iter().map(|v| format!("{v:.2}")).collect();
        println!(
            "{:<26}       misread {}: torso yaw {:.0}° ({}), decided {} (p {:.2} {:.2} {:.2} {:.2}), features {}",
            "",
            m.index,
            m.yaw_deg,
            name(Facing::of_yaw(m.yaw_deg)),
            name(m.decided),
            p[0],
            p[1],
            p[2],
            p[3],
            x.join(" ")
        );
    }
    for (i, s) in samples.iter().enumerate() {
        let (Some(t), Ok(f)) = (&s.truth, decide(&s.evidence, cal, options, None)) else { continue };
        if is_swap(t, &f.joints) {
            println!(
                "{:<26}       swap {i}: torso yaw {}, facing {}, swapped by the rule {}",
                "",
                s.yaw_deg.map_or("-".into(), |y| format!("{y:.0}°")),
                name(f.facing.facing),
                f.facing.swapped
            );
        }
    }
    Ok(())
}

/// The benchmark sets named in `names` (comma separated, from [`SET_NAMES`]); the PARSE sets
/// take photos `photos` (the test split 101-305 for the benchmark).
pub fn benchmark_sets(
    names: &str,
    n: usize,
    seed: u64,
    size: usize,
    hair: Option<Hair>,
    photos: (usize, usize),
) -> Result<Vec<SetSpec>, CliError> {
    let (first, last) = photos;
    let mut out = Vec::new();
    for name in names.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        if let Some(dir) = name.strip_prefix("dataset:") {
            let n = crate::backend_sets::dataset_images(std::path::Path::new(dir))?.len();
            out.push(SetSpec::Dataset { dir: dir.into(), n });
            continue;
        }
        match name {
            "synthetic" => out.push(SetSpec::Synthetic { seed, n, size, hair, view: View::Random, art: false }),
            "back" => out.push(SetSpec::Synthetic { seed, n, size, hair, view: View::Back, art: false }),
            "profile" => out.push(SetSpec::Synthetic { seed, n, size, hair, view: View::Profile, art: false }),
            "art" => out.push(SetSpec::Synthetic { seed, n, size, hair, view: View::Random, art: true }),
            "faceless" => {
                out.push(SetSpec::Synthetic { seed, n, size, hair: Some(Hair::None), view: View::Random, art: false })
            }
            "parse" => out.push(SetSpec::Parse { first, last, style: None, npr: None }),
            "negatives" => out.extend(NegativePage::ALL.map(|kind| SetSpec::Negative { kind, n: 60, seed })),
            other => match (other.parse::<Stylisation>(), other.strip_prefix("npr-").and_then(PhotoNpr::from_name)) {
                (Ok(s), _) => out.push(SetSpec::Parse { first, last, style: Some(s), npr: None }),
                (_, Some(f)) => out.push(SetSpec::Parse { first, last, style: None, npr: Some(f) }),
                _ => return Err(CliError(format!("--sets: unknown set {other:?}; expected {SET_NAMES}"))),
            },
        }
    }
    Ok(out)
}

/// `auto`'s PCK@0.2 and no-figure rate on `samples` with `cal` at each presence threshold of
/// `thresholds`, as "threshold: PCK / rate%" joined by commas.
fn presence_sweep(samples: &[Sample], cal: &Calibration, thresholds: &[f64]) -> Result<String, CliError> {
    let cells: Vec<String> = thresholds
        .iter()
        .map(|&m| {
            let o = FigureOptions { min_presence: m, ..FigureOptions::default() };
            score_set(samples, cal, &o).map(|s| format!("{m}: {:.3} / {:.1}%", s.pck[1], 100.0 * s.no_figure))
        })
        .collect::<Result<_, _>>()?;
    Ok(cells.join(", "))
}

/// Runs the evaluation on `specs` and prints the tables; each of `others` (name, calibration)
/// adds an `auto` row per set, scored on the same detections; `net` is the landmark backend's
/// network; `facing` the facing model and its diagnostics.
#[allow(clippy::too_many_arguments)]
pub fn run_sets(
    specs: &[SetSpec],
    facing: FacingEval,
    renderer: &SketchRenderer,
    parse_dir: &Path,
    cal: &Calibration,
    others: &[(String, Calibration)],
    model: &Model,
    net: &LandmarkNet,
) -> Result<(), CliError> {
    let ctx = SetContext { renderer, parse_dir, model, net };
    let options = FigureOptions { facing_model: facing.model, ..FigureOptions::default() };
    let facing_model = match &options.facing_model {
        Some(m) => m.clone(),
        None => FacingModel::embedded()?.clone(),
    };
    let averaged = options.average_agreement;
    let configs = [
        (Backend::Fmp, false, Fusion::PerImage, averaged, "fmp"),
        (Backend::BlazePose, false, Fusion::PerImage, averaged, "blazepose"),
        (Backend::Auto, false, Fusion::PerImage, averaged, "auto"),
        (Backend::Auto, false, Fusion::PerImage, 0.0, "auto unaveraged"),
        (Backend::Auto, false, Fusion::Confidence, averaged, "auto by confidence"),
        (Backend::Auto, false, Fusion::PerLimb, averaged, "auto per limb"),
        (Backend::Fmp, true, Fusion::PerImage, averaged, "fmp strict"),
        (Backend::BlazePose, true, Fusion::PerImage, averaged, "blazepose strict"),
    ];
    println!("PCK@0.1 / PCK@0.2, no-figure rate, mean ms per image (wall, images in parallel) per set and backend");
    println!("{:<26} {:>4}  {}", "set", "n", configs.map(|c| format!("{:<30}", c.4)).join(""));
    let mut positives: Vec<Sample> = Vec::new();
    let mut dump = vec![DUMP_HEADER.to_string()];
    for spec in specs {
        let samples = gather_set(spec, &ctx, &options)?;
        let mut cells = Vec::new();
        for &(backend, strict, fusion, average_agreement, _) in &configs {
            let o = FigureOptions { backend, strict, fusion, average_agreement, ..options.clone() };
            let s = score_set(&samples, cal, &o)?;
            let pck = if s.pck[0].is_nan() {
                "   -  /   -  ".to_string()
            } else {
                format!("{:.3} / {:.3}", s.pck[0], s.pck[1])
            };
            cells.push(format!("{pck} {:>5.1}% {:>4.0}ms  ", 100.0 * s.no_figure, 1e3 * s.seconds));
        }
        println!("{:<26} {:>4}  {}", spec.label(), samples.len(), cells.join(""));
        let auto = score_set(&samples, cal, &options)?;
        let limb = score_set(&samples, cal, &FigureOptions { fusion: Fusion::PerLimb, ..options.clone() })?;
        println!(
            "{:<26}       auto kept fmp on {:.0}%, blazepose on {:.0}% of its answers; per limb: fmp {:.0}%, blazepose {:.0}%, mixed {:.0}%",
            "",
            100.0 * auto.chosen[0],
            100.0 * auto.chosen[1],
            100.0 * limb.chosen[0],
            100.0 * limb.chosen[1],
            100.0 * limb.chosen[2]
        );
        for (rule, name) in [(true, "auto"), (false, "auto, the backends' labelling")] {
            let o = FigureOptions { facing_rule: rule, ..options.clone() };
            let s = score_set(&samples, cal, &o)?;
            println!(
                "{:<26}       {name}: PCK@0.2 {:.3}, >= {GROSS_JOINTS} joints wrong {:.1}%, left/right swaps {:.1}%, facing right / unknown / wrong {:.1} / {:.1} / {:.1}%",
                "",
                s.pck[1],
                100.0 * s.gross,
                100.0 * s.swaps,
                100.0 * s.facing[0],
                100.0 * s.facing[1],
                100.0 * s.facing[2]
            );
        }
        if facing.cases {
            print_facing_cases(&samples, &facing_model, cal, &options)?;
        }
        if let Some(path) = &facing.dump {
            dump.extend(dump_rows(&spec.label(), &samples, &facing_model, cal, &options)?);
            std::fs::write(path, dump.join("\n") + "\n").map_err(|e| CliError(format!("{}: {e}", path.display())))?;
        }
        let sweep = presence_sweep(&samples, cal, &[0.5, 0.2, 0.1, 0.05])?;
        println!("{:<26}       auto by min presence (PCK@0.2 / no figure): {sweep}", "");
        for (name, other) in others {
            let s = score_set(&samples, other, &FigureOptions::default())?;
            let stricter = presence_sweep(&samples, other, &[0.6, 0.7, 0.8, 0.9])?;
            println!(
                "{:<26}       auto with {name}: {:.3} / {:.3} {:>5.1}%; by min presence (PCK@0.2 / no figure): {}",
                "",
                s.pck[0],
                s.pck[1],
                100.0 * s.no_figure,
                stricter
            );
        }
        positives.extend(samples.into_iter().filter(|s| s.truth.is_some()));
    }
    for b in [Backend::Auto, Backend::Fmp, Backend::BlazePose] {
        let table = reliability(&positives, cal, &FigureOptions { backend: b, ..options.clone() }, 10)?;
        println!(
            "reliability of {}'s confidence on {} images with a figure (bin: n, mean confidence, observed PCK@0.2); ECE {:.3}",
            b.name(),
            positives.len(),
            expected_calibration_error(&table)
        );
        for bin in table.iter().filter(|b| b.n > 0) {
            println!("  [{:.1}, {:.1})  {:>5}  {:.3}  {:.3}", bin.lo, bin.hi, bin.n, bin.mean_confidence, bin.observed);
        }
    }
    Ok(())
}

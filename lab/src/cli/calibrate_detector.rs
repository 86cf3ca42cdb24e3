//! `sketchbody-lab calibrate-detector --out assets/detector_calibration.json`: fits the detector
//! backends' calibration (`detect::calibration`) on a calibration set disjoint from every
//! benchmark set: rendered sketches of another seed than the held-out set's, PARSE *training*
//! photos (1–100; with `--stylised` also through each stylisation, with `--npr` through each
//! training filter), and pages without a figure.

use std::path::PathBuf;

use sketchbody::detect::figure::FigureOptions;
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::Model;
use sketchbody_lab::eval::backends::{fit_calibration, refuse_negatives, Sample};
use sketchbody_lab::render::photo_npr::PhotoNpr;
use sketchbody_lab::render::stylise::{NegativePage, Stylisation};

use crate::backend_sets::{gather_set, SetContext, SetSpec};
use crate::render_sketch::renderer;
use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab calibrate-detector`.
#[derive(clap::Args)]
pub struct Args {
    /// Output calibration JSON.
    #[arg(long)]
    out: PathBuf,
    /// The PARSE folder (images/ and labels.csv).
    #[arg(long, default_value = "../shared/data/parse")]
    parse: PathBuf,
    /// Rendered sketches in the calibration set.
    #[arg(long, default_value_t = 200)]
    synthetic: usize,
    /// Seed of the rendered sketches (the held-out benchmark uses 2, training 1).
    #[arg(long, default_value_t = 11)]
    seed: u64,
    /// Last PARSE training photo used (1..=100).
    #[arg(long, default_value_t = 100, value_parser = sketchbody_cli::ranges::count(1..=100))]
    parse_last: usize,
    /// Also calibrate on the PARSE training photos through each stylisation. Off by default, so
    /// that the stylised benchmark sets (`eval-detector --sets`) test styles the calibration has
    /// never seen.
    #[arg(long)]
    stylised: bool,
    /// Also calibrate on the PARSE training photos through each training filter
    /// (`render::photo_npr`: Sobel ink, charcoal, marker), drawing-like images of real poses
    /// whose styles differ from the benchmark's stylisations.
    #[arg(long)]
    npr: bool,
    /// Pages of each kind without a figure (blank, text, clutter).
    #[arg(long, default_value_t = 40)]
    negatives: usize,
    /// Make the presence models refuse at least this fraction of each kind of page without a
    /// figure in the calibration set (`eval::backends::refuse_negatives`; e.g. 0.975). Off by
    /// default: the presence models stay calibrated probabilities.
    #[arg(long, value_parser = sketchbody_cli::ranges::real(0.0, 1.0, false))]
    refuse: Option<f64>,
    /// L2 penalty of the logistic fits.
    #[arg(long, default_value_t = 1e-2)]
    ridge: f64,
    /// The sketch model calibrated as the fmp backend instead of the embedded one (.skbd or
    /// PARSE JSON), e.g. a retraining candidate.
    #[arg(long)]
    fmp_model: Option<PathBuf>,
    /// The BlazePose landmark network calibrated as the blazepose backend instead of the
    /// embedded one (an ONNX file with the asset's interface), e.g. a fine-tuning candidate.
    #[arg(long)]
    landmark_model: Option<PathBuf>,
    /// Folder of mocap clips for the renderer (default as in render-sketch).
    #[arg(long)]
    mocap: Option<PathBuf>,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let model = match &a.fmp_model {
        Some(p) => Model::load_any(p)?,
        None => Model::embedded()?,
    };
    let net = match &a.landmark_model {
        Some(p) => crate::eval_detector::read_landmark_model(p)?,
        None => LandmarkNet::embedded()?,
    };
    let r = renderer(a.mocap.as_deref())?;
    let ctx = SetContext { renderer: &r, parse_dir: &a.parse, model: &model, net: &net };
    let mut specs = vec![SetSpec::Synthetic {
        seed: a.seed,
        n: a.synthetic,
        size: 512,
        hair: None,
        view: crate::backend_sets::View::Random,
        art: false,
    }];
    specs.push(SetSpec::Parse { first: 1, last: a.parse_last, style: None, npr: None });
    if a.stylised {
        for s in Stylisation::ALL {
            specs.push(SetSpec::Parse { first: 1, last: a.parse_last, style: Some(s), npr: None });
        }
    }
    if a.npr {
        for f in PhotoNpr::ALL {
            specs.push(SetSpec::Parse { first: 1, last: a.parse_last, style: None, npr: Some(f) });
        }
    }
    for kind in NegativePage::ALL {
        specs.push(SetSpec::Negative { kind, n: a.negatives, seed: a.seed });
    }
    let options = FigureOptions::default();
    let mut samples = Vec::new();
    let mut negative_ranges = Vec::new();
    for s in &specs {
        let start = samples.len();
        samples.extend(gather_set(s, &ctx, &options)?);
        if matches!(s, SetSpec::Negative { .. }) {
            negative_ranges.push(start..samples.len());
        }
    }
    let labels: Vec<String> = specs.iter().map(SetSpec::label).collect();
    let provenance = format!(
        "sketchbody-lab calibrate-detector --synthetic {} --seed {} --parse-last {}{}{} --negatives {}{} --ridge {}; sets: {}; {} images",
        a.synthetic,
        a.seed,
        a.parse_last,
        if a.stylised { " --stylised" } else { "" },
        if a.npr { " --npr" } else { "" },
        a.negatives,
        a.refuse.map(|q| format!(" --refuse {q}")).unwrap_or_default(),
        a.ridge,
        labels.join(", "),
        samples.len()
    );
    let mut cal = fit_calibration(&samples, a.ridge, &provenance)?;
    if let Some(q) = a.refuse {
        let sets: Vec<&[Sample]> = negative_ranges.iter().map(|r| &samples[r.clone()]).collect();
        let d = refuse_negatives(&mut cal, &sets, q)?;
        println!("presence intercepts lowered by {:.3} to refuse {q} of each negative set", -d);
    }
    sketchbody::fsutil::write_atomic(&a.out, (cal.to_json() + "\n").as_bytes())?;
    println!("calibration of {} images written to {}", samples.len(), a.out.display());
    println!("{}", cal.to_json());
    Ok(())
}

//! `sketchbody detect SKETCH --out JOINTS.json [--detector auto|fmp|blazepose] [--overlay X.png]`:
//! 2-D pose of the best figure (canonical 15 joints with calibrated confidences, the backend
//! used, the low-confidence flag, the other figures). `--model FILE` runs another sketch model
//! alone with its raw scores and threshold (the PARSE joints too).

use std::path::PathBuf;

use serde_json::{json, Map, Value};
use sketchbody::detect::figure::{Backend, FigureOptions, AVERAGE_AGREEMENT};
use sketchbody::detect::landmark::LandmarkNet;
use sketchbody::detect::{detect, DetectOptions, Detection, Model, PARSE_JOINT_NAMES};
use sketchbody::export::joints2d::{
    alternatives_json, detection_json as figure_json, facing_json, facing_summary, LOW_CONFIDENCE_HINT,
};
use sketchbody::image::{load_rgb_image, RgbImage};
use sketchbody::pipeline::figure::detect_figure;
use sketchbody::skeleton::Joints2;
use sketchbody::skeleton::{BONES, JOINT_NAMES};

use crate::CliError;

/// Arguments of `sketchbody detect`.
#[derive(clap::Args)]
pub struct Args {
    /// Input sketch or photo (PNG or JPEG).
    input: PathBuf,
    /// Backend: auto (the sketch model and BlazePose; one candidate per image: on a drawing the
    /// sketch model recognises, the one whose proportions the 3-D pose step finds nearer a
    /// body's, else the higher calibrated confidence), fmp (the sketch model), blazepose
    /// (MediaPipe's landmark model).
    #[arg(long, default_value = "auto", value_parser = parse_backend)]
    detector: Backend,
    /// Hard thresholds: "no figure" unless a backend passes its own threshold (the sketch model's
    /// score threshold, BlazePose's pose flag 0.5). Default: the best figure whenever the image
    /// plausibly holds one.
    #[arg(long)]
    strict: bool,
    /// With both backends (auto): each joint the two put within this fraction of the figure's
    /// size of each other becomes their mean (0 = keep the chosen backend's joints).
    #[arg(long, default_value_t = AVERAGE_AGREEMENT, value_parser = parse_fraction)]
    average_agreement: f64,
    /// Another sketch model, run alone with its raw scores and threshold (research): a binary
    /// `.skbd` model or the PARSE model JSON. Without it the embedded models run.
    #[arg(long)]
    model: Option<PathBuf>,
    /// Output joints JSON: the `sketchbody-joints2d` format (input of `sketchbody pose`) plus the
    /// confidences, PARSE joints and other figures (pixels, origin top-left, y down).
    #[arg(long)]
    out: PathBuf,
    /// Also write the input with the skeleton drawn on it (PNG).
    #[arg(long)]
    overlay: Option<PathBuf>,
    /// Score threshold of the sketch model, used with --strict or --model (default: the
    /// model's); negative values as `--threshold=-2`.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::ranges::real(f64::MIN, f64::MAX, false))]
    threshold: Option<f64>,
    /// Scales searched.
    #[command(flatten)]
    search: crate::search_args::SearchArgs,
    /// Longer-side cap in pixels (32..=16384); larger images are downscaled first.
    #[arg(long, default_value_t = sketchbody::detect::DEFAULT_MAX_DETECT_SIDE, value_parser = crate::ranges::count(32..=16384))]
    max_side: usize,
}

fn detection_json(d: &Detection) -> Value {
    let mut joints = Map::new();
    let mut conf = Map::new();
    for (j, name) in JOINT_NAMES.iter().enumerate() {
        joints.insert((*name).into(), json!(d.joints.xy[j]));
        conf.insert((*name).into(), json!(d.confidence[j]));
    }
    let mut parse = Map::new();
    for (j, name) in PARSE_JOINT_NAMES.iter().enumerate() {
        parse.insert((*name).into(), json!(d.parse_joints[j]));
    }
    json!({ "score": d.score, "bbox": d.bbox, "joints": joints, "confidence": conf, "parse_joints": parse })
}

/// The hint printed with "no figure".
pub const NO_FIGURE_HINT: &str =
    "if the image does hold a figure, give its 2-D joints with --joints (a sketchbody-joints2d file, docs/formats.md)";

/// Parses a finite fraction ≥ 0 (`--average-agreement`).
pub fn parse_fraction(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("{s:?} is not a finite number >= 0")),
    }
}

/// Parses `--detector`.
pub fn parse_backend(s: &str) -> Result<Backend, String> {
    s.parse().map_err(|e: sketchbody::Error| e.to_string())
}

/// Draws the skeleton `joints` on a copy of `img` (bones red, joints yellow; joints whose
/// confidence is under the low-confidence level in orange-red).
fn overlay(img: &RgbImage, joints: &Joints2, confidence: &[f64; 15]) -> Vec<u8> {
    let (w, h) = (img.width(), img.height());
    let mut px = img.as_bytes().to_vec();
    let mut put = |x: f64, y: f64, c: [u8; 3]| {
        if x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h {
            let i = 3 * ((y as usize) * w + x as usize);
            px[i..i + 3].copy_from_slice(&c);
        }
    };
    let r = (w.max(h) as f64 / 200.0).max(1.0);
    for &(a, b) in &BONES {
        let (p, q) = (joints.xy[a], joints.xy[b]);
        let n = ((q[0] - p[0]).hypot(q[1] - p[1]) * 2.0).ceil().max(1.0) as usize;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let (x, y) = (p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]));
            for o in [-0.5, 0.0, 0.5] {
                put(x + o * r, y, [255, 0, 0]);
                put(x, y + o * r, [255, 0, 0]);
            }
        }
    }
    for (p, &c) in joints.xy.iter().zip(confidence) {
        let low = c < sketchbody::detect::figure::LOW_CONFIDENCE;
        let k = (if low { 3.0 } else { 2.0 } * r).ceil() as i64;
        for dy in -k..=k {
            for dx in -k..=k {
                put(p[0] + dx as f64, p[1] + dy as f64, if low { [255, 80, 0] } else { [255, 220, 0] });
            }
        }
    }
    px
}

/// Writes the joints JSON and the optional overlay as one set (`fsutil::OutputSet`): both
/// replace their targets, or neither does.
fn write_outputs(
    a: &Args,
    img: &RgbImage,
    doc: &Value,
    joints: &Joints2,
    confidence: &[f64; 15],
) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(doc).map_err(|e| CliError(format!("JSON encoding failed: {e}")))?;
    let mut outputs = sketchbody::fsutil::OutputSet::new();
    outputs.write(&a.out, text.as_bytes())?;
    if let Some(path) = &a.overlay {
        let mut png = Vec::new();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut png),
            &overlay(img, joints, confidence),
            img.width() as u32,
            img.height() as u32,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| CliError(format!("{}: PNG encoding failed: {e}", path.display())))?;
        outputs.write(path, &png)?;
    }
    outputs.commit()?;
    Ok(())
}

fn header(a: &Args, img: &RgbImage) -> Value {
    json!({
        "format": "sketchbody-joints2d",
        "version": 1,
        "image": a.input.display().to_string(),
        "width": img.width(),
        "height": img.height(),
        "frame": "pixels; origin at the top-left corner of the top-left pixel; x right, y down",
    })
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let img = load_rgb_image(&a.input)?;
    let search = DetectOptions { threshold: a.threshold, max_side: a.max_side, ..a.search.options() };
    let no_figure = |e: sketchbody::Error| match e {
        sketchbody::Error::NoFigure { .. } => CliError(format!("{}: {e}; {NO_FIGURE_HINT}", a.input.display())),
        e => CliError(format!("{}: {e}", a.input.display())),
    };
    if let Some(path) = &a.model {
        let model = Model::load_any(path)?;
        let dets = detect(&img.view(), &model, &search).map_err(no_figure)?;
        let best = dets.best();
        let mut doc = header(&a, &img);
        doc["score"] = json!(best.score);
        doc["joints"] = detection_json(best)["joints"].clone();
        doc["confidence"] = detection_json(best)["confidence"].clone();
        doc["best"] = detection_json(best);
        doc["others"] = json!(dets.all[1..].iter().map(detection_json).collect::<Vec<_>>());
        write_outputs(&a, &img, &doc, &best.joints, &best.confidence)?;
        println!("score {:.3}, {} figure(s); joints written to {}", best.score, dets.all.len(), a.out.display());
        return Ok(());
    }
    let model = Model::embedded()?;
    let net = LandmarkNet::embedded_deferred();
    let options = FigureOptions {
        backend: a.detector,
        strict: a.strict,
        sketch: search,
        average_agreement: a.average_agreement,
        ..FigureOptions::default()
    };
    let f = detect_figure(&img.view(), &model, &net, &options, None).map_err(no_figure)?;
    let mut doc = header(&a, &img);
    let mut joints = Map::new();
    let mut conf = Map::new();
    for (j, name) in JOINT_NAMES.iter().enumerate() {
        joints.insert((*name).into(), json!(f.joints.xy[j]));
        conf.insert((*name).into(), json!(f.joint_confidence[j]));
    }
    doc["joints"] = Value::Object(joints);
    doc["confidence"] = Value::Object(conf);
    doc["detection"] = figure_json(&f);
    doc["facing"] = facing_json(&f.facing);
    doc["alternatives"] = alternatives_json(&f.facing)?;
    doc["others"] = json!(f.others.iter().map(detection_json).collect::<Vec<_>>());
    write_outputs(&a, &img, &doc, &f.joints, &f.joint_confidence)?;
    println!(
        "{} figure ({} joint(s) averaged with the other backend's), confidence {:.2}, {}, {} other figure(s); joints written to {}",
        f.backend.name(),
        f.averaged.iter().filter(|a| **a).count(),
        f.confidence,
        facing_summary(&f.facing),
        f.others.len(),
        a.out.display()
    );
    if f.low_confidence {
        eprintln!("sketchbody: {LOW_CONFIDENCE_HINT}");
    }
    Ok(())
}

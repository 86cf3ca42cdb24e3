//! `sketchbody detect SKETCH [--model FILE] --out JOINTS.json [--overlay X.png]`: 2-D pose of the
//! best figure (canonical 15 joints with confidences, the PARSE joints, the other figures), with
//! the embedded sketch-trained detector unless `--model` names another.

use std::path::PathBuf;

use serde_json::{json, Map, Value};
use sketchbody::detect::{detect, DetectOptions, Detection, Model, PARSE_JOINT_NAMES};
use sketchbody::image::{load_rgb_image, RgbImage};
use sketchbody::skeleton::{BONES, JOINT_NAMES};

use crate::CliError;

/// Arguments of `sketchbody detect`.
#[derive(clap::Args)]
pub struct Args {
    /// Input sketch or photo (PNG or JPEG).
    input: PathBuf,
    /// Detector model: a binary `.skbd` model or the PARSE model JSON (default: the embedded
    /// detector trained on synthetic concept sketches).
    #[arg(long)]
    model: Option<PathBuf>,
    /// Output joints JSON: the `sketchbody-joints2d` format (input of `sketchbody pose`) plus the
    /// confidences, PARSE joints and other figures (pixels, origin top-left, y down).
    #[arg(long)]
    out: PathBuf,
    /// Also write the input with the skeleton drawn on it (PNG).
    #[arg(long)]
    overlay: Option<PathBuf>,
    /// Score threshold (default: the model's); negative values as `--threshold=-2`.
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

/// Draws the skeleton of `d` on a copy of `img` (bones red, joints yellow).
fn overlay(img: &RgbImage, d: &Detection) -> Vec<u8> {
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
        let (p, q) = (d.joints.xy[a], d.joints.xy[b]);
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
    for p in &d.joints.xy {
        let k = (2.0 * r).ceil() as i64;
        for dy in -k..=k {
            for dx in -k..=k {
                put(p[0] + dx as f64, p[1] + dy as f64, [255, 220, 0]);
            }
        }
    }
    px
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let model = match &a.model {
        Some(p) => Model::load_any(p)?,
        None => Model::embedded()?,
    };
    let img = load_rgb_image(&a.input)?;
    let opts = DetectOptions { threshold: a.threshold, max_side: a.max_side, ..a.search.options() };
    let dets = detect(&img.view(), &model, &opts)?;
    let best = dets.best();
    let doc = json!({
        "format": "sketchbody-joints2d",
        "version": 1,
        "image": a.input.display().to_string(),
        "width": img.width(),
        "height": img.height(),
        "frame": "pixels; origin at the top-left corner of the top-left pixel; x right, y down",
        "score": best.score,
        "joints": detection_json(best)["joints"],
        "confidence": detection_json(best)["confidence"],
        "best": detection_json(best),
        "others": dets.all[1..].iter().map(detection_json).collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&doc).map_err(|e| CliError(format!("JSON encoding failed: {e}")))?;
    sketchbody::fsutil::write_atomic(&a.out, text.as_bytes())?;
    if let Some(path) = &a.overlay {
        let mut png = Vec::new();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut png),
            &overlay(&img, best),
            img.width() as u32,
            img.height() as u32,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| CliError(format!("{}: PNG encoding failed: {e}", path.display())))?;
        sketchbody::fsutil::write_atomic(path, &png)?;
    }
    println!("score {:.3}, {} figure(s); joints written to {}", best.score, dets.all.len(), a.out.display());
    Ok(())
}

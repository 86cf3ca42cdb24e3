//! `sketchbody-lab make-dataset N --seed S --out DIR`: N synthetic sketches in parallel (rayon).
//! Sample `i` is rendered from the seed `sample_seed(S, i)`, so the result does not depend on
//! the number of threads; samples whose three files exist are skipped (resumable), and each file
//! is written to a temporary name and renamed, so an interrupted run leaves no half-written
//! sample. Layout: docs/dataset.md. `--views side[,back]` makes turnarounds: each sample also
//! drawn from the side (the front camera turned +90° about the body's vertical) and the back,
//! the same body, pose and drawing style, as `STEM_LABEL.png` with each view's truth in the
//! sample's JSON (`views`, as the Blender set's).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use rayon::prelude::*;
use sketchbody::body::Gender;
use sketchbody::fsutil::write_atomic;
use sketchbody::image::{save_png, GrayImage};
use sketchbody::render::sketch::truth::{sample_complete, sample_seed, write_sample, ViewTruth};
use sketchbody::render::sketch::{CameraAngles, Sketch, SketchRenderer, SketchRequest};
use sketchbody::skeleton::Joints3;
use sketchbody::view::ViewLabel;

use crate::render_sketch::{parse_size, renderer};
use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab make-dataset`.
#[derive(clap::Args)]
pub struct Args {
    /// Number of samples.
    n: usize,
    /// Dataset seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output folder (created when missing).
    #[arg(long)]
    out: PathBuf,
    /// Image size: N or WxH pixels.
    #[arg(long, default_value = "512")]
    size: String,
    /// Folder of mocap clips (default as in render-sketch).
    #[arg(long)]
    mocap: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Also write a contact sheet of the first 24 samples (6 × 4, half size) to this PNG.
    #[arg(long)]
    contact_sheet: Option<PathBuf>,
    /// Turnarounds: each sample also drawn from these views (side, side_left, back), comma-separated.
    #[arg(long, value_delimiter = ',', value_parser = parse_view)]
    views: Vec<ViewLabel>,
}

/// Parses a `--views` label (not the front: every sample is drawn from the front).
fn parse_view(text: &str) -> Result<ViewLabel, String> {
    match ViewLabel::parse(text) {
        Ok(ViewLabel::Front) => Err("the front view is every sample's own; give side, side_left or back".into()),
        Ok(l) => Ok(l),
        Err(e) => Err(e.to_string()),
    }
}

/// `s` drawn again from each of `views` (the same body, pose and style; the front camera turned
/// about the body's vertical by each label's yaw), each view's image written into `dir` as
/// `STEM_LABEL.png` and its truth added to `s.truth.views`.
fn add_views(
    r: &SketchRenderer,
    req: &SketchRequest,
    s: &mut Sketch,
    views: &[ViewLabel],
    dir: &Path,
    stem: &str,
) -> Result<(), CliError> {
    let gender = Gender::parse(&s.truth.gender)?;
    let joints: Joints3 = std::array::from_fn(|k| s.truth.joints3d[k]);
    let front = s.truth.camera.angles;
    for &label in views {
        let mut yaw = front.yaw_deg + label.yaw_deg();
        if yaw > 180.0 {
            yaw -= 360.0;
        }
        let vreq = SketchRequest {
            gender: Some(gender),
            shape_weights: Some(s.truth.shape_weights.clone()),
            joints: Some(joints),
            camera: Some(CameraAngles { yaw_deg: yaw, ..front }),
            style: Some(s.truth.style.clone()),
            ..req.clone()
        };
        let v = r.render(&vreq)?;
        let image = format!("{stem}_{}.png", label.name());
        let img = GrayImage::from_vec(v.truth.width, v.truth.height, v.pixels)?;
        save_png(&img.view(), &dir.join(&image))?;
        s.truth.views.push(ViewTruth {
            label: label.name().into(),
            yaw_deg: label.yaw_deg(),
            image,
            joints2d: v.truth.joints2d,
            visible: v.truth.visible,
            camera: v.truth.camera,
        });
    }
    Ok(())
}

/// Tiles the first (up to) 24 sample images of `dir`, halved, 6 to a row, into a gray PNG.
fn contact_sheet(dir: &std::path::Path, n: usize, out: &std::path::Path) -> Result<(), CliError> {
    let count = n.min(24);
    let imgs = (0..count)
        .map(|i| sketchbody::image::load_image(&dir.join(format!("{}.png", stem(i)))))
        .collect::<Result<Vec<_>, _>>()?;
    let (tw, th) = imgs.iter().fold((1, 1), |(w, h), im| (w.max(im.width() / 2), h.max(im.height() / 2)));
    let cols = count.min(6);
    let rows = count.div_ceil(6);
    let gap = 4;
    let (w, h) = (cols * (tw + gap) + gap, rows * (th + gap) + gap);
    let mut px = vec![96u8; w * h];
    for (k, im) in imgs.iter().enumerate() {
        let (ox, oy) = (gap + (k % 6) * (tw + gap), gap + (k / 6) * (th + gap));
        let (iw, src) = (im.width(), im.as_bytes());
        for y in 0..im.height() / 2 {
            for x in 0..iw / 2 {
                let s: u32 = [(0, 0), (1, 0), (0, 1), (1, 1)]
                    .iter()
                    .map(|&(a, b)| src[(2 * y + b) * iw + 2 * x + a] as u32)
                    .sum();
                px[(oy + y) * w + ox + x] = ((s + 2) / 4) as u8;
            }
        }
    }
    let img = sketchbody::image::GrayImage::from_vec(w, h, px)?;
    sketchbody::image::save_png(&img.view(), out)?;
    Ok(())
}

/// File stem of sample `i`.
pub fn stem(i: usize) -> String {
    format!("{i:06}")
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let (width, height) = parse_size(&a.size)?;
    if a.n == 0 || a.n > 10_000_000 {
        return Err(CliError(format!("N = {}: expected 1..=10000000 samples", a.n)));
    }
    std::fs::create_dir_all(&a.out)
        .map_err(|e| CliError(format!("{}: cannot create the output folder: {e}", a.out.display())))?;
    // The manifest doubles as the check that the folder is writable.
    let manifest = serde_json::json!({
        "format": "sketchbody-dataset-1", "samples": a.n, "seed": a.seed, "width": width, "height": height,
        "sample_seed": "splitmix64(splitmix64(seed) ^ index)", "version": sketchbody::VERSION,
        "views": a.views.iter().map(|v| v.name()).collect::<Vec<_>>(),
    });
    write_atomic(&a.out.join("dataset.json"), manifest.to_string().as_bytes())?;
    let r = renderer(a.mocap.as_deref())?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.unwrap_or(0))
        .build()
        .map_err(|e| CliError(format!("thread pool: {e}")))?;
    let todo: Vec<usize> = (0..a.n).filter(|&i| !sample_complete(&a.out, &stem(i))).collect();
    let skipped = a.n - todo.len();
    let done = AtomicUsize::new(0);
    let t0 = std::time::Instant::now();
    let last_draw = Mutex::new(0.0f64);
    let progress = |finished: usize| {
        let el = t0.elapsed().as_secs_f64();
        let mut last = last_draw.lock().unwrap_or_else(|p| p.into_inner());
        if finished < todo.len() && el - *last < 0.2 {
            return;
        }
        *last = el;
        let frac = finished as f64 / todo.len().max(1) as f64;
        let bar: String = (0..30).map(|k| if (k as f64) < frac * 30.0 { '#' } else { '.' }).collect();
        let rate = finished as f64 / el.max(1e-9);
        let eta = (todo.len() - finished) as f64 / rate.max(1e-9);
        eprint!("\r[{bar}] {finished}/{} {rate:.1}/s eta {eta:.0} s ", todo.len());
        let _ = std::io::stderr().flush();
    };
    let result: Result<(), CliError> = pool.install(|| {
        todo.par_iter().try_for_each(|&i| {
            let req = SketchRequest::random(sample_seed(a.seed, i as u64), width);
            let req = SketchRequest { width, height, ..req };
            let mut s = r.render(&req).map_err(|e| CliError(format!("sample {i}: {e}")))?;
            add_views(&r, &req, &mut s, &a.views, &a.out, &stem(i))
                .map_err(|e| CliError(format!("sample {i}: {}", e.0)))?;
            write_sample(&a.out, &stem(i), &s)?;
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok(())
        })
    });
    eprintln!();
    result?;
    if let Some(cs) = &a.contact_sheet {
        contact_sheet(&a.out, a.n, cs)?;
    }
    let el = t0.elapsed().as_secs_f64();
    println!(
        "{}: {} samples written, {skipped} already complete, {:.1} s ({:.2} sketches/s on {} threads)",
        a.out.display(),
        todo.len(),
        el,
        todo.len() as f64 / el.max(1e-9),
        pool.current_num_threads()
    );
    Ok(())
}

//! Training crops for fine-tuning the BlazePose landmark network on drawings (issue 15,
//! `scripts/finetune-blazepose.sh`): every crop is taken and preprocessed exactly as the
//! landmark backend does at inference (`detect::landmark::crop::crop_tensor`, OpenCV-quantised
//! bilinear resampling with white padding, then `prep::lighten_drawing`), and comes with the
//! true joints in crop pixels and the shipped network's own outputs on it (for distillation).
//!
//! Images (never PARSE photos 81–305, never the benchmark's stylisations):
//! - `sketches` rendered sketches of seed `seed` (512²), half plain, half in a random art style
//!   (`render::sketch::art`);
//! - PARSE training photos 1–80, plain and through the three training filters
//!   (`render::photo_npr`), each also mirrored;
//! - 40 text and 40 clutter pages (`render::stylise::negative_page`, seeds from `seed`): no
//!   joints, distillation only.
//!
//! Crops per image: an upright ROI around the ink box (its larger side × U(1.05, 1.6), centre
//! shifted by up to 8 % of the side), as the first pass and its retries take them; for figures an
//! upright ROI around the true joints' box (× U(1.15, 1.7)), and a second-pass-like ROI: centred
//! on the hips' midpoint, rotated so that hips → neck points up (± 0.12 rad), side 2.5 × the
//! largest hips-to-joint distance × 1.15 × U(0.9, 1.1) (MediaPipe's alignment ROI around the
//! body's circle).
//!
//! Output in OUT: `crops.u8` (N × 256 × 256 × 3 bytes, round(255 v) of the network's input),
//! `meta.f32` (N × 244 little-endian f32: kind, image index, 15 × (x, y) joints in crop px,
//! 15 joint weights (1 inside the crop or near it, 0 otherwise or no figure), 195 landmark values
//! and the pose flag of the embedded network on the exact f32 crop), `README.txt`.
//! Kinds: 0 plain sketch, 1 art sketch, 2 photo, 3 filtered photo, 4 negative page.
//!
//! `cargo run --release --example landmark_finetune_data -- PARSE_DIR OUT SKETCHES SEED`

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use sketchbody::body::BodyModel;
use sketchbody::detect::joints::parse_to_canonical;
use sketchbody::detect::landmark::crop::{crop_tensor, INPUT_SIDE};
use sketchbody::detect::landmark::roi::ink_box;
use sketchbody::detect::landmark::{prep, LandmarkNet, Roi};
use sketchbody::image::RgbImage;
use sketchbody::render::sketch::art::ArtStyle;
use sketchbody::render::sketch::truth::sample_seed;
use sketchbody::render::sketch::{SketchRenderer, SketchRequest};
use sketchbody::skeleton::{joint, MIRROR, NUM_JOINTS};
use sketchbody_lab::detect::parse_eval::read_labels;
use sketchbody_lab::render::photo_npr::{photo_npr, PhotoNpr};
use sketchbody_lab::render::stylise::{negative_page, NegativePage};

/// Last PARSE photo used: 81–100 are the validation photos, 101–305 the test split.
const LAST_PHOTO: usize = 80;
/// f32 values per crop in `meta.f32`.
const META: usize = 2 + 3 * NUM_JOINTS + 195 + 1;

/// One source image: pixels, true joints (None for a page without a figure), kind.
struct Source {
    image: RgbImage,
    joints: Option<[[f64; 2]; NUM_JOINTS]>,
    kind: u8,
    seed: u64,
}

fn gray_rgb(px: &[u8], w: usize, h: usize) -> Result<RgbImage, sketchbody::Error> {
    RgbImage::from_vec(w, h, px.iter().flat_map(|&v| [v; 3]).collect())
}

/// `img` flipped left-right and its joints mirrored (x → w − x, sides swapped).
fn mirrored(
    img: &RgbImage,
    j: &[[f64; 2]; NUM_JOINTS],
) -> Result<(RgbImage, [[f64; 2]; NUM_JOINTS]), sketchbody::Error> {
    let (w, h) = (img.width(), img.height());
    let src = img.as_bytes();
    let mut px = Vec::with_capacity(src.len());
    for y in 0..h {
        for x in (0..w).rev() {
            px.extend_from_slice(&src[3 * (y * w + x)..3 * (y * w + x) + 3]);
        }
    }
    let m = std::array::from_fn(|k| [w as f64 - j[MIRROR[k]][0], j[MIRROR[k]][1]]);
    Ok((RgbImage::from_vec(w, h, px)?, m))
}

/// Image point `p` in crop px of `roi` (the inverse of `Roi::to_image`, × 256).
fn to_crop(roi: &Roi, p: [f64; 2]) -> [f64; 2] {
    let (s, c) = roi.rotation.sin_cos();
    let (dx, dy) = ((p[0] - roi.cx) / roi.size, (p[1] - roi.cy) / roi.size);
    let n = INPUT_SIDE as f64;
    [(c * dx + s * dy + 0.5) * n, (-s * dx + c * dy + 0.5) * n]
}

/// Upright square ROI around box `b`, side × `scale`, centre shifted by `shift` of the side.
fn box_roi(b: [f64; 4], scale: f64, shift: [f64; 2]) -> Roi {
    let side = (b[2] - b[0]).max(b[3] - b[1]).max(8.0) * scale;
    Roi {
        cx: 0.5 * (b[0] + b[2]) + shift[0] * side,
        cy: 0.5 * (b[1] + b[3]) + shift[1] * side,
        size: side,
        rotation: 0.0,
    }
}

/// The ROIs of one image (see the module notes).
fn rois(src: &Source, rng: &mut ChaCha8Rng) -> Vec<Roi> {
    let mut out = Vec::new();
    let shift = |rng: &mut ChaCha8Rng| [rng.random_range(-0.08..0.08), rng.random_range(-0.08..0.08)];
    if let Some(b) = ink_box(&src.image.view()) {
        let s = rng.random_range(1.05..1.6);
        out.push(box_roi(b, s, shift(rng)));
    }
    if let Some(j) = &src.joints {
        let (mut b, pelvis) = ([f64::MAX, f64::MAX, f64::MIN, f64::MIN], j[joint::PELVIS]);
        for p in j {
            b = [b[0].min(p[0]), b[1].min(p[1]), b[2].max(p[0]), b[3].max(p[1])];
        }
        let s = rng.random_range(1.15..1.7);
        out.push(box_roi(b, s, shift(rng)));
        let r = j.iter().map(|p| (p[0] - pelvis[0]).hypot(p[1] - pelvis[1])).fold(0.0, f64::max) * 1.15;
        let (ux, uy) = (j[joint::NECK][0] - pelvis[0], j[joint::NECK][1] - pelvis[1]);
        let up_angle = ux.atan2(-uy) + rng.random_range(-0.12..0.12);
        let scale_point = [pelvis[0] + r * up_angle.sin(), pelvis[1] - r * up_angle.cos()];
        if let Ok(mut roi) = Roi::from_alignment(pelvis, scale_point) {
            roi.size *= rng.random_range(0.9..1.1);
            out.push(roi);
        }
    }
    out
}

/// Crops of one source: bytes and meta rows.
fn crops_of(net: &LandmarkNet, src: &Source, index: usize) -> Result<(Vec<u8>, Vec<f32>), sketchbody::Error> {
    let mut rng = ChaCha8Rng::seed_from_u64(src.seed);
    let (mut bytes, mut meta) = (Vec::new(), Vec::new());
    for roi in rois(src, &mut rng) {
        let mut t = crop_tensor(&src.image.view(), &roi);
        prep::lighten_drawing(&mut t);
        bytes.extend(t.iter().map(|&v| (v * 255.0).round().clamp(0.0, 255.0) as u8));
        let raw = net.run(t)?;
        meta.push(src.kind as f32);
        meta.push(index as f32);
        let n = INPUT_SIDE as f64;
        let (mut xy, mut wt) = (Vec::new(), Vec::new());
        for k in 0..NUM_JOINTS {
            match &src.joints {
                Some(j) => {
                    let c = to_crop(&roi, j[k]);
                    let inside = c.iter().all(|&v| (-0.1 * n..=1.1 * n).contains(&v));
                    xy.extend(c.map(|v| v as f32));
                    wt.push(if inside { 1.0 } else { 0.0 });
                }
                None => {
                    xy.extend([0.0, 0.0]);
                    wt.push(0.0);
                }
            }
        }
        meta.extend(xy);
        meta.extend(wt);
        meta.extend(raw.landmarks.iter().flatten());
        meta.push(raw.pose_flag);
    }
    Ok((bytes, meta))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [parse, out, n_sketches, seed] = args.as_slice() else {
        return Err("usage: landmark_finetune_data PARSE_DIR OUT SKETCHES SEED".into());
    };
    let (parse, out) = (PathBuf::from(parse), PathBuf::from(out));
    let (n_sketches, seed): (usize, u64) = (n_sketches.parse()?, seed.parse()?);
    std::fs::create_dir_all(&out)?;
    let net = LandmarkNet::embedded()?;
    let renderer = SketchRenderer::new(Arc::new(BodyModel::embedded()?), None)?;
    let t0 = std::time::Instant::now();

    // Sources, made lazily per index so that memory stays small.
    let labels = read_labels(&parse.join("labels.csv"))?;
    let photos: Vec<(usize, [[f64; 2]; NUM_JOINTS])> = (1..=LAST_PHOTO)
        .map(|n| {
            let name = format!("im{n:04}.jpg");
            let l = labels.iter().find(|l| l.image == name).ok_or(format!("no label for {name}"))?;
            let (j, _) = parse_to_canonical(&l.joints, &[1.0; 14]);
            Ok((n, j.xy.map(|p| [p[0] + 0.5, p[1] + 0.5])))
        })
        .collect::<Result<_, String>>()?;
    let n_photo_sources = photos.len() * 4 * 2;
    let n_neg = 80;
    let total = n_sketches + n_photo_sources + n_neg;
    let make = |i: usize| -> Result<Vec<Source>, sketchbody::Error> {
        let s = sample_seed(seed, i as u64);
        if i < n_sketches {
            let req = SketchRequest::random(s, 512);
            let art = i % 2 == 1;
            let sk = if art {
                let style = ArtStyle::random(&mut ChaCha8Rng::seed_from_u64(s ^ 0xA57));
                renderer.render_art(&req, &style)?
            } else {
                renderer.render(&req)?
            };
            let j: [[f64; 2]; NUM_JOINTS] = std::array::from_fn(|k| sk.truth.joints2d[k]);
            return Ok(vec![Source {
                image: gray_rgb(&sk.pixels, 512, 512)?,
                joints: Some(j),
                kind: art as u8,
                seed: s,
            }]);
        }
        let i2 = i - n_sketches;
        if i2 < n_photo_sources {
            let (n, j) = photos[i2 / 8];
            let (variant, mirror) = ((i2 % 8) / 2, i2 % 2 == 1);
            let img = sketchbody::image::load_rgb_image(&parse.join("images").join(format!("im{n:04}.jpg")))?;
            let img = if variant == 0 {
                img
            } else {
                let f = PhotoNpr::ALL[variant - 1];
                gray_rgb(
                    &photo_npr(&img.view(), f, sample_seed(seed ^ 0x5041_5253, (n * 16 + variant) as u64))?,
                    img.width(),
                    img.height(),
                )?
            };
            let (img, j) = if mirror { mirrored(&img, &j)? } else { (img, j) };
            return Ok(vec![Source { image: img, joints: Some(j), kind: if variant == 0 { 2 } else { 3 }, seed: s }]);
        }
        let k = i - n_sketches - n_photo_sources;
        let kind = if k.is_multiple_of(2) { NegativePage::Text } else { NegativePage::Clutter };
        let page = negative_page(kind, 512, 512, seed.wrapping_mul(7919) + k as u64)?;
        Ok(vec![Source { image: page, joints: None, kind: 4, seed: s }])
    };
    let done = std::sync::atomic::AtomicUsize::new(0);
    let parts: Vec<(Vec<u8>, Vec<f32>)> = (0..total)
        .into_par_iter()
        .map(|i| {
            let mut bytes = Vec::new();
            let mut meta = Vec::new();
            for src in make(i)? {
                let (b, m) = crops_of(&net, &src, i)?;
                bytes.extend(b);
                meta.extend(m);
            }
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if d.is_multiple_of(100) {
                eprintln!("{d}/{total} images, {:.0} s", t0.elapsed().as_secs_f64());
            }
            Ok((bytes, meta))
        })
        .collect::<Result<_, sketchbody::Error>>()?;
    let mut crops = std::io::BufWriter::new(std::fs::File::create(out.join("crops.u8"))?);
    let mut meta = std::io::BufWriter::new(std::fs::File::create(out.join("meta.f32"))?);
    let mut n = 0;
    for (b, m) in &parts {
        crops.write_all(b)?;
        for v in m {
            meta.write_all(&v.to_le_bytes())?;
        }
        n += m.len() / META;
    }
    crops.flush()?;
    meta.flush()?;
    write_readme(&out, n, n_sketches, seed)?;
    println!("{n} crops of {total} images in {:.0} s -> {}", t0.elapsed().as_secs_f64(), out.display());
    Ok(())
}

fn write_readme(out: &Path, n: usize, sketches: usize, seed: u64) -> std::io::Result<()> {
    std::fs::write(
        out.join("README.txt"),
        format!(
            "{n} crops (examples/landmark_finetune_data.rs): {sketches} sketches of seed {seed} (odd ones in art styles), \
             PARSE photos 1-{LAST_PHOTO} plain/sobel/charcoal/marker x mirrored, 40 text + 40 clutter pages.\n\
             crops.u8: N x 256 x 256 x 3; meta.f32: N x {META} (kind, image, 15x2 joints crop px, 15 weights, 195 teacher, flag)\n"
        ),
    )
}

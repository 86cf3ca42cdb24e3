//! Contact sheet of the detector's training looks, for people to look at: a rendered sketch
//! plain and in art styles (`render::sketch::art`), and PARSE *training* photos through the
//! training filters (`render::photo_npr`).
//!
//! `cargo run --release --example art_sheet [OUT.png] [SEED]` (default `docs/img/art-styles.png`,
//! seed 3); needs `../shared/data/parse/images`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use sketchbody::body::BodyModel;
use sketchbody::image::{load_rgb_image, save_png, RgbImage};
use sketchbody::render::sketch::art::{ArtStyle, Build, Fill};
use sketchbody::render::sketch::{SketchRenderer, SketchRequest};
use sketchbody_lab::render::photo_npr::{photo_npr, PhotoNpr};
use sketchbody_lab::render::stylise::contact_sheet;

const TILE: usize = 256;
const GAP: usize = 6;

fn gray_rgb(px: &[u8], w: usize, h: usize) -> Result<RgbImage, sketchbody::Error> {
    RgbImage::from_vec(w, h, px.iter().flat_map(|&v| [v; 3]).collect())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(args.next().unwrap_or_else(|| "docs/img/art-styles.png".into()));
    let seed: u64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(3);
    let r = SketchRenderer::new(Arc::new(BodyModel::embedded()?), None)?;
    let art =
        |fill, thick_ink, masses, build, textured_paper| ArtStyle { fill, thick_ink, masses, build, textured_paper };
    let styles = [
        art(Fill::Lines, true, true, Build::Natural, false),
        art(Fill::Flat, true, false, Build::Chibi, false),
        art(Fill::Cel, false, true, Build::Heroic, false),
        art(Fill::ScreenTone, false, true, Build::Natural, false),
        art(Fill::Watercolour, false, false, Build::Natural, true),
    ];
    let mut rows: Vec<Vec<RgbImage>> = Vec::new();
    for k in 0..2 {
        let req = SketchRequest::random(seed + k, TILE);
        let mut row = vec![gray_rgb(&r.render(&req)?.pixels, TILE, TILE)?];
        for s in &styles {
            row.push(gray_rgb(&r.render_art(&req, s)?.pixels, TILE, TILE)?);
        }
        rows.push(row);
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/parse/images");
    let mut row = Vec::new();
    for name in ["im0005.jpg", "im0040.jpg"] {
        let photo = load_rgb_image(&root.join(name))?;
        row.push(photo.clone());
        for f in PhotoNpr::ALL {
            row.push(gray_rgb(&photo_npr(&photo.view(), f, seed)?, photo.width(), photo.height())?);
        }
    }
    rows.push(row);
    let sheet = contact_sheet(&rows, TILE, GAP)?;
    save_png(&sheet.view(), &out)?;
    println!("{}: {}x{}, {} bytes", out.display(), sheet.width(), sheet.height(), std::fs::metadata(&out)?.len());
    Ok(())
}

//! Contact sheet of the proxy benchmark's stylisations, for people to look at: three PARSE test
//! photos, each as the original and in the three styles (XDoG ink, pencil hatching, flat colour),
//! and the three kinds of figure-free page below them (`render::stylise::contact_sheet`).
//!
//! `cargo run --release --example stylise_sheet [OUT.png] [SEED]` (default
//! `docs/img/stylised-parse.png`, seed 1); needs `../shared/data/parse/images`.

use std::path::{Path, PathBuf};

use sketchbody::image::{load_rgb_image, save_png, RgbImage};
use sketchbody_lab::render::stylise::{contact_sheet, negative_page, stylise, NegativePage, Stylisation};

/// Tile side, pixels; images are centred in their tile on a gray background.
const TILE: usize = 208;
const GAP: usize = 6;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(args.next().unwrap_or_else(|| "docs/img/stylised-parse.png".into()));
    let seed: u64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(1);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/parse/images");
    let mut rows: Vec<Vec<RgbImage>> = Vec::new();
    for name in ["im0101.jpg", "im0151.jpg", "im0201.jpg"] {
        let photo = load_rgb_image(&root.join(name))?;
        let mut row = vec![photo.clone()];
        for style in Stylisation::ALL {
            row.push(stylise(&photo.view(), style, seed)?);
        }
        rows.push(row);
    }
    rows.push(NegativePage::ALL.iter().map(|&k| negative_page(k, TILE, TILE, seed)).collect::<Result<_, _>>()?);
    let sheet = contact_sheet(&rows, TILE, GAP)?;
    save_png(&sheet.view(), &out)?;
    println!("{}: {}x{}, {} bytes", out.display(), sheet.width(), sheet.height(), std::fs::metadata(&out)?.len());
    Ok(())
}

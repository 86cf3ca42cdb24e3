//! Contact sheet of the proxy benchmark's stylisations, for people to look at: three PARSE test
//! photos, each as the original and in the three styles (XDoG ink, pencil hatching, flat colour),
//! and the three kinds of figure-free page below them. Pixels are stored with 5 bits a channel
//! so the PNG stays small.
//!
//! `cargo run --release --example stylise_sheet [OUT.png] [SEED]` (default
//! `docs/img/stylised-parse.png`, seed 1); needs `../shared/data/parse/images`.

use std::path::{Path, PathBuf};

use sketchbody::image::{load_rgb_image, RgbImage};
use sketchbody::render::stylise::{negative_page, save_rgb_png, stylise, NegativePage, Stylisation};

/// Tile side, pixels; images are centred in their tile on a gray background.
const TILE: usize = 208;
const GAP: usize = 6;
const BACKGROUND: u8 = 200;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(args.next().unwrap_or_else(|| "docs/img/stylised-parse.png".into()));
    let seed: u64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(1);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/parse/images");
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
    let cols = rows.iter().map(Vec::len).max().unwrap_or(1);
    let (w, h) = (cols * (TILE + GAP) + GAP, rows.len() * (TILE + GAP) + GAP);
    let mut data = vec![BACKGROUND; w * h * 3];
    for (r, row) in rows.iter().enumerate() {
        for (c, img) in row.iter().enumerate() {
            let (iw, ih) = (img.width().min(TILE), img.height().min(TILE));
            let x0 = GAP + c * (TILE + GAP) + (TILE - iw) / 2;
            let y0 = GAP + r * (TILE + GAP) + (TILE - ih) / 2;
            for y in 0..ih {
                let src = &img.as_bytes()[y * img.width() * 3..][..iw * 3];
                data[((y0 + y) * w + x0) * 3..][..iw * 3].copy_from_slice(src);
            }
        }
    }
    // Five bits a channel keep the file small (paper grain compresses badly) and look the same.
    data.iter_mut().for_each(|v| *v = (*v & !7) | (*v >> 5));
    save_rgb_png(&RgbImage::from_vec(w, h, data)?, &out)?;
    println!("{}: {w}x{h}, {} bytes", out.display(), std::fs::metadata(&out)?.len());
    Ok(())
}

//! `sketchbody-lab stylise IN OUT --style xdog|pencil|flat [--seed S]`: a photo or drawing turned into
//! one of the real-drawing proxy benchmark's styles (ink, pencil, flat colour), as an RGB PNG.

use std::path::PathBuf;

use sketchbody::image::load_rgb_image;
use sketchbody::image::save_png;
use sketchbody_lab::render::stylise::{stylise, Stylisation};

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab stylise`.
#[derive(clap::Args)]
pub struct Args {
    /// Input image (PNG or JPEG).
    input: PathBuf,
    /// Output image (RGB PNG of the input's size).
    output: PathBuf,
    /// Style: xdog (ink lines), pencil (pencil outlines and hatching), flat (flat colours).
    #[arg(long, value_parser = parse_style)]
    style: Stylisation,
    /// Seed of the style's random strokes and colour clustering.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

fn parse_style(s: &str) -> Result<Stylisation, String> {
    s.parse().map_err(|e: sketchbody::Error| e.to_string())
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let img = load_rgb_image(&a.input)?;
    let out = stylise(&img.view(), a.style, a.seed)?;
    save_png(&out.view(), &a.output)?;
    Ok(())
}

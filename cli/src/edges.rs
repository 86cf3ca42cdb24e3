//! `sketchbody edges IN OUT`: Canny edges (optionally after a Gaussian blur) as a PNG.

use std::path::PathBuf;

use sketchbody::image::{canny, gaussian_blur, load_image, save_png, CannyParams};

use crate::CliError;

/// Arguments of `sketchbody edges`.
#[derive(clap::Args)]
pub struct Args {
    /// Input image (PNG or JPEG; colour is converted to gray).
    input: PathBuf,
    /// Output edge map (PNG, 255 on edges).
    output: PathBuf,
    /// Lower hysteresis threshold (either order is accepted).
    #[arg(long, default_value_t = 50.0)]
    low: f64,
    /// Upper hysteresis threshold.
    #[arg(long, default_value_t = 150.0)]
    high: f64,
    /// Sobel aperture: 3, 5 or 7.
    #[arg(long, default_value_t = 3)]
    aperture: u32,
    /// Use the L2 gradient magnitude instead of L1.
    #[arg(long)]
    l2: bool,
    /// Gaussian pre-smoothing with this sigma in pixels (none by default).
    #[arg(long)]
    blur: Option<f64>,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let img = load_image(&a.input)?;
    let img = match a.blur {
        Some(sigma) => gaussian_blur(&img.view(), sigma)?,
        None => img,
    };
    let params = CannyParams { threshold1: a.low, threshold2: a.high, aperture: a.aperture, l2_gradient: a.l2 };
    let edges = canny(&img.view(), &params)?;
    save_png(&edges.view(), &a.output)?;
    Ok(())
}

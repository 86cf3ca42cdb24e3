//! `sketchbody-lab negative-page OUT --kind blank|text|clutter [--size WxH] [--seed S]`: a page
//! without a figure (blank paper, notes, doodles or a UI mock-up) for the "no figure" rate.

use std::path::PathBuf;

use sketchbody::image::save_png;
use sketchbody_lab::render::stylise::{negative_page, NegativePage};

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab negative-page`.
#[derive(clap::Args)]
pub struct Args {
    /// Output image (RGB PNG).
    output: PathBuf,
    /// Kind of page: blank, text or clutter.
    #[arg(long, value_parser = parse_kind)]
    kind: NegativePage,
    /// Page size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512", value_parser = parse_size)]
    size: (usize, usize),
    /// Seed of every random choice on the page.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

fn parse_kind(s: &str) -> Result<NegativePage, String> {
    s.parse().map_err(|e: sketchbody::Error| e.to_string())
}

fn parse_size(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("{s:?} is not WIDTHxHEIGHT (e.g. 512x512)");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    Ok((w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?))
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let page = negative_page(a.kind, a.size.0, a.size.1, a.seed)?;
    save_png(&page.view(), &a.output)?;
    Ok(())
}

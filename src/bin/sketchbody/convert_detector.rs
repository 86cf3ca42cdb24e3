//! `sketchbody convert-detector IN OUT`: rewrites a detector model (PARSE JSON or binary) in the
//! project's binary format (`docs/formats.md`, "Detector model").

use std::path::PathBuf;

use sketchbody::detect::Model;

use crate::CliError;

/// Arguments of `sketchbody convert-detector`.
#[derive(clap::Args)]
pub struct Args {
    /// Input model: the PARSE JSON or a binary model.
    input: PathBuf,
    /// Output binary model (`.skbd`), written atomically.
    output: PathBuf,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let m = Model::load_any(&a.input)?;
    m.save(&a.output)?;
    println!("{} parts, {} filters written to {}", m.parts.len(), m.filters.len(), a.output.display());
    Ok(())
}

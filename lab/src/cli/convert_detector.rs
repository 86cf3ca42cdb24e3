//! `sketchbody-lab convert-detector IN OUT [--threshold T]`: rewrites a detector model (PARSE JSON
//! or binary) in the project's binary format (`docs/formats.md`, "Detector model"), optionally
//! with a recalibrated default detection threshold.

use std::path::PathBuf;

use sketchbody::detect::Model;

use sketchbody_cli::CliError;

/// Arguments of `sketchbody-lab convert-detector`.
#[derive(clap::Args)]
pub struct Args {
    /// Input model: the PARSE JSON or a binary model.
    input: PathBuf,
    /// Output binary model (`.skbd`), written atomically.
    output: PathBuf,
    /// New default detection threshold stored in the model (score units; below it a sketch
    /// has "no figure"). Default: keep the input's.
    #[arg(long, allow_hyphen_values = true)]
    threshold: Option<f64>,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let mut m = Model::load_any(&a.input)?;
    if let Some(t) = a.threshold {
        if !t.is_finite() {
            return Err(CliError(format!("--threshold {t}: must be finite")));
        }
        m.thresh = t;
    }
    m.save(&a.output)?;
    println!(
        "{} parts, {} filters, threshold {} written to {}",
        m.parts.len(),
        m.filters.len(),
        m.thresh,
        a.output.display()
    );
    Ok(())
}

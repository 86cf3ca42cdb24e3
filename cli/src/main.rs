//! The `sketchbody` command-line tool: the artist's commands. One file per subcommand (in the
//! crate's library, shared with the research tool `sketchbody-lab`). Errors print one line
//! (`sketchbody: ...`) naming the file and the reason, and exit with status 1 (2 for usage
//! errors, from clap).

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use sketchbody_cli::{body, default_sigpipe, detect, edges, exit_code, one_malloc_arena, pose, run};

#[derive(Parser)]
#[command(name = "sketchbody", version, about = "Concept sketch of a human character to a rigged 3-D base mesh")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The main job: sketch (+ 2-D joints) to a rigged, posed 3-D body and its report.
    Run(Box<run::Args>),
    /// 2-D pose (15 joints with confidences) of the figure in a sketch, with a detector model.
    Detect(detect::Args),
    /// 3-D pose and weak-perspective camera from 2-D joints (JSON in, JSON out).
    Pose(pose::Args),
    /// A body of the embedded shape model, optionally posed, as .glb or .obj (+ preview PNG).
    Body(body::Args),
    /// Canny edge map of an image (bit-exact with OpenCV's cv::Canny).
    Edges(edges::Args),
}

fn main() -> ExitCode {
    default_sigpipe();
    one_malloc_arena();
    let result = match Cli::parse().command {
        Command::Run(a) => run::run(*a),
        Command::Detect(a) => detect::run(a),
        Command::Pose(a) => pose::run(a),
        Command::Body(a) => body::run(a),
        Command::Edges(a) => edges::run(a),
    };
    exit_code("sketchbody", result)
}

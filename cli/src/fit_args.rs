//! Shape-fit options shared by `run` and `run-dataset` (defaults are `FitOptions::default()`).

use sketchbody::body::skin::SkinMethod;
use sketchbody::fit::{FitOptions, MatchScore};
use sketchbody::pipeline::{DetectedJointsFit, PipelineOptions};

use crate::CliError;

/// Fit options on the command line.
#[derive(clap::Args, Clone, Debug)]
pub struct FitArgs {
    /// Match score: paper (eq. 7), filled (IoU with the filled figure) or chamfer (default).
    #[arg(long, default_value = "chamfer")]
    pub score: String,
    /// Seed of every random step of the fit.
    #[arg(long, default_value_t = FitOptions::default().seed)]
    pub seed: u64,
    /// Samples per SIR iteration (S).
    #[arg(long, default_value_t = FitOptions::default().samples, value_parser = crate::ranges::count(2..=100_000))]
    pub samples: usize,
    /// The first SIR iteration draws this many times `--samples`, halved at each resampling
    /// down to `--samples` (1 = a flat population).
    #[arg(long, default_value_t = FitOptions::default().initial_factor, value_parser = crate::ranges::count(1..=64))]
    pub initial_factor: usize,
    /// Most SIR iterations (T).
    #[arg(long, default_value_t = FitOptions::default().max_iterations, value_parser = crate::ranges::count(1..=1000))]
    pub iterations: usize,
    /// Transition step in standard deviations (Σ = diag(s² λ)).
    #[arg(long, default_value_t = FitOptions::default().transition_scale, value_parser = crate::ranges::real(0.0, f64::MAX, true))]
    pub transition_scale: f64,
    /// Likelihood temperature of the non-paper scores.
    #[arg(long, default_value_t = FitOptions::default().temperature, value_parser = crate::ranges::real(0.0, f64::MAX, true))]
    pub temperature: f64,
    /// Longest raster side of the fit, pixels.
    #[arg(long, default_value_t = FitOptions::default().raster_max_side, value_parser = crate::ranges::count(16..=4096))]
    pub raster_side: usize,
    /// Convergence tolerance, standard deviations.
    #[arg(long, default_value_t = FitOptions::default().tolerance, value_parser = crate::ranges::real(0.0, f64::MAX, true))]
    pub tolerance: f64,
    /// Weight of the 2-D joint term (score loses this × mean projected-joint distance, raster px).
    #[arg(long, default_value_t = FitOptions::default().joint_weight, value_parser = crate::ranges::real(0.0, f64::MAX, false))]
    pub joint_weight: f64,
    /// PCA dimensions searched (default: all 10 of a gendered space's prior, 5 for the both-sexes
    /// space).
    #[arg(long)]
    pub dims: Option<usize>,
    /// Dual-quaternion skinning instead of linear blend skinning.
    #[arg(long)]
    pub dqs: bool,
    /// Stretch bones so the joints land exactly on the estimated 3-D joints (in the fit and the
    /// posed outputs; the rest mesh keeps the shape's bone lengths).
    #[arg(long)]
    pub retarget: bool,
    /// Give every fit sample its own camera scale and translation, refitted to its own posed
    /// joints vs the 2-D joints, so the size comes from the shape (`--sample-camera false`: the
    /// pipeline's camera for every sample).
    #[arg(long, default_value_t = FitOptions::default().sample_camera, action = clap::ArgAction::Set)]
    pub sample_camera: bool,
    /// The character's rest height in metres, when known (character sheets carry one): the
    /// fitted mesh is scaled to it.
    #[arg(long, value_parser = crate::ranges::real(0.1, 10.0, false))]
    pub height: Option<f64>,
    /// Also search bone-length factors (legs, arms, shoulders, head, torso) with this prior
    /// standard deviation of each log factor (0 = off).
    #[arg(long, default_value_t = FitOptions::default().proportion_sd, value_parser = crate::ranges::real(0.0, 0.5, false))]
    pub proportion_sd: f64,
    /// Centre the bone factors' prior on their closed-form estimate from the 2-D joints' bone
    /// lengths, the estimated pose and camera (`--estimate-proportions true|false`).
    #[arg(long, default_value_t = FitOptions::default().estimate_proportions, action = clap::ArgAction::Set)]
    pub estimate_proportions: bool,
    /// Clothing-robust chamfer cap, raster pixels: silhouette boundary pixels inside the
    /// sketch's outer outline cost at most this (12 = the plain chamfer).
    #[arg(long, default_value_t = FitOptions::default().inside_cap, value_parser = crate::ranges::real(0.0, f64::MAX, true))]
    pub inside_cap: f64,
    /// Keep the pose solver's camera instead of refitting its scales and translation to the
    /// gender's mean skeleton before the fit.
    #[arg(long)]
    pub keep_pose_scale: bool,
    /// Weight of BlazePose's relative joint depths in the 3-D pose step's choices when the joints
    /// are detected (px² of depth residual per px² of reprojection; 0 = off: the pose step's
    /// learned depths instead, as for given joints).
    #[arg(long, default_value_t = PipelineOptions::default().depth_hint, value_parser = crate::ranges::real(0.0, 100.0, false))]
    pub depth_hint: f64,
    /// Weight of the pose step's learned joint depths (`PoseOptions::depth_prior`; 0 = off).
    #[arg(long, default_value_t = sketchbody::pose::PoseOptions::default().depth_prior, value_parser = crate::ranges::real(0.0, sketchbody::pose::options::MAX_DEPTH_PRIOR, false))]
    pub depth_prior: f64,
    /// Straighten the arms and legs drawn straight that the 3-D pose step bent by at most 60° in
    /// depth (`PoseOptions::straight_limbs`): for figures drawn standing or posing with straight
    /// limbs. Off by default (on unseen motion it straightens truly bent limbs too).
    #[arg(long)]
    pub straight_limbs: bool,
    /// With detected joints, the fit's joint weight is multiplied by this (0..=1).
    #[arg(long, default_value_t = DetectedJointsFit::default().joint_weight_scale, value_parser = crate::ranges::real(0.0, 1.0, false))]
    pub detected_joint_weight_scale: f64,
    /// With detected joints, search bone-length factors in the fit too (`--proportion-sd`);
    /// default: the fit keeps the pose step's proportions.
    #[arg(long, default_value_t = DetectedJointsFit::default().proportions, action = clap::ArgAction::Set)]
    pub detected_proportions: bool,
    /// With detected joints, the pose step reads BlazePose's own joints and depths when they
    /// agree with the chosen figure.
    #[arg(long, default_value_t = DetectedJointsFit::default().landmark_pose, action = clap::ArgAction::Set)]
    pub landmark_pose: bool,
    /// With detected joints and automatic gender, fit the gendered space the detected-joints
    /// gender classifier picks (`--detected-classifier-gender false`: the both-sexes fit).
    #[arg(long, default_value_t = DetectedJointsFit::default().classifier_gender, action = clap::ArgAction::Set)]
    pub detected_classifier_gender: bool,
    /// With automatic gender, the fit's prior mass on the male end is the gender classifier's
    /// probability from the sketch's joints and outline (`--gender-evidence true|false`; false:
    /// 0.5 on each end).
    #[arg(long, default_value_t = PipelineOptions::default().gender_evidence, action = clap::ArgAction::Set)]
    pub gender_evidence: bool,
    /// With automatic gender, a fixed prior mass on the male end (0..=1; overrides
    /// --gender-evidence).
    #[arg(long, value_parser = crate::ranges::real(0.0, 1.0, false))]
    pub male_prior: Option<f64>,
    /// With automatic gender, choose the gender by the classifier (hard choice) and fit that
    /// gender's space (`--classify-gender true|false`).
    #[arg(long, default_value_t = PipelineOptions::default().classify_gender, action = clap::ArgAction::Set)]
    pub classify_gender: bool,
    /// PCA dimensions of the two gendered fits that decide the gender with --classify-gender
    /// (default: the spaces' 96%-energy dimension, 4); the chosen gender is refitted with
    /// --dims when those differ.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub gender_decision_dims: Option<u32>,
    /// Pairs of deciding fits (fit seeds --seed, --seed + 1, …) whose score margins are
    /// averaged with --classify-gender.
    #[arg(long, default_value_t = PipelineOptions::default().gender_decision_seeds as u32, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub gender_decision_seeds: u32,
    /// Samples per iteration of each deciding fit with --classify-gender (default: --samples).
    #[arg(long, value_parser = crate::ranges::count(2..=100_000))]
    pub gender_decision_samples: Option<usize>,
    /// Most SIR iterations of each deciding fit with --classify-gender (`0`: --iterations).
    #[arg(long, default_value_t = PipelineOptions::default().gender_decision_iterations.unwrap_or(0), value_parser = crate::ranges::count(0..=1000))]
    pub gender_decision_iterations: usize,
    /// When the height is unknown (no --height) and the joints are given, calibrate the fitted
    /// body: map a gendered fit's shape weights, then scale it to the calibrated height (the fit
    /// alone draws the body toward the prior's mean; `--calibrate-fit false` keeps the fit's
    /// weights and height; detected joints keep them anyway).
    #[arg(long, default_value_t = PipelineOptions::default().calibrate_fit, action = clap::ArgAction::Set)]
    pub calibrate_fit: bool,
}

/// Parses a match-score name.
pub fn parse_score(s: &str) -> Result<MatchScore, CliError> {
    match s.to_ascii_lowercase().as_str() {
        "paper" => Ok(MatchScore::Paper),
        "filled" | "filled-iou" => Ok(MatchScore::FilledIou),
        "chamfer" => Ok(MatchScore::Chamfer),
        "chamfer2" | "two-sided" => Ok(MatchScore::TwoSidedChamfer),
        _ => Err(CliError(format!("--score {s:?}: expected paper, filled, chamfer or chamfer2"))),
    }
}

/// Short name of a match score (the CLI's spelling).
pub fn score_name(s: MatchScore) -> &'static str {
    match s {
        MatchScore::Paper => "paper",
        MatchScore::FilledIou => "filled",
        MatchScore::Chamfer => "chamfer",
        MatchScore::TwoSidedChamfer => "chamfer2",
    }
}

impl FitArgs {
    /// The fit's adjustments for detected joints these arguments describe.
    pub fn detected(&self) -> DetectedJointsFit {
        DetectedJointsFit {
            joint_weight_scale: self.detected_joint_weight_scale,
            proportions: self.detected_proportions,
            landmark_pose: self.landmark_pose,
            classifier_gender: self.detected_classifier_gender,
        }
    }

    /// The 3-D pose step's options these arguments describe (the defaults but the learned depths'
    /// weight and the straight limbs).
    pub fn pose_options(&self) -> sketchbody::pose::PoseOptions {
        sketchbody::pose::PoseOptions {
            depth_prior: self.depth_prior,
            straight_limbs: self.straight_limbs,
            ..sketchbody::pose::PoseOptions::default()
        }
    }

    /// The pipeline's options these arguments describe, with the fit options `fit` (from
    /// [`FitArgs::options`]) and `mean_shape`; the gender and the joints' source stay defaults.
    pub fn pipeline_options(&self, fit: FitOptions, mean_shape: bool) -> PipelineOptions {
        PipelineOptions {
            fit,
            mean_shape,
            keep_pose_scale: self.keep_pose_scale,
            depth_hint: self.depth_hint,
            pose: self.pose_options(),
            detected: self.detected(),
            gender_evidence: self.gender_evidence,
            classify_gender: self.classify_gender,
            gender_decision_dims: self.gender_decision_dims.map(|d| d as usize),
            gender_decision_seeds: self.gender_decision_seeds as usize,
            gender_decision_samples: self.gender_decision_samples,
            gender_decision_iterations: (self.gender_decision_iterations > 0)
                .then_some(self.gender_decision_iterations),
            calibrate_fit: self.calibrate_fit,
            ..PipelineOptions::default()
        }
    }

    /// The fit options these arguments describe.
    pub fn options(&self) -> Result<FitOptions, CliError> {
        Ok(FitOptions {
            samples: self.samples,
            initial_factor: self.initial_factor,
            max_iterations: self.iterations,
            dims: self.dims,
            transition_scale: self.transition_scale,
            score: parse_score(&self.score)?,
            temperature: self.temperature,
            raster_max_side: self.raster_side,
            tolerance: self.tolerance,
            seed: self.seed,
            skinning: if self.dqs { SkinMethod::DualQuaternion } else { SkinMethod::Linear },
            retarget: self.retarget,
            joint_weight: self.joint_weight,
            sample_camera: self.sample_camera,
            height: self.height,
            proportion_sd: self.proportion_sd,
            inside_cap: self.inside_cap,
            estimate_proportions: self.estimate_proportions,
            male_prior: self.male_prior,
        })
    }
}

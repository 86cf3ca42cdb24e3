//! `sketchbody pose JOINTS2D.json --out POSE3D.json`: 3-D pose and camera from 2-D joints
//! (formats in docs/formats.md).

use std::path::PathBuf;

use sketchbody::export::joints2d::load_joints2d;
use sketchbody::export::pose3d::pose3d_json;
use sketchbody::fsutil::write_atomic;
use sketchbody::pose::options::RotationTarget;
use sketchbody::pose::{dict_io, estimate_pose, PoseOptions};

use crate::CliError;

/// Arguments of `sketchbody pose`.
#[derive(clap::Args)]
pub struct Args {
    /// Input 2-D joints (JSON, format "sketchbody-joints2d").
    input: PathBuf,
    /// Output 3-D pose (JSON, format "sketchbody-pose3d").
    #[arg(long)]
    out: PathBuf,
    /// Pose dictionary file (default: the embedded one).
    #[arg(long)]
    dictionary: Option<PathBuf>,
    /// Relative limb-length tolerance κ (0 = equality).
    #[arg(long, default_value_t = PoseOptions::default().kappa, value_parser = crate::ranges::real(0.0, 10.0, false))]
    kappa: f64,
    /// Pull of the camera rotation toward --alpha-target, α in [0, 1] (eq. 4).
    #[arg(long, default_value_t = PoseOptions::default().alpha, value_parser = crate::ranges::real(0.0, 1.0, false))]
    alpha: f64,
    /// What α pulls toward: level (the pitch to 0, default) or identity (the paper's eq. 4).
    #[arg(long, default_value = PoseOptions::default().alpha_target.name())]
    alpha_target: String,
    /// Fit independent sx and sy (eq. 1) instead of one scale for both image axes.
    #[arg(long)]
    free_scales: bool,
    /// Most bases to choose (0..=32).
    #[arg(long, default_value_t = PoseOptions::default().max_bases, value_parser = crate::ranges::count(0..=32))]
    max_bases: usize,
    /// Stop adding bases at this reprojection RMS, pixels.
    #[arg(long, default_value_t = PoseOptions::default().tolerance, value_parser = crate::ranges::real(0.0, 1.0e4, false))]
    tolerance: f64,
    /// Weight prior, metres (0 = the paper's eq. 3).
    #[arg(long, default_value_t = PoseOptions::default().prior, value_parser = crate::ranges::real(0.0, 1.0, false))]
    prior: f64,
    /// Nearest-neighbour starts (exemplar poses tried; 0 = start from the mean pose, the paper).
    #[arg(long, default_value_t = PoseOptions::default().starts, value_parser = crate::ranges::count(0..=32))]
    starts: usize,
    /// Limb candidates for recomposing exemplar starts (0 = whole exemplars).
    #[arg(long, default_value_t = PoseOptions::default().limb_candidates, value_parser = crate::ranges::count(0..=4096))]
    limb_candidates: usize,
    /// Blend temperature of the exemplar starts' hypotheses, px² per joint (0 = the best one).
    #[arg(long, default_value_t = PoseOptions::default().blend, value_parser = crate::ranges::real(0.0, 1.0e6, false))]
    blend: f64,
    /// Free-joint refinement: expected 2-D joint error, metres at the figure's scale (0 = off).
    #[arg(long, default_value_t = PoseOptions::default().joint_noise, value_parser = crate::ranges::real(0.0, 1.0, false))]
    joint_noise: f64,
    /// Skip the final Levenberg–Marquardt refinement.
    #[arg(long)]
    no_refine: bool,
    /// Keep the dictionary's proportions instead of estimating the drawn ones (factors 1).
    #[arg(long)]
    fixed_proportions: bool,
    /// Switch off the standing prior (upright torso, feet under the pelvis on one ground plane).
    #[arg(long)]
    no_standing_prior: bool,
    /// Switch off the knee limits (knees bent backwards flipped in depth).
    #[arg(long)]
    no_knee_limits: bool,
    /// The fixed prior on the drawn proportions instead of the learned one (assets/factor_prior.json).
    #[arg(long)]
    no_factor_prior: bool,
    /// Weight of the learned joints' depths (assets/factor_prior.json) where the solver chooses
    /// between readings; 0 = off.
    #[arg(long, default_value_t = PoseOptions::default().depth_prior, value_parser = crate::ranges::real(0.0, sketchbody::pose::options::MAX_DEPTH_PRIOR, false))]
    depth_prior: f64,
    /// Spread (m) of the free-joint step's pull of every bone's depth change toward the learned
    /// depths'; 0 = off.
    #[arg(long, default_value_t = PoseOptions::default().learned_depth_sd, value_parser = crate::ranges::real(0.0, 1.0, false))]
    learned_depth_sd: f64,
    /// Relative spread of each bone's length in the free-joint step (log-normal about the
    /// estimate's, left and right pulled equal); 0 = the estimate's lengths kept.
    #[arg(long, default_value_t = PoseOptions::default().bone_length_sd, value_parser = crate::ranges::real(0.0, 1.0, false))]
    bone_length_sd: f64,
    /// Spread (m) of the free-joint step's pull of the knees', ankles', elbows' and wrists'
    /// depths toward the solve's; 0 = that of the other joints (0.02 m).
    #[arg(long, default_value_t = PoseOptions::default().limb_depth_sd, value_parser = crate::ranges::real(0.0, 1.0, false))]
    limb_depth_sd: f64,
    /// Weight of the learned bend prior of the knees and elbows (assets/factor_prior.json) in
    /// the free-joint step; 0 = off.
    #[arg(long, default_value_t = PoseOptions::default().bend_prior, value_parser = crate::ranges::real(0.0, sketchbody::pose::options::MAX_BEND_PRIOR, false))]
    bend_prior: f64,
    /// Straighten the arms and legs drawn straight that the solve bent by at most 60° in depth
    /// (the drawn proportions absorb the bend): for figures drawn standing or posing with
    /// straight limbs. Off by default (on unseen motion it straightens truly bent limbs too).
    #[arg(long)]
    straight_limbs: bool,
}

/// Runs the command.
pub fn run(a: Args) -> Result<(), CliError> {
    let joints = load_joints2d(&a.input)?;
    let dict = match &a.dictionary {
        Some(p) => dict_io::read(p)?,
        None => dict_io::embedded()?,
    };
    let opts = PoseOptions {
        kappa: a.kappa,
        alpha: a.alpha,
        alpha_target: RotationTarget::parse(&a.alpha_target)?,
        equal_scales: !a.free_scales,
        max_bases: a.max_bases,
        tolerance: a.tolerance,
        refine: !a.no_refine,
        prior: a.prior,
        starts: a.starts,
        limb_candidates: a.limb_candidates,
        blend: a.blend,
        joint_noise: a.joint_noise,
        proportions: !a.fixed_proportions,
        standing_prior: !a.no_standing_prior,
        knee_limits: !a.no_knee_limits,
        factor_prior: !a.no_factor_prior,
        depth_prior: a.depth_prior,
        learned_depth_sd: a.learned_depth_sd,
        bone_length_sd: a.bone_length_sd,
        limb_depth_sd: a.limb_depth_sd,
        bend_prior: a.bend_prior,
        straight_limbs: a.straight_limbs,
    };
    let est = estimate_pose(&dict, &joints, &opts)?;
    let doc = pose3d_json(&est, &dict, &opts);
    let mut bytes = serde_json::to_vec_pretty(&doc).map_err(|e| CliError(e.to_string()))?;
    bytes.push(b'\n');
    write_atomic(&a.out, &bytes)?;
    println!("{}: {} bases, reprojection RMS {:.3} px", a.out.display(), est.bases.len(), est.rms);
    Ok(())
}

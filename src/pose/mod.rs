//! Step 2 of the paper (§II-B, eqs. 1–4): 3-D joints and a weak-perspective camera from 2-D
//! joints, by projected matching pursuit over a dictionary of action-specific basis poses.
//!
//! - [`motion`]: motion tables (canonical-joint CSV), pose normalisation, mirroring.
//! - [`alternatives`]: the ranked depth readings of an estimate and the flip of one limb's depth.
//! - [`bend_prior`]: the learned prior on the bends of the knees and elbows.
//! - [`blend`]: posterior-mean blend of the exemplar starts' hypotheses.
//! - [`depth_hint`]: relative joint depths from an image cue, weighing the solver's choices.
//! - [`dictionary`]: the basis-pose dictionary (eq. 2) and its learning (per-action PCA).
//! - [`exemplar`]: the nearest-neighbour starts (exemplar poses ranked by an affine camera fit).
//! - [`figure`]: drawn proportions as unknowns (per-group bone-length factors).
//! - [`factor_prior`]: the learned prior on the factors (a network from the 2-D joints).
//! - [`mlp`]: the small network the learned prior uses.
//! - [`dict_io`]: the dictionary's binary file format and the embedded default.
//! - [`plausibility`]: the standing prior and the knee limits of the free-joint step.
//! - [`options`]: solver options (κ, α, basis count, tolerance).
//! - [`problem`]: a validated 2-D input with the model of eq. (1)–(3).
//! - [`qcls`]: least squares under the two-sided limb-length constraint of eq. (3).
//! - [`camera_fit`]: the camera step (SVD of M, eq. 4 blend, projection onto SO(3)).
//! - [`pursuit`]: the matching pursuit driver ([`estimate_pose`]).
//! - [`refine`]: the joint Levenberg–Marquardt refinement with the constraint kept exactly.
//! - [`joint_fit`]: the free-joint refinement (joints leave the dictionary's span; bone lengths
//!   under a prior, knee and elbow bends under the learned one).
//! - [`straighten`]: limbs drawn straight kept straight in depth (the last step).
//!
//! Units: 3-D joints are metres of a 1.75 m person (every pose is normalised to that stature,
//! see [`motion::normalize_pose`]); 2-D joints are image pixels (origin top-left, y down).

pub mod alternatives;
pub mod bend_prior;
pub mod blend;
pub mod camera_fit;
pub mod depth_hint;
pub mod dict_io;
pub mod dictionary;
pub mod exemplar;
pub mod factor_prior;
pub mod mlp;
pub mod figure;
pub mod joint_fit;
pub mod motion;
pub mod options;
pub mod plausibility;
pub mod problem;
pub mod pursuit;
pub mod qcls;
pub mod refine;
pub mod straighten;
pub mod views;

pub use alternatives::{flip_limb, pick_alternative, Alternative, FlipStatus, Limb};
pub use depth_hint::DepthHint;
pub use dictionary::{Dictionary, LearnParams};
pub use options::PoseOptions;
pub use pursuit::{estimate_pose, estimate_pose_hinted, estimate_pose_with_factor_prior, PoseEstimate};
pub use refine::refine_pose;

//! Learning and measuring the pose step's assets.
//!
//! - [`bvh`]: BVH reader with a joint-name mapping for CMU-, Mixamo- and Rokoko-style rigs.
//! - [`learn`]: clip selection and provenance for learning the dictionary from folders and BVH files.
//! - [`factor_train`]: training the learned factor prior on projected mocap with random cameras
//!   and proportions.
//! - [`metrics`]: MPJPE, PA-MPJPE, limb direction errors.
//! - [`mlp_train`]: training the factor prior's small network (Adam).

pub mod bvh;
pub mod factor_train;
pub mod learn;
pub mod metrics;
pub mod mlp_train;

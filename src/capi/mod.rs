//! The C ABI: the only module with `extern "C"` functions and raw pointers.
//!
//! Conventions (see `docs/c-api.md`): every function returns an [`skb_status`] (0 = OK) and
//! writes results through trailing out-parameters; on failure a thread-local message is
//! available from [`skb_last_error_message`] and no output is written. Every entry point checks
//! its pointers and sizes and runs inside a panic boundary, so a Rust panic becomes
//! `SKB_ERR_PANIC` instead of aborting the host. Only the three text getters (`skb_version`,
//! `skb_status_str`, `skb_last_error_message`) return a pointer instead of a status, and the
//! `skb_*_free` functions return nothing (freeing NULL is a no-op).
#![allow(non_camel_case_types)]

#[macro_use]
mod panic;
#[macro_use]
mod ptr;
mod body;
mod detect;
mod error;
mod fit;
mod image;
mod mesh_ops;
mod pipeline;
mod pose;
mod sketch;
mod status;
mod version;

pub use body::{
    skb_context, skb_context_default_dim, skb_context_free, skb_context_new, skb_context_num_components, skb_mesh,
    skb_mesh_copy_faces, skb_mesh_copy_joints, skb_mesh_copy_shape_weights, skb_mesh_copy_skin_weights,
    skb_mesh_copy_triangles, skb_mesh_copy_vertices, skb_mesh_face_count, skb_mesh_free, skb_mesh_gender,
    skb_mesh_joint_count, skb_mesh_new_from_shape, skb_mesh_shape_weight_count, skb_mesh_skin_weight_count,
    skb_mesh_vertex_count, SKB_GENDER_FEMALE, SKB_GENDER_MALE, SKB_MAX_INFLUENCES, SKB_NUM_BONES, SKB_NUM_JOINTS,
};
pub use detect::{
    skb_detect, skb_detect_options, skb_detect_options_free, skb_detect_options_new, skb_detect_options_set_scales,
    skb_detect_options_set_threshold, skb_detector, skb_detector_detect, skb_detector_free, skb_detector_new_from_file,
};
pub use error::skb_last_error_message;
pub use fit::{
    skb_fit_options, skb_fit_options_free, skb_fit_options_new, skb_fit_options_set_dims,
    skb_fit_options_set_estimate_proportions, skb_fit_options_set_gender, skb_fit_options_set_height,
    skb_fit_options_set_inside_cap, skb_fit_options_set_iterations, skb_fit_options_set_joint_weight,
    skb_fit_options_set_proportion_sd, skb_fit_options_set_raster_side, skb_fit_options_set_sample_camera,
    skb_fit_options_set_samples, skb_fit_options_set_score, skb_fit_options_set_seed, skb_fit_options_set_skinning,
    skb_fit_options_set_temperature, skb_fit_options_set_tolerance, skb_fit_options_set_transition_scale,
    skb_fit_shape, skb_progress_fn, SKB_GENDER_AUTO, SKB_SCORE_CHAMFER, SKB_SCORE_FILLED_IOU, SKB_SCORE_PAPER,
    SKB_SCORE_TWO_SIDED_CHAMFER, SKB_SKIN_DUAL_QUATERNION, SKB_SKIN_LINEAR,
};
pub use image::{skb_canny, skb_gaussian_blur, skb_image, SKB_MAX_IMAGE_SIDE};
pub use mesh_ops::{
    skb_camera, skb_mesh_copy_posed_joints, skb_mesh_copy_posed_vertices, skb_mesh_pose, skb_mesh_rasterize,
    skb_mesh_write_glb, skb_mesh_write_obj, skb_mesh_write_preview, skb_rasterize_triangles, skb_rasterizer,
    skb_rasterizer_free, skb_rasterizer_new, SKB_POSE_DUAL_QUATERNION, SKB_POSE_RETARGET,
};
pub use pipeline::{
    skb_gray_image, skb_gray_image_free, skb_gray_image_load, skb_gray_image_view, skb_result, skb_result_camera,
    skb_result_copy_faces, skb_result_copy_joints3d, skb_result_copy_skin_weights, skb_result_copy_vertices,
    skb_result_counts, skb_result_evidence, skb_result_free, skb_result_gender, skb_result_gender_value,
    skb_result_joints2d, skb_result_mesh, skb_result_score, skb_result_shape_weights, skb_run_pipeline,
    SKB_JOINTS_ESTIMATED, SKB_JOINTS_POSED, SKB_JOINTS_REST,
};
pub use pose::{
    skb_estimate_pose, skb_joints2d, skb_pose3d, skb_pose_dictionary, skb_pose_dictionary_basis,
    skb_pose_dictionary_bone_lengths, skb_pose_dictionary_free, skb_pose_dictionary_load, skb_pose_dictionary_mean,
    skb_pose_dictionary_new_default, skb_pose_dictionary_num_bases, skb_pose_options, skb_pose_options_free,
    skb_pose_options_new, skb_pose_options_set_alpha, skb_pose_options_set_blend, skb_pose_options_set_joint_noise,
    skb_pose_options_set_kappa, skb_pose_options_set_limb_candidates, skb_pose_options_set_max_bases,
    skb_pose_options_set_prior, skb_pose_options_set_refine, skb_pose_options_set_starts,
    skb_pose_options_set_tolerance, skb_pose_refine, SKB_POSE_DIM, SKB_POSE_MAX_BASES,
};
pub use sketch::{
    skb_render_sketch, skb_sketch_options, skb_sketch_options_free, skb_sketch_options_new,
    skb_sketch_options_set_camera, skb_sketch_options_set_style, SKB_SKETCH_STYLE_CLEAN, SKB_SKETCH_STYLE_RANDOM,
};
pub use status::{skb_status, skb_status_str};
pub use version::{skb_version, SKB_VERSION_MAJOR, SKB_VERSION_MINOR, SKB_VERSION_PATCH, SKB_VERSION_STRING};

pub(crate) use error::{clear_last_error as error_reset, fail as error_fail};
pub(crate) use panic::panic_status;

//! The 3-D pose step (paper §II-B): `skb_pose_dictionary`, `skb_pose_options`,
//! `skb_pose3d_estimate`, the fixed-basis refinement `skb_pose3d_refine`, and the estimate handle
//! `skb_pose_estimate` with its ranked depth readings and `skb_pose_estimate_flip_limb`.

use std::ffi::c_char;
use std::path::Path;

use nalgebra::Matrix3;

use sketchbody_core::camera::WeakPerspective;
use sketchbody_core::error::Error;
use sketchbody_core::pose::dictionary::POSE_DIM;
use sketchbody_core::pose::options::RotationTarget;
use sketchbody_core::pose::{
    dict_io, estimate_pose, flip_limb, pick_alternative, refine_pose, Dictionary, FlipStatus, Limb, PoseEstimate,
    PoseOptions,
};
use sketchbody_core::skeleton::{Joints2, NUM_BONES};

use super::error::fail;
use super::ptr::*;
use super::status::skb_status;

/// Length of a pose vector (x, y, z of each joint in canonical order).
pub const SKB_POSE_DIM: u32 = 45;
/// Size of the basis arrays of `skb_pose3d` (the most bases a pose may use).
pub const SKB_POSE_MAX_BASES: u32 = 32;
/// `skb_pose_options_set_alpha_target`: α pulls toward the identity (the paper's eq. 4).
pub const SKB_ALPHA_TARGET_IDENTITY: u32 = 0;
/// `skb_pose_options_set_alpha_target`: α pulls the pitch toward 0 (yaw and roll kept; default).
pub const SKB_ALPHA_TARGET_LEVEL: u32 = 1;

const _: () = assert!(
    SKB_POSE_DIM as usize == POSE_DIM && SKB_POSE_MAX_BASES as usize == sketchbody_core::pose::options::MAX_BASES
);

/// 15 image joints in canonical order (head, neck, r_shoulder, r_elbow, r_wrist, l_shoulder,
/// l_elbow, l_wrist, pelvis, r_hip, r_knee, r_ankle, l_hip, l_knee, l_ankle): pixels, origin at
/// the top-left image corner, y down. Every position must be finite; `visible[j] == 0` marks a
/// joint whose position is only a guess (its residuals are dropped; at least 8 must be visible).
/// Plain data, 256 bytes; its layout is part of the ABI.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct skb_joints2d {
    /// (x, y) of each joint, pixels.
    pub xy: [[f64; 2]; 15],
    /// 1 = known, 0 = missing.
    pub visible: [u8; 15],
    /// Set to 0.
    pub reserved: u8,
}

/// A 3-D pose and its weak-perspective camera: `u = sx (R X)_x + tx`, `v = −sy (R X)_y + ty`.
/// Joints are metres of a 1.75 m person in the model frame (+Y up, +Z toward the viewer when
/// R = I, pelvis at the origin). Plain data, 880 bytes; its layout is part of the ABI.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct skb_pose3d {
    /// (x, y, z) of each joint, metres, canonical order.
    pub joints: [[f64; 3]; 15],
    /// Horizontal scale, pixels per metre.
    pub sx: f64,
    /// Vertical scale, pixels per metre.
    pub sy: f64,
    /// Rotation R, row-major 3 × 3.
    pub r: [f64; 9],
    /// Translation (tx, ty), pixels.
    pub t: [f64; 2],
    /// RMS reprojection error per visible joint, pixels.
    pub rms_px: f64,
    /// (Σ‖X_i − X_j‖² − Σ l²) / Σ l² over the bones: within ±kappa when the constraint holds.
    pub length_excess: f64,
    /// Weight of the prior residuals `prior_weight · weights[k] / sigma_k`, pixels (0 = none).
    pub prior_weight: f64,
    /// Weight of each chosen basis, metres (first `num_bases` entries used, the rest 0).
    pub weights: [f64; 32],
    /// Number of chosen bases, 0..=32.
    pub num_bases: u32,
    /// Dictionary columns of the chosen bases (first `num_bases` entries used).
    pub bases: [u32; 32],
    /// Set to 0.
    pub reserved: u32,
}

const _: () = assert!(std::mem::size_of::<skb_joints2d>() == 256);
const _: () = assert!(std::mem::size_of::<skb_pose3d>() == 880 && std::mem::align_of::<skb_pose3d>() == 8);

/// The basis-pose dictionary (mean pose, bases, bone lengths). Immutable after creation: one
/// dictionary may be used from many threads at once. Free with `skb_pose_dictionary_free`.
pub struct skb_pose_dictionary {
    pub(crate) inner: Dictionary,
}

/// Options of `skb_pose3d_estimate` / `skb_pose3d_refine`. Created with defaults (κ = 0.05 relative,
/// α = 0.8 toward the level target, sx = sy, 4 bases, 0.5 px, refinement on, prior 0.1 m,
/// 12 exemplar starts, 64 limb candidates, blend 30 px², free-joint refinement at 0.014 m).
/// Not synchronised: do not change it
/// while another thread uses it. Free with `skb_pose_options_free`.
pub struct skb_pose_options {
    pub(crate) inner: PoseOptions,
}

fn out_of_range(name: &'static str, detail: String) -> skb_status {
    fail(&sketchbody_core::Error::OutOfRange { name, detail })
}

/// Creates the embedded default dictionary (learned from the DeepMimic clips, see
/// assets/README.md). Thread-safe.
/// @param out receives a new dictionary the caller owns (`skb_pose_dictionary_free`); not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_dictionary_new_default(out: *mut *mut skb_pose_dictionary) -> skb_status {
    unsafe {
        ffi_boundary! {
            let out = try_status!(out_slot(out));
            let inner = try_core!(dict_io::embedded());
            give(out, skb_pose_dictionary { inner })
        }
    }
}

/// Loads a dictionary file (`.skbpd`, docs/formats.md; made by `sketchbody-lab learn-poses`).
/// Magic, version, sizes and checksum are checked. Thread-safe.
/// @param path the file path, NUL-terminated UTF-8.
/// @param out receives a new dictionary the caller owns (`skb_pose_dictionary_free`); not NULL.
/// @return SKB_OK; SKB_ERR_IO when the file cannot be read; SKB_ERR_CORRUPT_DATA when a check
///         fails; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_dictionary_new_from_file(
    path: *const c_char,
    out: *mut *mut skb_pose_dictionary,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let p = try_status!(try_str(path, "path"));
            let out = try_status!(out_slot(out));
            let inner = try_core!(dict_io::read(Path::new(p)));
            give(out, skb_pose_dictionary { inner })
        }
    }
}

/// Frees a dictionary. Do not use it afterwards.
/// @param dict the dictionary to free; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_dictionary_free(dict: *mut skb_pose_dictionary) {
    unsafe { free_box(dict) }
}

/// The number of basis poses K. Thread-safe.
/// @param dict the dictionary, only read.
/// @param out receives K; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_dictionary_basis_count(
    dict: *const skb_pose_dictionary,
    out: *mut usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let d = try_status!(try_ref(dict, "dict"));
            let out = try_status!(try_mut(out, "out"));
            *out = d.inner.num_bases();
            skb_status::SKB_OK
        }
    }
}

/// Copies the mean pose μ. Thread-safe.
/// @param dict the dictionary, only read.
/// @param dst receives 45 values (x, y, z per joint), metres.
/// @param dst_len the element count of `dst`, ≥ 45.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_dictionary_copy_mean(
    dict: *const skb_pose_dictionary,
    dst: *mut f64,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let d = try_status!(try_ref(dict, "dict"));
            try_status!(out_slice(dst, dst_len, POSE_DIM, "dst"))[..POSE_DIM].copy_from_slice(d.inner.mean.as_slice());
            skb_status::SKB_OK
        }
    }
}

/// Copies one basis pose (a unit 45-vector) and its spread. Thread-safe.
/// @param dict the dictionary, only read.
/// @param index the basis, < K.
/// @param dst receives the basis's 45 values.
/// @param dst_len the element count of `dst`, ≥ 45.
/// @param sigma receives the basis's spread σ (metres, used by the weight prior); may be NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `index` ≥ K; SKB_ERR_BUFFER_TOO_SMALL for a short
///         `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_dictionary_copy_basis(
    dict: *const skb_pose_dictionary,
    index: u32,
    dst: *mut f64,
    dst_len: usize,
    sigma: *mut f64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let d = try_status!(try_ref(dict, "dict"));
            if dst.is_null() {
                return null("dst");
            }
            let k = index as usize;
            if k >= d.inner.num_bases() {
                return out_of_range("basis index", format!("{k} is not below {}", d.inner.num_bases()));
            }
            // Short or absurd (over isize::MAX bytes) lengths are refused before anything is written.
            let out = try_status!(out_slice(dst, dst_len, POSE_DIM, "dst"));
            out[..POSE_DIM].copy_from_slice(d.inner.bases.column(k).as_slice());
            write_opt(sigma, d.inner.sigma[k]);
            skb_status::SKB_OK
        }
    }
}

/// Copies the 14 average bone lengths l_ij. Their squares sum to the Σ l² of the length
/// constraint. Thread-safe.
/// @param dict the dictionary, only read.
/// @param dst receives the lengths, metres, bone order of docs/c-api.md.
/// @param dst_len the element count of `dst`, ≥ 14.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_dictionary_copy_bone_lengths(
    dict: *const skb_pose_dictionary,
    dst: *mut f64,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let d = try_status!(try_ref(dict, "dict"));
            try_status!(out_slice(dst, dst_len, NUM_BONES, "dst"))[..NUM_BONES].copy_from_slice(&d.inner.bone_lengths);
            skb_status::SKB_OK
        }
    }
}

/// Creates pose options with the defaults. Thread-safe.
/// @param out receives a new options handle the caller owns (`skb_pose_options_free`); not NULL.
/// @return SKB_OK; SKB_ERR_NULL_POINTER for a NULL `out`.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_new(out: *mut *mut skb_pose_options) -> skb_status {
    unsafe {
        ffi_boundary! {
            let out = try_status!(out_slot(out));
            give(out, skb_pose_options { inner: PoseOptions::default() })
        }
    }
}

/// Frees pose options.
/// @param opts the options to free; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_free(opts: *mut skb_pose_options) {
    unsafe { free_box(opts) }
}

/// Applies `set` to a copy of the options, validates the copy and stores it only if valid.
unsafe fn set_option(opts: *mut skb_pose_options, set: impl FnOnce(&mut PoseOptions)) -> skb_status {
    unsafe {
        let o = try_status!(try_mut(opts, "opts"));
        let mut next = o.inner;
        set(&mut next);
        try_core!(next.validate());
        o.inner = next;
        skb_status::SKB_OK
    }
}

/// Sets κ, the relative limb-length tolerance: |Σ‖X_i − X_j‖² − Σ l²| ≤ κ Σ l² (the paper's
/// κ = 8 CMU units² is about 0.017, see docs/formats.md).
/// @param opts the options, changed.
/// @param kappa κ, in [0, 10] (0 = equality; default 0.05).
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_kappa(opts: *mut skb_pose_options, kappa: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.kappa = kappa) }
    }
}

/// Sets α of eq. (4), the pull of the camera rotation toward its target
/// (`skb_pose_options_set_alpha_target`).
/// @param opts the options, changed.
/// @param alpha α, in [0, 1]. Default 0.8.
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_alpha(opts: *mut skb_pose_options, alpha: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.alpha = alpha) }
    }
}

/// Sets what α pulls the camera rotation toward.
/// @param opts the options, changed.
/// @param target `SKB_ALPHA_TARGET_LEVEL` (default: the fitted rotation with its pitch removed,
///               yaw and roll kept) or `SKB_ALPHA_TARGET_IDENTITY` (the paper's eq. 4).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_alpha_target(opts: *mut skb_pose_options, target: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            let t = match target {
                SKB_ALPHA_TARGET_IDENTITY => RotationTarget::Identity,
                SKB_ALPHA_TARGET_LEVEL => RotationTarget::Level,
                _ => {
                    if opts.is_null() {
                        return null("opts");
                    }
                    return fail(&Error::OutOfRange { name: "alpha_target", detail: format!("{target} (expected 0 identity, 1 level)") });
                }
            };
            set_option(opts, |o| o.alpha_target = t)
        }
    }
}

/// Sets whether the camera fit and the refinement use one scale for both image axes.
/// @param opts the options, changed.
/// @param equal true: sx = sy (default); false: independent sx and sy (eq. 1).
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_equal_scales(opts: *mut skb_pose_options, equal: bool) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.equal_scales = equal) }
    }
}

/// Sets the most bases the pursuit may choose.
/// @param opts the options, changed.
/// @param max_bases 0..=32 (0 = mean pose with a fitted camera; default 4).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE outside the range (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_max_bases(opts: *mut skb_pose_options, max_bases: u32) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.max_bases = max_bases as usize) }
    }
}

/// Sets the stopping tolerance on the reprojection RMS.
/// @param opts the options, changed.
/// @param tolerance_px pixels, in [0, 10000] (default 0.5).
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_tolerance(opts: *mut skb_pose_options, tolerance_px: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.tolerance = tolerance_px) }
    }
}

/// Turns the final Levenberg–Marquardt refinement on or off.
/// @param opts the options, changed.
/// @param refine true: on (default); false: off.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_refine(opts: *mut skb_pose_options, refine: bool) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.refine = refine) }
    }
}

/// Sets the weight prior (see docs).
/// @param opts the options, changed.
/// @param prior_m metres, in [0, 1] (0 = the paper's eq. (3) exactly; default 0.1).
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_prior(opts: *mut skb_pose_options, prior_m: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.prior = prior_m) }
    }
}

/// Sets the number of nearest-neighbour starts: the pursuit runs from each of this many
/// training poses of the dictionary that best explain the 2-D joints and keeps the best result.
/// @param opts the options, changed.
/// @param starts 0..=32 (0 = from the mean pose, as in the paper; default 12).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE outside the range (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_starts(opts: *mut skb_pose_options, starts: u32) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.starts = starts as usize) }
    }
}

/// Sets the limb candidates for recomposing nearest-neighbour starts.
/// @param opts the options, changed.
/// @param count 0..=4096 (0 = whole training poses; default 64).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE outside the range (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_limb_candidates(opts: *mut skb_pose_options, count: u32) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.limb_candidates = count as usize) }
    }
}

/// Sets the blend temperature of the exemplar starts' hypotheses (see docs/benchmarks.md
/// "3-D pose").
/// @param opts the options, changed.
/// @param tau_px2 px² per visible joint, in [0, 1e6] (0 = return the single best hypothesis;
///                default 30).
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_blend(opts: *mut skb_pose_options, tau_px2: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.blend = tau_px2) }
    }
}

/// Sets the free-joint refinement's expected 2-D joint error. After the dictionary fit every
/// joint may then leave the dictionary's span to follow the 2-D joints, bone lengths kept. With
/// it on the returned joints are no longer base + Σ basis · weight of the dictionary's own base
/// pose; `skb_pose3d_refine` still continues from them (see `skb_pose3d_refine`).
/// @param opts the options, changed.
/// @param noise_m metres at the figure's scale (a 1.75 m person), in [0, 1]; 0 turns it off
///                (default 0.014 m, 4 px on a 500-px figure; raise it for rough joints such
///                as detections).
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_joint_noise(opts: *mut skb_pose_options, noise_m: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.joint_noise = noise_m) }
    }
}

/// Sets whether the drawn proportions are estimated with the pose: six per-group bone-length
/// factors (head, torso, shoulders, arms, hips, legs; `skb_pose3d_estimate_figure` returns them)
/// and a second solve on the 2-D joints unstylised by them; the returned joints then have the
/// figure's proportions.
/// @param opts the options, changed.
/// @param on true: on (default); false: off (for `skb_pose3d_refine`: the fixed-basis refinement
///           needs joints = base + Σ basis · weight on the dictionary's skeleton).
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_proportions(opts: *mut skb_pose_options, on: bool) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.proportions = on) }
    }
}

/// Sets the standing prior of the free-joint refinement: for a figure whose 2-D joints show it
/// standing on both feet, an upright torso, the head over the neck and both ankles under the
/// pelvis on one ground plane. Acts only with joint noise > 0.
/// @param opts the options, changed.
/// @param on true: on (default); false: off.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_standing_prior(opts: *mut skb_pose_options, on: bool) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.standing_prior = on) }
    }
}

/// Sets the knee limits of the free-joint refinement: knees bent backwards are flipped in depth
/// (image and bone lengths unchanged). Acts only with joint noise > 0.
/// @param opts the options, changed.
/// @param on true: on (default); false: off.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_knee_limits(opts: *mut skb_pose_options, on: bool) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.knee_limits = on) }
    }
}

/// Sets the straight limbs: the last step straightens every arm and leg drawn straight that the
/// solve bent by at most 60° in depth (the middle joint moves onto the segment between the
/// limb's ends; the ends and the image are kept, the two bones get shorter). For figures drawn
/// standing or posing with straight limbs; on unseen motion it straightens truly bent limbs too
/// (docs/benchmarks.md, "3-D pose").
/// @param opts the options, changed.
/// @param on true: on; false: off (default).
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_straight_limbs(opts: *mut skb_pose_options, on: bool) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.straight_limbs = on) }
    }
}

/// Sets the learned factor prior: the prior on the drawn proportions is predicted from the 2-D
/// joints by the embedded regression (`assets/factor_prior.json`) instead of a fixed spread
/// about the dictionary's proportions. Acts only with the proportions estimated.
/// @param opts the options, changed.
/// @param on true: on (default); false: off.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_factor_prior(opts: *mut skb_pose_options, on: bool) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.factor_prior = on) }
    }
}

/// Sets the weight of the learned joints' depths: where the solver chooses between readings of
/// a near-frontal figure (a limb toward or away from the viewer), the depths predicted from the
/// 2-D joints by the embedded network (`assets/factor_prior.json`) add this many px² of cost per
/// px² of depth disagreement. `skb_pose3d_estimate` always uses them when on; the pipeline
/// replaces them by BlazePose's own depths when it detected the joints with BlazePose.
/// @param opts the options, changed.
/// @param weight in [0, 10] (default 0.05; 0 = off).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE outside [0, 10] (SKB_ERR_NON_FINITE for NaN or
///         infinity; options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_options_set_depth_prior(opts: *mut skb_pose_options, weight: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_option(opts, |o| o.depth_prior = weight) }
    }
}

/// Number of proportion groups of `skb_pose_figure`.
pub const SKB_POSE_GROUPS: u32 = 6;

/// The drawn proportions and plausibility of an estimate (`skb_pose3d_estimate_figure`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
#[allow(non_camel_case_types)]
pub struct skb_pose_figure {
    /// Bone-length factors relative to the dictionary's skeleton: head, torso, shoulders, arms,
    /// hips, legs; each in [0.5, 2]; all 1 with proportions off.
    pub factors: [f64; SKB_POSE_GROUPS as usize],
    /// 1 when a plausible body explains the 2-D joints; 0 when the reprojection RMS exceeds 5%
    /// of the figure's extent or a factor sits at the end of its range (the estimate is still
    /// the best found).
    pub plausible: i32,
    /// Zero.
    pub reserved: i32,
}

const _: () = assert!(SKB_POSE_GROUPS as usize == sketchbody_core::pose::figure::NUM_GROUPS);

/// `skb_pose3d_estimate` that also writes the drawn proportions and the plausibility flag.
/// Thread-safe.
/// @param dict the dictionary, only read.
/// @param joints the 2-D joints, only read.
/// @param opts pose options, only read, or NULL for the defaults.
/// @param out receives the pose and camera; not written on error.
/// @param figure receives the drawn proportions and the plausibility flag; not NULL; not
///               written on error.
/// @return the statuses of `skb_pose3d_estimate`.
#[no_mangle]
pub unsafe extern "C" fn skb_pose3d_estimate_figure(
    dict: *const skb_pose_dictionary,
    joints: *const skb_joints2d,
    opts: *const skb_pose_options,
    out: *mut skb_pose3d,
    figure: *mut skb_pose_figure,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let d = try_status!(try_ref(dict, "dict"));
            let joints = try_status!(try_ref(joints, "joints"));
            let out = try_status!(try_mut(out, "out"));
            let figure = try_status!(try_mut(figure, "figure"));
            let (e, pose) = try_status!(estimate_out(d, joints, opt_ref(opts)));
            *out = pose;
            *figure = skb_pose_figure { factors: e.factors.k, plausible: i32::from(e.plausible), reserved: 0 };
            skb_status::SKB_OK
        }
    }
}

pub(crate) fn joints_in(j: &skb_joints2d) -> Joints2 {
    Joints2 { xy: j.xy, visible: std::array::from_fn(|k| j.visible[k] != 0) }
}

fn pose_out(e: &PoseEstimate, prior_weight: f64) -> skb_pose3d {
    let mut out = skb_pose3d {
        joints: e.joints,
        sx: e.camera.sx,
        sy: e.camera.sy,
        r: std::array::from_fn(|i| e.camera.r[(i / 3, i % 3)]),
        t: e.camera.t,
        rms_px: e.rms,
        length_excess: e.length_excess,
        prior_weight,
        weights: [0.0; 32],
        num_bases: e.bases.len() as u32,
        bases: [0; 32],
        reserved: 0,
    };
    for (k, (&b, &w)) in e.bases.iter().zip(&e.weights).enumerate() {
        out.bases[k] = b as u32;
        out.weights[k] = w;
    }
    out
}

/// The estimate of `skb_pose3d_estimate` / `skb_pose3d_estimate_figure` and its C form (`opts`
/// `None` = the defaults); errors are already recorded for `skb_last_error_message`.
fn estimate_out(
    d: &skb_pose_dictionary,
    joints: &skb_joints2d,
    opts: Option<&skb_pose_options>,
) -> Result<(PoseEstimate, skb_pose3d), skb_status> {
    let j = joints_in(joints);
    let o = opts.map(|o| o.inner).unwrap_or_default();
    let e = estimate_pose(&d.inner, &j, &o).map_err(|err| fail(&err))?;
    let pose = pose_out(&e, prior_weight(&d.inner, &j, &o));
    Ok((e, pose))
}

fn prior_weight(d: &Dictionary, j: &Joints2, o: &PoseOptions) -> f64 {
    sketchbody_core::pose::problem::Problem::new(d, j, o.prior).map(|p| p.prior_w).unwrap_or(0.0)
}

/// Estimates the 3-D pose and camera from 2-D joints: matching pursuit of eq. 3, then the joint
/// refinement if enabled; by default from 12 exemplar starts whose results are blended (see
/// `skb_pose_options_set_starts`), and last the free-joint refinement (see
/// `skb_pose_options_set_joint_noise`). Thread-safe (with distinct `out`); CPU time per pose
/// in docs/benchmarks.md ("3-D pose").
/// @param dict the dictionary, only read.
/// @param joints the 2-D joints, only read.
/// @param opts pose options, only read, or NULL for the defaults.
/// @param out receives the pose and camera; not written on error.
/// @return SKB_OK; SKB_ERR_TOO_FEW_JOINTS (fewer than 15 finite joints or fewer than 8
///         visible); SKB_ERR_COINCIDENT_JOINTS (a bone whose ends coincide);
///         SKB_ERR_DEGENERATE (collinear or tiny figures); SKB_ERR_OUT_OF_RANGE (coordinates
///         beyond ±1e6 px); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose3d_estimate(
    dict: *const skb_pose_dictionary,
    joints: *const skb_joints2d,
    opts: *const skb_pose_options,
    out: *mut skb_pose3d,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let d = try_status!(try_ref(dict, "dict"));
            let joints = try_status!(try_ref(joints, "joints"));
            let out = try_status!(try_mut(out, "out"));
            *out = try_status!(estimate_out(d, joints, opt_ref(opts))).1;
            skb_status::SKB_OK
        }
    }
}

/// The fixed-basis refinement alone: runs the joint Levenberg–Marquardt refinement of rotation,
/// sx, sy, t and the weights on `joints`, keeping |length excess| ≤ κ exactly (a start outside
/// the bound is first moved onto it). Use it to re-polish a pose after editing its camera or
/// weights, or to compare with another solver. Thread-safe.
/// @param dict the dictionary, only read.
/// @param joints the 2-D joints, only read.
/// @param opts pose options, only read, or NULL for the defaults.
/// @param start the starting pose, only read: its bases, weights and camera; its base pose is
///              taken as `joints − Σ_k basis_k · weights_k`, i.e. the mean pose or the exemplar
///              start `skb_pose3d_estimate` used, so pass the joints it returned.
/// @param out receives the refined pose; may equal `start`.
/// @return SKB_OK; the errors of `skb_pose3d_estimate`; SKB_ERR_OUT_OF_RANGE for a start with
///         0 or more than 32 bases or a basis index ≥ K; SKB_ERR_NON_FINITE for a non-finite
///         weight or base-pose value; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose3d_refine(
    dict: *const skb_pose_dictionary,
    joints: *const skb_joints2d,
    opts: *const skb_pose_options,
    start: *const skb_pose3d,
    out: *mut skb_pose3d,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let d = try_status!(try_ref(dict, "dict"));
            let j = joints_in(try_status!(try_ref(joints, "joints")));
            let s = *try_status!(try_ref(start, "start"));
            let o = opt_ref(opts).map(|o| o.inner).unwrap_or_default();
            let out = try_status!(try_mut(out, "out"));
            let n = s.num_bases as usize;
            if n == 0 || n > SKB_POSE_MAX_BASES as usize {
                return out_of_range("start->num_bases", format!("{n} is not in 1..=32"));
            }
            let camera = WeakPerspective { sx: s.sx, sy: s.sy, r: Matrix3::from_row_slice(&s.r), t: s.t };
            // The base pose (μ or an exemplar start) is what the joints are without the bases.
            let mut base = sketchbody_core::pose::dictionary::pose_to_vec(&s.joints);
            for (&b, &w) in s.bases[..n].iter().zip(&s.weights[..n]) {
                if b as usize >= d.inner.num_bases() {
                    return out_of_range("start->bases", format!("index {b} is not below {}", d.inner.num_bases()));
                }
                base.axpy(-w, &d.inner.bases.column(b as usize), 1.0);
            }
            let base = sketchbody_core::pose::dictionary::vec_to_pose(base.as_slice());
            let start_est = PoseEstimate {
                joints: s.joints,
                camera,
                bases: s.bases[..n].iter().map(|&b| b as usize).collect(),
                weights: s.weights[..n].to_vec(),
                rms: s.rms_px,
                length_excess: s.length_excess,
                base,
                base_parts: None,
                factors: sketchbody_core::pose::figure::BodyFactors::default(),
                plausible: true,
                alternatives: Vec::new(),
                depth_costs: None,
            };
            let e = try_core!(refine_pose(&d.inner, &j, &o, &start_est));
            *out = pose_out(&e, prior_weight(&d.inner, &j, &o));
            skb_status::SKB_OK
        }
    }
}

/// `SKB_LIMB_*`: a limb bone whose depth can be flipped, the index of `skb_pose_estimate_flip_limb` and of
/// `skb_pose_estimate_copy_alternative_flipped`: right upper arm (shoulder → elbow).
pub const SKB_LIMB_R_UPPER_ARM: u32 = 0;
/// Right forearm (elbow → wrist).
pub const SKB_LIMB_R_FOREARM: u32 = 1;
/// Left upper arm.
pub const SKB_LIMB_L_UPPER_ARM: u32 = 2;
/// Left forearm.
pub const SKB_LIMB_L_FOREARM: u32 = 3;
/// Right thigh (hip → knee).
pub const SKB_LIMB_R_THIGH: u32 = 4;
/// Right shin (knee → ankle).
pub const SKB_LIMB_R_SHIN: u32 = 5;
/// Left thigh.
pub const SKB_LIMB_L_THIGH: u32 = 6;
/// Left shin.
pub const SKB_LIMB_L_SHIN: u32 = 7;
/// Number of limb bones (`SKB_LIMB_*` are below it).
pub const SKB_NUM_LIMBS: u32 = 8;
/// Most alternatives of a pose estimate (the estimate itself included).
pub const SKB_MAX_ALTERNATIVES: u32 = 8;

/// `*outcome` of `skb_pose_estimate_flip_limb` and the re-pose functions: done.
pub const SKB_REPOSE_DONE: u32 = 0;
/// The limb lies in the picture plane (its depth offset is at most 5 % of its length): no
/// depth to flip; nothing changed.
pub const SKB_REPOSE_NO_DEPTH: u32 = 1;
/// A visible moved joint lies outside the sketch; nothing changed.
pub const SKB_REPOSE_JOINT_OUTSIDE_IMAGE: u32 = 2;
/// Two visible moved joints lie on each other (within 1 % of the figure's size); nothing changed.
pub const SKB_REPOSE_JOINTS_COINCIDE: u32 = 3;
/// No plausible body explains the moved joints; nothing changed.
pub const SKB_REPOSE_IMPLAUSIBLE: u32 = 4;

const _: () = assert!(
    SKB_NUM_LIMBS as usize == Limb::ALL.len()
        && SKB_MAX_ALTERNATIVES as usize == sketchbody_core::pose::alternatives::MAX_ALTERNATIVES
        && SKB_LIMB_L_SHIN as usize == Limb::LShin as usize
        && SKB_LIMB_R_THIGH as usize == Limb::RThigh as usize
);

/// A 3-D pose estimate with its ranked depth readings ("alternatives": the first is the estimate
/// itself, the others flip limbs toward or away from the camera, best first; the score is px²,
/// lower = better, see docs/formats.md "3-D pose JSON"). Made by `skb_pose_estimate_new` or
/// `skb_pose_estimate_new_from_result`; free with `skb_pose_estimate_free`. Reading it from several
/// threads at once is safe; `skb_pose_estimate_flip_limb` and `skb_pose_estimate_pick_alternative` change it and must
/// not run while another thread uses it.
pub struct skb_pose_estimate {
    pub(crate) inner: PoseEstimate,
    pub(crate) prior_weight: f64,
}

pub(crate) fn limb_in(limb: u32) -> Result<Limb, skb_status> {
    Limb::from_index(limb as usize)
        .ok_or_else(|| out_of_range("limb", format!("{limb} is not below {SKB_NUM_LIMBS} (SKB_LIMB_*)")))
}

fn alternative_at(e: &PoseEstimate, index: u32) -> Result<&sketchbody_core::pose::Alternative, skb_status> {
    e.alternatives
        .get(index as usize)
        .ok_or_else(|| out_of_range("index", format!("{index} is not below the {} alternatives", e.alternatives.len())))
}

/// `skb_pose3d_estimate` into a new estimate handle that also holds the ranked alternatives.
/// Thread-safe.
/// @param dict the dictionary, only read.
/// @param joints the 2-D joints, only read.
/// @param opts pose options, only read, or NULL for the defaults.
/// @param out receives a new estimate the caller owns (`skb_pose_estimate_free`); untouched on
///            error; not NULL.
/// @return the statuses of `skb_pose3d_estimate`.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_estimate_new(
    dict: *const skb_pose_dictionary,
    joints: *const skb_joints2d,
    opts: *const skb_pose_options,
    out: *mut *mut skb_pose_estimate,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let d = try_status!(try_ref(dict, "dict"));
            let joints = try_status!(try_ref(joints, "joints"));
            let out = try_status!(out_slot(out));
            let (e, pose) = try_status!(estimate_out(d, joints, opt_ref(opts)));
            give(out, skb_pose_estimate { inner: e, prior_weight: pose.prior_weight })
        }
    }
}

/// Frees an estimate. Do not use it afterwards.
/// @param est the estimate to free; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_estimate_free(est: *mut skb_pose_estimate) {
    unsafe { free_box(est) }
}

/// The estimate's current pose and camera: after flips and picks, the chosen reading's joints
/// (the camera, bases and RMS are unchanged by them).
/// @param est the estimate, only read.
/// @param out receives the pose; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_estimate_pose(est: *const skb_pose_estimate, out: *mut skb_pose3d) -> skb_status {
    unsafe {
        ffi_boundary! {
            let e = try_status!(try_ref(est, "est"));
            try_status!(write_out(out, pose_out(&e.inner, e.prior_weight), "out"));
            skb_status::SKB_OK
        }
    }
}

/// The number of alternatives.
/// @param est the estimate, only read.
/// @param out receives 1..=`SKB_MAX_ALTERNATIVES`, or 0 for an estimate without them; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_estimate_alternative_count(
    est: *const skb_pose_estimate,
    out: *mut usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let e = try_status!(try_ref(est, "est"));
            try_status!(write_out(out, e.inner.alternatives.len(), "out"));
            skb_status::SKB_OK
        }
    }
}

/// Copies one alternative's 15 joints and its score. On error nothing is written.
/// @param est the estimate, only read.
/// @param index the alternative, below `skb_pose_estimate_alternative_count`.
/// @param dst receives x, y, z doubles per joint, metres, the frame of `skb_pose3d.joints`.
/// @param dst_len the element count of `dst`, ≥ 45.
/// @param score receives the score (px², lower = better); may be NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `index` ≥ the count; SKB_ERR_BUFFER_TOO_SMALL for a
///         short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_estimate_copy_alternative_joints(
    est: *const skb_pose_estimate,
    index: u32,
    dst: *mut f64,
    dst_len: usize,
    score: *mut f64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let e = try_status!(try_ref(est, "est"));
            let a = try_status!(alternative_at(&e.inner, index));
            let out = try_status!(out_slice(dst, dst_len, 45, "dst"));
            for (o, p) in out.chunks_exact_mut(3).zip(&a.joints) {
                o.copy_from_slice(p);
            }
            write_opt(score, a.score);
            skb_status::SKB_OK
        }
    }
}

/// The number of limbs an alternative flips relative to the current pose.
/// @param est the estimate, only read.
/// @param index the alternative, below the alternative count.
/// @param out receives the count (0 for alternative 0; at most `SKB_NUM_LIMBS`); not NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `index` ≥ the alternative count; argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_estimate_alternative_flipped_count(
    est: *const skb_pose_estimate,
    index: u32,
    out: *mut usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let e = try_status!(try_ref(est, "est"));
            let a = try_status!(alternative_at(&e.inner, index));
            try_status!(write_out(out, a.flipped.len(), "out"));
            skb_status::SKB_OK
        }
    }
}

/// Copies the limbs an alternative flips relative to the current pose. Alternative 0 flips
/// none.
/// @param est the estimate, only read.
/// @param index the alternative, below the alternative count.
/// @param dst receives `SKB_LIMB_*` values, ascending.
/// @param dst_len the element count of `dst`, ≥ `skb_pose_estimate_alternative_flipped_count`
///                (`SKB_NUM_LIMBS` always suffices).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `index` ≥ the alternative count;
///         SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_estimate_copy_alternative_flipped(
    est: *const skb_pose_estimate,
    index: u32,
    dst: *mut u32,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let e = try_status!(try_ref(est, "est"));
            let a = try_status!(alternative_at(&e.inner, index));
            let out = try_status!(out_slice(dst, dst_len, a.flipped.len(), "dst"));
            for (o, l) in out.iter_mut().zip(&a.flipped) {
                *o = l.index() as u32;
            }
            skb_status::SKB_OK
        }
    }
}

/// Flips the depth of a limb of the estimate in place and re-solves (the image and every bone
/// length are kept; the alternatives are re-ranked relative to the new pose; a few
/// microseconds). Flipping the same limb twice returns the original. Not thread-safe on one
/// estimate.
/// @param est the estimate, changed.
/// @param limb `SKB_LIMB_*`.
/// @param outcome receives `SKB_REPOSE_DONE`, or `SKB_REPOSE_NO_DEPTH` for a limb lying in the
///                picture plane (nothing changed); may be NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `limb` ≥ `SKB_NUM_LIMBS`; argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_estimate_flip_limb(
    est: *mut skb_pose_estimate,
    limb: u32,
    outcome: *mut u32,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let e = try_status!(try_mut(est, "est"));
            let l = try_status!(limb_in(limb));
            let (next, status) = flip_limb(&e.inner, l);
            e.inner = next;
            write_opt(outcome, match status { FlipStatus::Flipped => SKB_REPOSE_DONE, FlipStatus::NoDepth => SKB_REPOSE_NO_DEPTH });
            skb_status::SKB_OK
        }
    }
}

/// Makes an alternative the estimate's pose: its limbs flipped in place, the alternatives
/// re-ranked relative to it. Not thread-safe on one estimate.
/// @param est the estimate, changed.
/// @param index the alternative (0 keeps the current pose).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `index` ≥ the count (nothing changed); argument errors
///         as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_estimate_pick_alternative(est: *mut skb_pose_estimate, index: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            let e = try_status!(try_mut(est, "est"));
            try_status!(alternative_at(&e.inner, index));
            if let Some(p) = pick_alternative(&e.inner, index as usize) {
                e.inner = p;
            }
            skb_status::SKB_OK
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn figure() -> skb_joints2d {
        let d = dict_io::embedded().unwrap();
        let mut j = skb_joints2d { xy: [[0.0; 2]; 15], visible: [1; 15], reserved: 0 };
        for (k, p) in j.xy.iter_mut().enumerate() {
            *p = [256.0 + 280.0 * d.mean[3 * k], 300.0 - 280.0 * d.mean[3 * k + 1]];
        }
        j
    }

    #[test]
    fn estimate_refine_and_errors() {
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        unsafe {
            let mut d = std::ptr::null_mut();
            assert_eq!(skb_pose_dictionary_new_default(&mut d), skb_status::SKB_OK);
            let mut o = std::ptr::null_mut();
            assert_eq!(skb_pose_options_new(&mut o), skb_status::SKB_OK);
            assert_eq!(skb_pose_options_set_alpha(o, f64::NAN), skb_status::SKB_ERR_NON_FINITE);
            assert_eq!(skb_pose_options_set_alpha(o, 2.0), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_pose_options_set_alpha_target(o, 2), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_pose_options_set_alpha_target(std::ptr::null_mut(), 2), skb_status::SKB_ERR_NULL_POINTER);
            assert_eq!(skb_pose_options_set_alpha_target(o, SKB_ALPHA_TARGET_IDENTITY), skb_status::SKB_OK);
            assert_eq!((*o).inner.alpha_target, RotationTarget::Identity);
            assert_eq!(skb_pose_options_set_equal_scales(o, false), skb_status::SKB_OK);
            assert!(!(*o).inner.equal_scales);
            assert_eq!(skb_pose_options_set_max_bases(o, 33), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_pose_options_set_kappa(o, 0.02), skb_status::SKB_OK);
            assert_eq!(skb_pose_options_set_max_bases(o, 4), skb_status::SKB_OK);
            assert_eq!(skb_pose_options_set_starts(o, 33), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_pose_options_set_limb_candidates(o, 5000), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_pose_options_set_blend(o, f64::NAN), skb_status::SKB_ERR_NON_FINITE);
            assert_eq!(skb_pose_options_set_blend(o, -1.0), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_pose_options_set_joint_noise(o, f64::NAN), skb_status::SKB_ERR_NON_FINITE);
            assert_eq!(skb_pose_options_set_joint_noise(o, 1.5), skb_status::SKB_ERR_OUT_OF_RANGE);
            let j = figure();
            let mut p: skb_pose3d = std::mem::zeroed();
            let mut fig: skb_pose_figure = std::mem::zeroed();
            assert_eq!(skb_pose3d_estimate_figure(d, &j, o, &mut p, &mut fig), skb_status::SKB_OK);
            assert!(fig.factors.iter().all(|k| (0.5..=2.0).contains(k)) && fig.plausible == 1, "{fig:?}");
            assert_eq!(
                skb_pose3d_estimate_figure(d, &j, o, &mut p, std::ptr::null_mut()),
                skb_status::SKB_ERR_NULL_POINTER
            );
            // The fixed-basis refinement below continues from the dictionary's skeleton.
            assert_eq!(skb_pose_options_set_proportions(o, false), skb_status::SKB_OK);
            assert!(!(*o).inner.proportions);
            assert_eq!(skb_pose_options_set_standing_prior(o, false), skb_status::SKB_OK);
            assert_eq!(skb_pose_options_set_knee_limits(o, false), skb_status::SKB_OK);
            assert!(!(*o).inner.standing_prior && !(*o).inner.knee_limits);
            assert!(!(*o).inner.straight_limbs);
            assert_eq!(skb_pose_options_set_straight_limbs(o, true), skb_status::SKB_OK);
            assert!((*o).inner.straight_limbs);
            assert_eq!(skb_pose_options_set_straight_limbs(o, false), skb_status::SKB_OK);
            assert!((*o).inner.factor_prior);
            assert_eq!(skb_pose_options_set_factor_prior(o, false), skb_status::SKB_OK);
            assert!(!(*o).inner.factor_prior);
            assert_eq!((*o).inner.depth_prior, 0.05);
            assert_eq!(skb_pose_options_set_depth_prior(o, -1.0), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!((*o).inner.depth_prior, 0.05);
            assert_eq!(skb_pose_options_set_depth_prior(o, 0.0), skb_status::SKB_OK);
            assert_eq!((*o).inner.depth_prior, 0.0);
            // The free-joint refinement (on by default) follows the 2-D joints more closely.
            assert_eq!(skb_pose3d_estimate(d, &j, o, &mut p), skb_status::SKB_OK);
            let free_rms = p.rms_px;
            assert_eq!(skb_pose_options_set_joint_noise(o, 0.0), skb_status::SKB_OK);
            assert_eq!((*o).inner.joint_noise, 0.0);
            // From an exemplar start (the default): refining the result must not undo the fit,
            // which holds only if the base pose is recovered as joints − Σ basis · weight.
            assert_eq!(skb_pose3d_estimate(d, &j, o, &mut p), skb_status::SKB_OK);
            assert!(p.num_bases > 0);
            assert!(free_rms < p.rms_px, "free joints {free_rms} px, dictionary pose {} px", p.rms_px);
            let mut q: skb_pose3d = std::mem::zeroed();
            assert_eq!(skb_pose3d_refine(d, &j, o, &p, &mut q), skb_status::SKB_OK);
            assert!(q.rms_px <= p.rms_px + 1e-9, "{} > {}", q.rms_px, p.rms_px);
            // The figure is the mean pose seen from the front: from μ (the paper) it fits.
            assert_eq!(skb_pose_options_set_starts(o, 0), skb_status::SKB_OK);
            assert_eq!(skb_pose3d_estimate(d, &j, o, &mut p), skb_status::SKB_OK);
            assert!(p.rms_px < 1.0, "rms {}", p.rms_px);
            assert!(p.length_excess.abs() <= 0.02 + 1e-9);
            if p.num_bases > 0 {
                assert_eq!(skb_pose3d_refine(d, &j, o, &p, &mut q), skb_status::SKB_OK);
                assert!(q.rms_px <= p.rms_px + 1e-9);
            }
            let mut bad = j;
            bad.xy[3] = [f64::NAN, 0.0];
            assert_eq!(skb_pose3d_estimate(d, &bad, o, &mut q), skb_status::SKB_ERR_TOO_FEW_JOINTS);
            let mut bad = j;
            bad.xy[3] = bad.xy[2];
            assert_eq!(skb_pose3d_estimate(d, &bad, o, &mut q), skb_status::SKB_ERR_COINCIDENT_JOINTS);
            let mut bad = j;
            for (k, xy) in bad.xy.iter_mut().enumerate() {
                *xy = [k as f64, 2.0 * k as f64];
            }
            assert_eq!(skb_pose3d_estimate(d, &bad, o, &mut q), skb_status::SKB_ERR_DEGENERATE);
            let mut bad = j;
            bad.visible = [0; 15];
            assert_eq!(skb_pose3d_estimate(d, &bad, o, &mut q), skb_status::SKB_ERR_TOO_FEW_JOINTS);
            assert_eq!(skb_pose3d_estimate(std::ptr::null(), &j, o, &mut q), skb_status::SKB_ERR_NULL_POINTER);
            assert_eq!(skb_pose3d_estimate(d, &j, o, std::ptr::null_mut()), skb_status::SKB_ERR_NULL_POINTER);
            let mut v = [0.0; 45];
            let mut sigma = 0.0;
            assert_eq!(skb_pose_dictionary_copy_basis(d, 0, v.as_mut_ptr(), 45, &mut sigma), skb_status::SKB_OK);
            assert!(sigma > 0.0);
            assert_eq!(
                skb_pose_dictionary_copy_basis(d, 0, v.as_mut_ptr(), 44, &mut sigma),
                skb_status::SKB_ERR_BUFFER_TOO_SMALL
            );
            assert_eq!(
                skb_pose_dictionary_copy_basis(d, 100000, v.as_mut_ptr(), 45, &mut sigma),
                skb_status::SKB_ERR_OUT_OF_RANGE
            );
            let path = c"/nonexistent/x.skbpd";
            let mut d2 = std::ptr::null_mut();
            assert_eq!(skb_pose_dictionary_new_from_file(path.as_ptr(), &mut d2), skb_status::SKB_ERR_IO);
            skb_pose_options_free(o);
            skb_pose_options_free(std::ptr::null_mut());
            skb_pose_dictionary_free(d);
            skb_pose_dictionary_free(std::ptr::null_mut());
        }
    }

    #[test]
    fn estimate_handle_lists_the_cores_alternatives_and_flips_like_it() {
        let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch_joints.json");
        let core_j = sketchbody_core::export::joints2d::load_joints2d(Path::new(root)).unwrap();
        let mut j = skb_joints2d { xy: core_j.xy, visible: [0; 15], reserved: 0 };
        for (v, &c) in j.visible.iter_mut().zip(&core_j.visible) {
            *v = u8::from(c);
        }
        let core = estimate_pose(&dict_io::embedded().unwrap(), &core_j, &PoseOptions::default()).unwrap();
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        unsafe {
            let mut d = std::ptr::null_mut();
            assert_eq!(skb_pose_dictionary_new_default(&mut d), skb_status::SKB_OK);
            let mut e = std::ptr::null_mut();
            assert_eq!(skb_pose_estimate_new(d, &j, std::ptr::null(), &mut e), skb_status::SKB_OK);
            let mut n = 0usize;
            assert_eq!(skb_pose_estimate_alternative_count(e, &mut n), skb_status::SKB_OK);
            assert_eq!(n, core.alternatives.len());
            assert!(n >= 2, "{n}");
            for (i, a) in core.alternatives.iter().enumerate() {
                let (mut x, mut score) = ([0.0f64; 45], f64::NAN);
                assert_eq!(
                    skb_pose_estimate_copy_alternative_joints(e, i as u32, x.as_mut_ptr(), 45, &mut score),
                    skb_status::SKB_OK
                );
                assert_eq!(x.to_vec(), a.joints.iter().flatten().copied().collect::<Vec<_>>());
                assert_eq!(score, a.score);
                let (mut limbs, mut count) = ([u32::MAX; 8], usize::MAX);
                assert_eq!(skb_pose_estimate_alternative_flipped_count(e, i as u32, &mut count), skb_status::SKB_OK);
                assert_eq!(
                    skb_pose_estimate_copy_alternative_flipped(e, i as u32, limbs.as_mut_ptr(), 8),
                    skb_status::SKB_OK
                );
                assert_eq!(limbs[..count].to_vec(), a.flipped.iter().map(|l| l.index() as u32).collect::<Vec<_>>());
            }
            // Flipping alternative 1's first limb twice: there and back, as the core does.
            let limb = core.alternatives[1].flipped[0];
            let mut outcome = u32::MAX;
            let mut p: skb_pose3d = std::mem::zeroed();
            assert_eq!(skb_pose_estimate_flip_limb(e, limb.index() as u32, &mut outcome), skb_status::SKB_OK);
            assert_eq!(outcome, SKB_REPOSE_DONE);
            assert_eq!(skb_pose_estimate_pose(e, &mut p), skb_status::SKB_OK);
            let once = flip_limb(&core, limb).0;
            assert_eq!(p.joints, once.joints);
            assert_eq!(skb_pose_estimate_flip_limb(e, limb.index() as u32, &mut outcome), skb_status::SKB_OK);
            assert_eq!(skb_pose_estimate_pose(e, &mut p), skb_status::SKB_OK);
            let back = p
                .joints
                .iter()
                .flatten()
                .zip(core.joints.iter().flatten())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(back < 1e-12, "{back}");
            // Picking alternative 1 takes its joints.
            assert_eq!(skb_pose_estimate_pick_alternative(e, 1), skb_status::SKB_OK);
            assert_eq!(skb_pose_estimate_pose(e, &mut p), skb_status::SKB_OK);
            let picked = p
                .joints
                .iter()
                .flatten()
                .zip(core.alternatives[1].joints.iter().flatten())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(picked < 1e-12, "{picked}");
            skb_pose_estimate_free(e);
            skb_pose_dictionary_free(d);
        }
    }
}

//! The shape fit from C: `skb_fit_options` (an opaque options handle with setters), the
//! progress callback type `skb_progress_fn` and `skb_context_fit_shape`.

use std::ffi::{c_int, c_void};
use std::sync::Arc;

use sketchbody_core::body::skin::SkinMethod;
use sketchbody_core::body::Gender;
use sketchbody_core::camera::WeakPerspective;
use sketchbody_core::error::Error;
use sketchbody_core::fit::{FitOptions, MatchScore};
use sketchbody_core::image::to_gray;
use sketchbody_core::pipeline::shape_keys::ShapeOrigin;
use sketchbody_core::pipeline::{fit_body, BodyChoice};
use sketchbody_core::skeleton::{Joints3, NUM_JOINTS};

use super::body::Posed;
use super::body::{skb_context, skb_mesh};
use super::error::{fail, fail_with};
use super::image::{skb_image, view_of};
use super::mesh_ops::skb_camera;
use super::ptr::*;
use super::status::skb_status;

/// Progress callback: called from the calling thread with the fraction of the work done
/// (0..=1, non-decreasing) after each stage and each fit iteration; `user` is the caller's
/// pointer, passed through untouched. Return 0 to continue, non-zero to cancel: the call then
/// returns `SKB_ERR_CANCELLED` within one fit iteration, having freed everything it made.
pub type skb_progress_fn = Option<unsafe extern "C" fn(user: *mut c_void, fraction: f32) -> c_int>;

/// `skb_fit_options_set_score`: the paper's eq. 7 (IoU of the silhouette with the edge map).
pub const SKB_SCORE_PAPER: u32 = 0;
/// `skb_fit_options_set_score`: IoU with the figure region filled from the closed strokes.
pub const SKB_SCORE_FILLED_IOU: u32 = 1;
/// `skb_fit_options_set_score`: silhouette boundary to edge chamfer distance (the default).
pub const SKB_SCORE_CHAMFER: u32 = 2;
/// `skb_fit_options_set_score`: chamfer plus the mean distance of the sketch's edges to the
/// silhouette (two-sided).
pub const SKB_SCORE_TWO_SIDED_CHAMFER: u32 = 3;
/// `skb_fit_options_set_skinning`: linear blend skinning (the default).
pub const SKB_SKIN_LINEAR: u32 = 0;
/// `skb_fit_options_set_skinning`: dual-quaternion skinning.
pub const SKB_SKIN_DUAL_QUATERNION: u32 = 1;
/// `skb_fit_options_set_gender`: the gender is the fit's or the classifier's (default).
pub const SKB_GENDER_AUTO: u32 = 2;

/// Options of `skb_context_fit_shape` and `skb_pipeline_run`'s fit. Created with the library defaults
/// (200 samples after a first iteration of 1600 halved each iteration, ≤ 8 iterations, transition scale 0.3, chamfer score, temperature 2.0, 2-D joint
/// weight 1.0 (used by `skb_pipeline_run`, which has the 2-D joints), raster side 256 px, tolerance 0.02, seed 1, linear blend skinning, the shape space's default
/// dimension, gender automatic, height unknown, per-sample cameras on, bone-length factors with
/// prior sd 0.1). Every setter validates its value and leaves the options
/// unchanged on error. Not synchronised: do not change it while another thread uses it; reading
/// it from several calls at once is fine. Free with `skb_fit_options_free`.
pub struct skb_fit_options {
    pub(crate) fit: FitOptions,
    pub(crate) gender: Option<Gender>,
}

/// Creates fit options with the defaults. Thread-safe.
/// @param out receives a new options handle the caller owns (release with
///            `skb_fit_options_free`); not NULL.
/// @return SKB_OK; SKB_ERR_NULL_POINTER for a NULL `out`.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_new(out: *mut *mut skb_fit_options) -> skb_status {
    unsafe {
        ffi_boundary! {
            let out = try_status!(out_slot(out));
            give(out, skb_fit_options { fit: FitOptions::default(), gender: None })
        }
    }
}

/// Frees fit options.
/// @param opts the options to free; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_free(opts: *mut skb_fit_options) {
    unsafe { free_box(opts) }
}

/// Applies `set` to a copy, validates it and stores it only if valid.
unsafe fn set_fit(opts: *mut skb_fit_options, set: impl FnOnce(&mut FitOptions) -> Result<(), Error>) -> skb_status {
    unsafe {
        let o = try_status!(try_mut(opts, "opts"));
        let mut next = o.fit.clone();
        try_core!(set(&mut next));
        try_core!(next.validate());
        o.fit = next;
        skb_status::SKB_OK
    }
}

/// Sets the samples per SIR iteration, S.
/// @param opts the options, changed.
/// @param samples the sample count, in 2..=100000.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE outside the range (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_samples(opts: *mut skb_fit_options, samples: u32) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.samples = samples as usize; Ok(()) }) }
    }
}

/// Sets the most SIR iterations, T.
/// @param opts the options, changed.
/// @param iterations the iteration limit, in 1..=1000.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE outside the range (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_iterations(opts: *mut skb_fit_options, iterations: u32) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.max_iterations = iterations as usize; Ok(()) }) }
    }
}

/// Sets the transition step s in standard deviations (Σ = diag(s² λ_k)).
/// @param opts the options, changed.
/// @param scale the step, finite and > 0.
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_transition_scale(opts: *mut skb_fit_options, scale: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.transition_scale = scale; Ok(()) }) }
    }
}

/// Sets the match score.
/// @param opts the options, changed.
/// @param score `SKB_SCORE_PAPER`, `SKB_SCORE_FILLED_IOU`, `SKB_SCORE_CHAMFER` (the default) or
///              `SKB_SCORE_TWO_SIDED_CHAMFER`.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_score(opts: *mut skb_fit_options, score: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            set_fit(opts, |o| {
                o.score = match score {
                    SKB_SCORE_PAPER => MatchScore::Paper,
                    SKB_SCORE_FILLED_IOU => MatchScore::FilledIou,
                    SKB_SCORE_CHAMFER => MatchScore::Chamfer,
                    SKB_SCORE_TWO_SIDED_CHAMFER => MatchScore::TwoSidedChamfer,
                    _ => return Err(Error::OutOfRange { name: "score", detail: format!("{score} (expected 0 paper, 1 filled IoU, 2 chamfer, 3 two-sided chamfer)") }),
                };
                Ok(())
            })
        }
    }
}

/// Sets the likelihood temperature of the non-paper scores (exp(score / temperature)).
/// @param opts the options, changed.
/// @param temperature the temperature, finite and > 0.
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_temperature(opts: *mut skb_fit_options, temperature: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.temperature = temperature; Ok(()) }) }
    }
}

/// Sets the weight of the 2-D joint term: the score loses weight × the mean distance in raster
/// pixels between each sample's projected rig joints and the 2-D joints (used by
/// `skb_pipeline_run`, which has the 2-D joints).
/// @param opts the options, changed.
/// @param weight the weight, ≥ 0; 0 turns the term off.
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN (or infinity); SKB_ERR_OUT_OF_RANGE for a negative
///         weight (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_joint_weight(opts: *mut skb_fit_options, weight: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.joint_weight = weight; Ok(()) }) }
    }
}

/// Sets the character's known rest height (character sheets carry one). With a height the
/// fitted rest mesh is scaled about its pelvis to it (and, without per-sample cameras, every fit
/// sample too).
/// @param opts the options, changed.
/// @param metres the height in metres, in 0.1..=10; 0 means unknown (the default).
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN; SKB_ERR_OUT_OF_RANGE for other values outside the
///         range, negative included (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_height(opts: *mut skb_fit_options, metres: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.height = (metres != 0.0).then_some(metres); Ok(()) }) }
    }
}

/// Turns per-sample cameras on or off: each fit sample's camera scales and translation are
/// refitted to its own posed joints vs the 2-D joints, so the size comes from the shape. Only
/// `skb_pipeline_run` has 2-D joints; `skb_context_fit_shape` ignores it.
/// @param opts the options, changed.
/// @param on true: on (the default); false: off.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_sample_camera(opts: *mut skb_fit_options, on: bool) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.sample_camera = on; Ok(()) }) }
    }
}

/// Sets the prior standard deviation of the fit's log bone-length factors (legs, arms,
/// shoulders, head, torso).
/// @param opts the options, changed.
/// @param sd the standard deviation, in 0..=0.5; 0 searches PCA weights only (default 0.1).
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_proportion_sd(opts: *mut skb_fit_options, sd: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.proportion_sd = sd; Ok(()) }) }
    }
}

/// Turns the closed-form proportion estimate on or off: the bone factors' prior is centred on
/// the factors estimated from the 2-D joints' bone lengths, the estimated pose and camera
/// instead of 1 (needs 2-D joints and a proportion sd > 0: only `skb_pipeline_run` has 2-D
/// joints; `skb_context_fit_shape` ignores it). Not thread-safe on one handle, like every setter.
/// @param opts the options, changed.
/// @param on true: on (the default); false: off.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_estimate_proportions(opts: *mut skb_fit_options, on: bool) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.estimate_proportions = on; Ok(()) }) }
    }
}

/// Sets the longest raster side of the fit.
/// @param opts the options, changed.
/// @param side the side in pixels, in 16..=4096.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE outside the range (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_raster_side(opts: *mut skb_fit_options, side: u32) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.raster_max_side = side as usize; Ok(()) }) }
    }
}

/// Sets the convergence tolerance.
/// @param opts the options, changed.
/// @param tolerance the tolerance in standard deviations of the weights, finite and > 0.
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_tolerance(opts: *mut skb_fit_options, tolerance: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.tolerance = tolerance; Ok(()) }) }
    }
}

/// Sets the seed of every random step (same seed, same result on any thread count).
/// @param opts the options, changed.
/// @param seed the seed (default 1).
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_seed(opts: *mut skb_fit_options, seed: u64) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.seed = seed; Ok(()) }) }
    }
}

/// Sets the skinning.
/// @param opts the options, changed.
/// @param method `SKB_SKIN_LINEAR` (the default) or `SKB_SKIN_DUAL_QUATERNION`.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_skinning(opts: *mut skb_fit_options, method: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            set_fit(opts, |o| {
                o.skinning = match method {
                    SKB_SKIN_LINEAR => SkinMethod::Linear,
                    SKB_SKIN_DUAL_QUATERNION => SkinMethod::DualQuaternion,
                    _ => return Err(Error::OutOfRange { name: "skinning", detail: format!("{method} (expected 0 linear, 1 dual quaternion)") }),
                };
                Ok(())
            })
        }
    }
}

/// Sets the clothing-robust chamfer's cap: silhouette boundary pixels inside the sketch's outer
/// outline cost at most this, so strokes that may be clothing do not pull the body outward.
/// @param opts the options, changed.
/// @param cap the cap in raster pixels, finite and > 0 (default 4); 12 or more is the plain
///            chamfer.
/// @return SKB_OK; SKB_ERR_NON_FINITE for NaN or infinity, SKB_ERR_OUT_OF_RANGE for other values
///         outside the range (options unchanged); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_inside_cap(opts: *mut skb_fit_options, cap: f64) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.inside_cap = cap; Ok(()) }) }
    }
}

/// Sets the PCA dimensions searched. `skb_pipeline_run` with automatic gender decides the gender
/// with two fits in 4 dimensions and then fits the chosen gender with these.
/// @param opts the options, changed.
/// @param dims the dimension count; 0 restores the default (a gendered space: all 10 of its
///             prior's dimensions; the both-sexes space: its default 5).
/// @return SKB_OK; argument errors as docs/c-api.md. A value above the model's GMM dimension fails
///         at fit time (SKB_ERR_OUT_OF_RANGE), not here.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_dims(opts: *mut skb_fit_options, dims: u32) -> skb_status {
    unsafe {
        ffi_boundary! { set_fit(opts, |o| { o.dims = (dims > 0).then_some(dims as usize); Ok(()) }) }
    }
}

/// Sets the gender of the fit.
/// @param opts the options, changed.
/// @param gender `SKB_GENDER_FEMALE`, `SKB_GENDER_MALE` or `SKB_GENDER_AUTO` (the default:
///               `skb_context_fit_shape` fits the both-sexes space, gender a continuous weight;
///               `skb_pipeline_run` fits the gendered space the gender classifier picks, see
///               `skb_result_gender`; `skb_result_gender_value` reads it).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value (options unchanged); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_fit_options_set_gender(opts: *mut skb_fit_options, gender: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            let o = try_status!(try_mut(opts, "opts"));
            o.gender = if gender == SKB_GENDER_AUTO {
                None
            } else {
                match Gender::from_index(gender) {
                    Ok(g) => Some(g),
                    Err(_) => return fail(&Error::OutOfRange { name: "gender", detail: format!("{gender} (expected 0 female, 1 male, 2 auto)") }),
                }
            };
            skb_status::SKB_OK
        }
    }
}

/// Wraps a C progress callback as the core's `FnMut(f32) -> bool` (continue while it returns 0).
pub(crate) fn progress_closure(progress: skb_progress_fn, user: *mut c_void) -> impl FnMut(f32) -> bool {
    move |f| match progress {
        // SAFETY: the caller of the exported function promised a valid callback and `user`.
        Some(cb) => unsafe { cb(user, f) == 0 },
        None => true,
    }
}

/// Fits the body shape (SIR, paper §II-C) to an edge map for a known 3-D pose and camera.
/// Thread-safe (the context is shared read-only); runs on the rayon pool; the callback is
/// called on the calling thread.
/// @param ctx the context, only read.
/// @param joints 15 × (x, y, z) doubles, metres, model frame (as `skb_pose3d.joints` from
///               `skb_pose3d_estimate`).
/// @param joints_len the element count of `joints`: 45.
/// @param camera maps the joints to `edges`' pixels.
/// @param edges the sketch's edge map: 1, 3 or 4 channels; any non-zero pixel is an edge (e.g.
///              from `skb_image_canny`).
/// @param opts fit options, only read, or NULL for the defaults (gender automatic: the
///             both-sexes space is fitted, gender a continuous weight; the mesh's gender is the
///             nearer one and its weights are the blended space's, weight 0 its gender axis).
/// @param progress the progress callback, or NULL; a non-zero return cancels.
/// @param user passed to `progress` unchanged.
/// @param score receives the best sample's match score (higher is better); may be NULL.
/// @param out receives a new mesh the caller owns (`skb_mesh_free`): the fitted rest shape (its
///            gender from `skb_mesh_gender`, its weights from `skb_mesh_copy_shape_weights`)
///            already posed to `joints` (no retargeting, the options' skinning; read with
///            `skb_mesh_copy_posed_vertices`; scaled to the options' height when one is set,
///            else the fitted height: `skb_pipeline_run` calibrates the fitted body when its
///            2-D joints are given, this call has none); not NULL.
/// @return SKB_OK; SKB_ERR_NON_FINITE for non-finite joints or camera; SKB_ERR_OUT_OF_RANGE for
///         a `joints_len` other than 45, an invalid camera or options, or a pose no sample can
///         be projected with; SKB_ERR_BLANK_IMAGE for an edge map without edges;
///         SKB_ERR_CANCELLED (nothing allocated remains); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_context_fit_shape(
    ctx: *const skb_context,
    joints: *const f64,
    joints_len: usize,
    camera: *const skb_camera,
    edges: *const skb_image,
    opts: *const skb_fit_options,
    progress: skb_progress_fn,
    user: *mut c_void,
    score: *mut f64,
    out: *mut *mut skb_mesh,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let ctx = try_status!(try_ref(ctx, "ctx"));
            if joints_len != 3 * NUM_JOINTS {
                return fail(&Error::OutOfRange { name: "joints_len", detail: format!("{joints_len}, expected {}", 3 * NUM_JOINTS) });
            }
            let j = try_status!(try_slice_of(joints, joints_len, "joints"));
            let pose: Joints3 = std::array::from_fn(|i| [j[3 * i], j[3 * i + 1], j[3 * i + 2]]);
            let cam = WeakPerspective::from(try_status!(try_ref(camera, "camera")));
            let edge_map = try_core!(to_gray(&try_status!(view_of(edges))));
            if out.is_null() {
                return fail_with(skb_status::SKB_ERR_NULL_POINTER, "out is NULL");
            }
            let (fit_opts, gender) = match opt_ref(opts) {
                Some(o) => (o.fit.clone(), o.gender),
                None => (FitOptions::default(), None),
            };
            if edge_map.as_bytes().iter().all(|&e| e == 0) {
                return fail(&Error::BlankImage { width: edge_map.width(), height: edge_map.height(), low: 0.0, high: 0.0 });
            }
            let mut cb = progress_closure(progress, user);
            let choice = BodyChoice { gender, ..BodyChoice::default() };
            let body = try_core!(fit_body(&ctx.model, &pose, &cam, &edge_map, None, &fit_opts, &choice, &mut cb));
            write_opt(score, body.score);
            let shape = try_core!(ShapeOrigin::of_fit(&body));
            let posed = Posed { pose: body.ik_pose, vertices: body.posed_vertices };
            let mesh = skb_mesh {
                model: Arc::clone(&ctx.model),
                gender: body.gender,
                rest: body.rest,
                shape,
                posed: Some(Box::new(posed)),
            };
            try_status!(write_out(out, Box::into_raw(Box::new(mesh)), "out"));
            skb_status::SKB_OK
        }
    }
}

//! The main job from C: `skb_pipeline_run` (sketch + 2-D joints → fitted, posed, rigged body)
//! with its owned result handle `skb_result`, and `skb_gray_image` (a decoded image file) so a
//! host needs no image library of its own.

use std::cell::OnceCell;
use std::ffi::{c_char, c_void};
use std::sync::Arc;

use sketchbody_core::body::BodyModel;
use sketchbody_core::detect::figure::FigureOptions;
use sketchbody_core::detect::landmark::LandmarkNet;
use sketchbody_core::detect::model::Model;
use sketchbody_core::error::Error;
use sketchbody_core::image::{load_image, to_gray, GrayImage};
use sketchbody_core::pipeline::shape_keys::ShapeOrigin;
use sketchbody_core::pipeline::{
    repose, run_pipeline_views, FigureJoints, GivenJoints, InterimBody, JointsSource, PipelineOptions, PipelineResult,
    ReposeOutcome, ReposeRequest, ViewInput,
};
use sketchbody_core::pose::dict_io;
use sketchbody_core::skeleton::NUM_JOINTS;

use super::body::Posed;
use super::body::{copy_skin_weights, skb_context, skb_mesh};
use super::detect::{embedded_detector, figure_info, skb_figure_info};
use super::fit::{progress_closure, skb_fit_options, skb_progress_fn};
use super::image::{skb_image, view_of};
use super::mesh_ops::skb_camera;
use super::pose::{joints_in, skb_joints2d, skb_pose_dictionary, skb_pose_options};
use super::ptr::*;
use super::status::skb_status;
use super::views::{skb_view_input, view_label};

/// `skb_result_copy_joints3d`: the rest joints of the fitted shape.
pub const SKB_JOINTS_REST: u32 = 0;
/// `skb_result_copy_joints3d`: the posed joints of the fitted mesh.
pub const SKB_JOINTS_POSED: u32 = 1;
/// `skb_result_copy_joints3d`: the 3-D pose estimated from the 2-D joints (a 1.75 m person).
pub const SKB_JOINTS_ESTIMATED: u32 = 2;

/// A decoded image file, 8-bit gray (colour converted with OpenCV's weights). Create with
/// `skb_gray_image_new_from_file`, view with `skb_gray_image_view`, free with `skb_gray_image_free`.
/// Immutable: several threads may read it at once.
pub struct skb_gray_image {
    inner: GrayImage,
}

/// The result of `skb_pipeline_run`, owned by the caller (free with `skb_result_free`). It owns
/// all its data (nothing refers to the inputs). Several threads may read it at once; only the
/// re-pose functions (`skb_result_pick_alternative`, `skb_result_flip_limb`,
/// `skb_result_repose_joints`) change it, in place, and must not run while another thread uses it.
pub struct skb_result {
    model: Arc<BodyModel>,
    pub(crate) inner: PipelineResult,
}

/// Loads a PNG or JPEG file as gray (colour converted with OpenCV's weights). Thread-safe.
/// @param path the file path, NUL-terminated UTF-8.
/// @param out receives a new image the caller owns (free with `skb_gray_image_free`); not NULL.
/// @return SKB_OK; SKB_ERR_IO (missing, unreadable); SKB_ERR_DECODE (not an image, truncated);
///         SKB_ERR_IMAGE_TOO_LARGE; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_gray_image_new_from_file(
    path: *const c_char,
    out: *mut *mut skb_gray_image,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let p = try_status!(path_arg(path, "path"));
            let out = try_status!(out_slot(out));
            let inner = try_core!(load_image(p));
            give(out, skb_gray_image { inner })
        }
    }
}

/// A borrowed 1-channel `skb_image` view of a decoded image.
/// @param img the image, only read.
/// @param out receives the view (stride = width), valid while `img` lives; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_gray_image_view(img: *const skb_gray_image, out: *mut skb_image) -> skb_status {
    unsafe {
        ffi_boundary! {
            let i = &try_status!(try_ref(img, "img")).inner;
            let (w, h) = (i.width() as u32, i.height() as u32);
            try_status!(write_out(out, skb_image { data: i.as_bytes().as_ptr(), width: w, height: h, stride: w, channels: 1 }, "out"));
            skb_status::SKB_OK
        }
    }
}

/// Frees an image from `skb_gray_image_new_from_file`.
/// @param img the image to free; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_gray_image_free(img: *mut skb_gray_image) {
    unsafe { free_box(img) }
}

/// Runs the main job on a sketch: Canny edges (50/150, aperture 3), the 2-D joints, the 3-D
/// pose and camera (with detected joints, BlazePose's relative joint depths weigh the solver's
/// choices), the shape fit (with detected joints: half the joint weight, no bone-factor search,
/// and with automatic gender the gendered space the detected-joints gender classifier picks),
/// and the fitted shape posed to the estimate. Without a height in `fit_opts` and with `joints`
/// given, the fitted body is calibrated: a gendered fit's shape weights are mapped and its
/// height calibrated (docs/benchmarks.md, "Shape calibration", "Height calibration"); detected
/// joints keep the fitted body. Thread-safe; runs on the rayon pool; the callback is called on
/// the calling thread.
/// @param ctx the context, only read.
/// @param sketch the sketch: 1, 3 or 4 channels, dark strokes on light paper.
/// @param joints the 2-D joints with their visibility, only read; NULL: the context's embedded
///               detector finds them, as `skb_context_detect` with default options.
/// @param dict the pose dictionary, only read; NULL: the embedded dictionary.
/// @param pose_opts pose options, only read; NULL: the defaults.
/// @param fit_opts fit options, only read; NULL: the defaults (the gender defaults to
///                 automatic: chosen by the gender classifier, see `skb_result_gender`).
/// @param progress gets the fraction of the whole run, or NULL; a non-zero return cancels
///                 within one fit iteration, freeing everything.
/// @param user passed to `progress` unchanged.
/// @param out receives a new result the caller owns (`skb_result_free`); untouched on error;
///            not NULL.
/// @return SKB_OK; SKB_ERR_IMAGE_TOO_SMALL (a side < 32 px); SKB_ERR_BLANK_IMAGE;
///         SKB_ERR_NO_FIGURE (NULL joints and the detector finds no figure);
///         SKB_ERR_JOINT_OUTSIDE_IMAGE; SKB_ERR_NON_FINITE (a visible joint NaN); the pose
///         solver's SKB_ERR_TOO_FEW_JOINTS, SKB_ERR_COINCIDENT_JOINTS, SKB_ERR_DEGENERATE;
///         SKB_ERR_CANCELLED; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pipeline_run(
    ctx: *const skb_context,
    sketch: *const skb_image,
    joints: *const skb_joints2d,
    dict: *const skb_pose_dictionary,
    pose_opts: *const skb_pose_options,
    fit_opts: *const skb_fit_options,
    progress: skb_progress_fn,
    user: *mut c_void,
    out: *mut *mut skb_result,
) -> skb_status {
    unsafe { run(ctx, sketch, joints, &[], dict, pose_opts, fit_opts, progress, None, user, out) }
}

/// Interim-body callback of `skb_pipeline_run_progressive`: called on the calling thread with
/// the caller's `user`, the stage (`SKB_INTERIM_MEAN_SHAPE`, `SKB_INTERIM_DECIDING_FIT`) and a
/// posed mesh borrowed for the call only (read it with the mesh getters, e.g.
/// `skb_mesh_copy_posed_vertices`; do not free or keep it).
pub type skb_interim_fn = Option<unsafe extern "C" fn(user: *mut c_void, stage: u32, mesh: *const skb_mesh)>;

/// `skb_interim_fn` stage: the mean shape of the expected gender posed to the estimated 3-D
/// pose, right after the pose step.
pub const SKB_INTERIM_MEAN_SHAPE: u32 = 0;
/// `skb_interim_fn` stage: the gender decision's fit of the chosen gender, posed, before the
/// final fit (only when the gender is decided by fitting: automatic gender with given joints).
pub const SKB_INTERIM_DECIDING_FIT: u32 = 1;

/// `skb_pipeline_run` that also shows the bodies it has before the final one, so a host can
/// draw something at once. The result is `skb_pipeline_run`'s for the same inputs. Arguments,
/// ownership, errors and threading as `skb_pipeline_run`.
/// @param ctx as in `skb_pipeline_run`.
/// @param sketch as in `skb_pipeline_run`.
/// @param joints as in `skb_pipeline_run` (NULL: detected).
/// @param dict as in `skb_pipeline_run` (NULL: the embedded dictionary).
/// @param pose_opts as in `skb_pipeline_run` (NULL: the defaults).
/// @param fit_opts as in `skb_pipeline_run` (NULL: the defaults).
/// @param progress as in `skb_pipeline_run` (may be NULL).
/// @param interim may be NULL; gets the mean shape in the estimated pose as soon as the pose is
///                known (a few ms after the pose step), then the deciding fit of the chosen
///                gender before the final fit.
/// @param user passed unchanged to both `progress` and `interim`.
/// @param out as in `skb_pipeline_run`.
/// @return the statuses of `skb_pipeline_run`.
#[no_mangle]
pub unsafe extern "C" fn skb_pipeline_run_progressive(
    ctx: *const skb_context,
    sketch: *const skb_image,
    joints: *const skb_joints2d,
    dict: *const skb_pose_dictionary,
    pose_opts: *const skb_pose_options,
    fit_opts: *const skb_fit_options,
    progress: skb_progress_fn,
    interim: skb_interim_fn,
    user: *mut c_void,
    out: *mut *mut skb_result,
) -> skb_status {
    unsafe { run(ctx, sketch, joints, &[], dict, pose_opts, fit_opts, progress, interim, user, out) }
}

/// Calls `f` with each interim body as a borrowed `skb_mesh` of `model`.
fn interim_closure(
    f: unsafe extern "C" fn(*mut c_void, u32, *const skb_mesh),
    user: *mut c_void,
    model: Arc<BodyModel>,
) -> impl FnMut(&InterimBody) {
    move |b| {
        let posed = Posed { pose: b.pose.clone(), vertices: b.posed_vertices.to_vec() };
        let mesh = skb_mesh {
            model: Arc::clone(&model),
            gender: b.gender,
            rest: b.rest.clone(),
            shape: b.shape.clone(),
            posed: Some(Box::new(posed)),
        };
        // SAFETY: the caller of the exported function promised a valid callback and `user`;
        // `mesh` outlives the call.
        unsafe { f(user, b.stage.index(), &mesh) };
    }
}

/// The entry points' shared body (`views`: a turnaround's extra views, empty for one view).
///
/// # Safety
/// `ctx`, `sketch`, `joints`, `dict`, `pose_opts`, `fit_opts`, `out` and every view's `sketch` and
/// `joints` are NULL or valid for the documented lengths during the call; `progress` and
/// `interim` are NULL or valid callbacks for `user`.
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn run(
    ctx: *const skb_context,
    sketch: *const skb_image,
    joints: *const skb_joints2d,
    views: &[skb_view_input],
    dict: *const skb_pose_dictionary,
    pose_opts: *const skb_pose_options,
    fit_opts: *const skb_fit_options,
    progress: skb_progress_fn,
    interim: skb_interim_fn,
    user: *mut c_void,
    out: *mut *mut skb_result,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let ctx = try_status!(try_ref(ctx, "ctx"));
            let colour = try_status!(view_of(sketch));
            let gray = try_core!(to_gray(&colour));
            let mut view_images = Vec::with_capacity(views.len());
            for v in views {
                let label = try_status!(view_label(v.label));
                let colour = try_status!(view_of(v.sketch));
                let gray = try_core!(to_gray(&colour));
                view_images.push((label, colour, gray, opt_ref(v.joints)));
            }
            let out = try_status!(out_slot(out));
            let figure_options = FigureOptions::default();
            // The detector and landmark network, loaded when a view has no joints.
            let detection: OnceCell<Result<(&Model, LandmarkNet), Error>> = OnceCell::new();
            let source_for = |given: Option<&skb_joints2d>, colour| -> Result<Box<dyn JointsSource + '_>, Error> {
                if let Some(j) = given {
                    return Ok(Box::new(GivenJoints(joints_in(j))));
                }
                let loaded = detection.get_or_init(|| Ok((embedded_detector(ctx)?, LandmarkNet::embedded()?)));
                let (model, net) = loaded.as_ref().map_err(|e| Error::CorruptData(format!("the embedded detector: {e}")))?;
                Ok(Box::new(FigureJoints { model, net, options: &figure_options, colour: Some(colour) }))
            };
            let source = try_core!(source_for(opt_ref(joints), colour));
            let mut view_sources = Vec::with_capacity(view_images.len());
            for (_, colour, _, given) in &view_images {
                view_sources.push(try_core!(source_for(*given, *colour)));
            }
            let view_inputs: Vec<ViewInput> = view_images
                .iter()
                .zip(&view_sources)
                .map(|((label, _, gray, _), source)| ViewInput { label: *label, sketch: gray, source: source.as_ref() })
                .collect();
            let embedded;
            let d = match opt_ref(dict) {
                Some(d) => &d.inner,
                None => {
                    embedded = try_core!(dict_io::embedded());
                    &embedded
                }
            };
            let mut options = PipelineOptions::default();
            if let Some(p) = opt_ref(pose_opts) {
                options.pose = p.inner;
            }
            if let Some(f) = opt_ref(fit_opts) {
                options.fit = f.fit.clone();
                options.gender = f.gender;
            }
            let mut cb = progress_closure(progress, user);
            let mut show = interim.map(|f| interim_closure(f, user, Arc::clone(&ctx.model)));
            let show = show.as_mut().map(|c| c as &mut dyn FnMut(&InterimBody));
            let inner = try_core!(run_pipeline_views(&ctx.model, d, &gray, source.as_ref(), &view_inputs, &options, &mut cb, show));
            give(out, skb_result { model: Arc::clone(&ctx.model), inner })
        }
    }
}

/// Frees a result.
/// @param result the result to free; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_result_free(result: *mut skb_result) {
    unsafe { free_box(result) }
}

/// The result's gender: the given one, or with automatic gender the classifier's choice
/// between the two gendered fits (given joints) or the detected-joints classifier's choice of
/// the one gendered space fitted (detected joints).
/// @param result the result, only read.
/// @param gender receives `SKB_GENDER_FEMALE` or `SKB_GENDER_MALE`; not NULL.
/// @param by_score receives whether the gender was fitted (true) or given (false); may be NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_gender(
    result: *const skb_result,
    gender: *mut u32,
    by_score: *mut bool,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            try_status!(write_out(gender, r.gender as u32, "gender"));
            write_opt(by_score, r.gender_fitted);
            skb_status::SKB_OK
        }
    }
}

/// The fitted gender value and the confidence in `skb_result_gender`.
/// @param result the result, only read.
/// @param value receives 0 = the female mean shape … 1 = the male mean (0 or 1 when a gendered
///              space was fitted, as by default); not NULL.
/// @param confidence receives the probability that `skb_result_gender` is right (0.5..=1; 1 when
///                   the gender was given): with given joints, the gender classifier's (the
///                   sketch's joint and outline widths and the score margin of the two gendered
///                   fits); with detected joints, the detected-joints classifier's (the same
///                   widths); may be NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_gender_value(
    result: *const skb_result,
    value: *mut f64,
    confidence: *mut f64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            try_status!(write_out(value, r.gender_value, "value"));
            write_opt(confidence, r.gender_confidence);
            skb_status::SKB_OK
        }
    }
}

/// The detection behind the result's 2-D joints.
/// @param result the result, only read.
/// @param info receives the backend kept, calibrated confidence, presence and the
///             low-confidence flag (show the joints to the user for correction); not NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE when the joints were given to `skb_pipeline_run`, not
///         detected (nothing written); SKB_ERR_NULL_POINTER.
#[no_mangle]
pub unsafe extern "C" fn skb_result_detection(result: *const skb_result, info: *mut skb_figure_info) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let info = try_status!(try_mut(info, "info"));
            match &r.detection {
                Some(f) => {
                    *info = figure_info(f);
                    skb_status::SKB_OK
                }
                None => super::error::fail(&Error::OutOfRange { name: "detection", detail: "the 2-D joints were given, not detected".into() }),
            }
        }
    }
}

/// Whether the fit is low-evidence, and the fraction of the fitted outline the strokes support.
/// @param result the result, only read.
/// @param low receives true when the sketch's strokes support less than half of the fitted
///            outline (e.g. a figure under a cloak to the ground: the body is mostly the
///            prior's); not NULL.
/// @param edge_support receives that fraction (0..=1; NaN for the mean shape); may be NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_evidence(
    result: *const skb_result,
    low: *mut bool,
    edge_support: *mut f64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            try_status!(write_out(low, r.low_evidence, "low"));
            write_opt(edge_support, r.edge_support);
            skb_status::SKB_OK
        }
    }
}

/// Number of body parts `skb_result_copy_part_support` reports.
pub const SKB_NUM_BODY_PARTS: u32 = 6;
const _: () = assert!(SKB_NUM_BODY_PARTS as usize == sketchbody_core::fit::BodyPart::ALL.len());

/// Per body part, the share of the fitted silhouette's outline within 2 raster pixels of a
/// stroke. A part below 0.5 is one the drawing does not support (clothing, a shape no body
/// has): the body there is the prior's reading.
/// @param result the result, only read.
/// @param dst receives `dst[0..6]`, each in 0..=1, in the order head, torso, right arm, left
///            arm, right leg, left leg (the figure's own sides); NaN for a part with no outline
///            in view and for every part of the mean shape.
/// @param dst_len the element count of `dst`, at least `SKB_NUM_BODY_PARTS`.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_copy_part_support(
    result: *const skb_result,
    dst: *mut f64,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let out = try_status!(out_slice(dst, dst_len, SKB_NUM_BODY_PARTS as usize, "dst"));
            for (k, o) in out.iter_mut().take(SKB_NUM_BODY_PARTS as usize).enumerate() {
                *o = r.part_support.and_then(|p| p.support[k]).unwrap_or(f64::NAN);
            }
            skb_status::SKB_OK
        }
    }
}

/// The best match score (higher is better) of the chosen fit.
/// @param result the result, only read.
/// @param gender the result's gender (`skb_result_gender`: the given gender's space or the
///               gendered fit the classifier chose).
/// @param score receives the score; not NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for the other gender; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_score(result: *const skb_result, gender: u32, score: *mut f64) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let chosen = r.chosen_fit();
            let Some(g) = chosen.filter(|_| r.gender as u32 == gender) else {
                return super::error::fail(&Error::OutOfRange { name: "gender", detail: format!("{gender} was not fitted") });
            };
            try_status!(write_out(score, g.score, "score"));
            skb_status::SKB_OK
        }
    }
}

/// Writes `count(result)` to `*out`: the body of the result's count and length getters.
///
/// # Safety
/// As those getters: `result` NULL or a live result, `out` NULL or valid for one write.
pub(crate) unsafe fn write_result_count(
    result: *const skb_result,
    out: *mut usize,
    count: impl FnOnce(&PipelineResult) -> usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            try_status!(write_out(out, count(r), "out"));
            skb_status::SKB_OK
        }
    }
}

/// The result body's vertex count (13380).
/// @param result the result, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_vertex_count(result: *const skb_result, out: *mut usize) -> skb_status {
    unsafe { write_result_count(result, out, |r| r.mesh.vertices.len()) }
}

/// The result body's quad-face count (13378).
/// @param result the result, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_face_count(result: *const skb_result, out: *mut usize) -> skb_status {
    unsafe { write_result_count(result, out, |r| r.mesh.quads.len()) }
}

/// Copies the posed or rest vertices. On error nothing is written.
/// @param result the result, only read.
/// @param posed true: the posed vertices; false: the rest vertices.
/// @param dst receives x, y, z floats per vertex, metres, model frame.
/// @param dst_len the element count of `dst` in floats, ≥ 3 × vertex count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_copy_vertices(
    result: *const skb_result,
    posed: bool,
    dst: *mut f32,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let v = if posed { &r.posed_vertices } else { &r.mesh.vertices };
            let out = try_status!(out_slice(dst, dst_len, 3 * v.len(), "dst"));
            for (o, p) in out.chunks_exact_mut(3).zip(v) {
                o.copy_from_slice(p);
            }
            skb_status::SKB_OK
        }
    }
}

/// Copies the quad faces.
/// @param result the result, only read.
/// @param dst receives 4 vertex indices per face, counter-clockwise seen from outside (a
///            triangle repeats its third index).
/// @param dst_len the element count of `dst` in integers, ≥ 4 × face count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_copy_faces(result: *const skb_result, dst: *mut u32, dst_len: usize) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let out = try_status!(out_slice(dst, dst_len, 4 * r.mesh.quads.len(), "dst"));
            for (o, q) in out.chunks_exact_mut(4).zip(&r.mesh.quads) {
                o.copy_from_slice(q);
            }
            skb_status::SKB_OK
        }
    }
}

/// The 2-D joints used (pixels, with visibility).
/// @param result the result, only read.
/// @param out receives the joints; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_joints2d(result: *const skb_result, out: *mut skb_joints2d) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let j = skb_joints2d { xy: r.joints2d.xy, visible: r.joints2d.visible.map(u8::from), reserved: 0 };
            try_status!(write_out(out, j, "out"));
            skb_status::SKB_OK
        }
    }
}

/// Copies 15 3-D joints.
/// @param result the result, only read.
/// @param which `SKB_JOINTS_REST`, `SKB_JOINTS_POSED` or `SKB_JOINTS_ESTIMATED`.
/// @param dst receives x, y, z doubles per joint, metres, model frame.
/// @param dst_len the element count of `dst` in doubles, ≥ 45.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another `which`; SKB_ERR_BUFFER_TOO_SMALL for a
///         short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_copy_joints3d(
    result: *const skb_result,
    which: u32,
    dst: *mut f64,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let j = match which {
                SKB_JOINTS_REST => &r.mesh.joints,
                SKB_JOINTS_POSED => &r.posed_joints,
                SKB_JOINTS_ESTIMATED => &r.pose.joints,
                _ => return super::error::fail(&Error::OutOfRange { name: "which", detail: format!("{which} (expected 0 rest, 1 posed, 2 estimated)") }),
            };
            let out = try_status!(out_slice(dst, dst_len, 3 * NUM_JOINTS, "dst"));
            for (o, p) in out.chunks_exact_mut(3).zip(j) {
                o.copy_from_slice(p);
            }
            skb_status::SKB_OK
        }
    }
}

/// The result's weak-perspective camera (model metres → sketch pixels): the posed body's,
/// fitted to its skeleton, so it projects `SKB_JOINTS_POSED` and the posed vertices onto the
/// sketch (`SKB_JOINTS_ESTIMATED` are at the pose step's 1.75 m scale and land on the drawn
/// joints only for a body of that height).
/// @param result the result, only read.
/// @param out receives the camera; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_camera(result: *const skb_result, out: *mut skb_camera) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let c = &r.pose.camera;
            let cam = skb_camera { sx: c.sx, sy: c.sy, r: std::array::from_fn(|i| c.r[(i / 3, i % 3)]), t: c.t };
            try_status!(write_out(out, cam, "out"));
            skb_status::SKB_OK
        }
    }
}

/// Copies the skin weights as `skb_mesh_copy_skin_weights` does: for vertex v, slots
/// `4v .. 4v+3` of both buffers.
/// @param result the result, only read.
/// @param bones receives bone indices 0..13.
/// @param weights receives the weights, summing to 1 per vertex.
/// @param len the element count of each buffer, ≥ 4 × vertex count.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for short buffers; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_copy_skin_weights(
    result: *const skb_result,
    bones: *mut u32,
    weights: *mut f32,
    len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            copy_skin_weights(&r.mesh.weights, bones, weights, len)
        }
    }
}

/// The number of fitted PCA shape weights (the fit's dimensions).
/// @param result the result, only read.
/// @param out receives the count; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_shape_weight_count(result: *const skb_result, out: *mut usize) -> skb_status {
    unsafe { write_result_count(result, out, |r| r.weights.len()) }
}

/// Copies the fitted PCA shape weights.
/// @param result the result, only read.
/// @param dst receives the weights, metres.
/// @param dst_len the element count of `dst` in doubles, at least `skb_result_shape_weight_count`.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_copy_shape_weights(
    result: *const skb_result,
    dst: *mut f64,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let n = r.weights.len();
            let out = try_status!(out_slice(dst, dst_len, n, "dst"));
            out[..n].copy_from_slice(&r.weights);
            skb_status::SKB_OK
        }
    }
}

/// A new `skb_mesh` of the result (the fitted rest shape, posed as in the result), for the mesh
/// functions (`skb_mesh_write_glb`, `skb_mesh_write_obj`, ...).
/// @param result the result, only read.
/// @param out receives a new mesh the caller owns (`skb_mesh_free`); not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_mesh_new_from_result(result: *const skb_result, out: *mut *mut skb_mesh) -> skb_status {
    unsafe {
        ffi_boundary! {
            let res = try_status!(try_ref(result, "result"));
            let r = &res.inner;
            let rest = sketchbody_core::body::RestShape { vertices: r.mesh.vertices.clone(), joints: r.mesh.joints };
            let posed = Posed { pose: r.ik_pose.clone(), vertices: r.posed_vertices.clone() };
            let shape = try_core!(ShapeOrigin::of_result(r));
            let mesh = skb_mesh { model: Arc::clone(&res.model), gender: r.gender, rest, shape, posed: Some(Box::new(posed)) };
            try_status!(write_out(out, Box::into_raw(Box::new(mesh)), "out"));
            skb_status::SKB_OK
        }
    }
}

/// The result's 3-D pose (`SKB_JOINTS_ESTIMATED`) with its ranked alternatives as a new
/// estimate handle: list the readings with `skb_pose_estimate_alternative_count` /
/// `skb_pose_estimate_copy_alternative_joints` / `skb_pose_estimate_copy_alternative_flipped`.
/// A copy: flipping it does not change the result (use `skb_result_flip_limb` /
/// `skb_result_pick_alternative` for that).
/// @param result the result, only read.
/// @param out receives a new estimate the caller owns (`skb_pose_estimate_free`); not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_pose_estimate_new_from_result(
    result: *const skb_result,
    out: *mut *mut super::pose::skb_pose_estimate,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let out = try_status!(out_slot(out));
            let d = try_core!(dict_io::embedded_shared());
            let prior_weight = sketchbody_core::pose::problem::Problem::new(d, &r.joints2d, r.posing_options.pose.prior)
                .map(|p| p.prior_w)
                .unwrap_or(0.0);
            give(out, super::pose::skb_pose_estimate { inner: r.pose.clone(), prior_weight })
        }
    }
}

/// `*outcome` code of a re-pose.
fn outcome_code(o: ReposeOutcome) -> u32 {
    use super::pose::*;
    match o {
        ReposeOutcome::Reposed => SKB_REPOSE_DONE,
        ReposeOutcome::NoDepth => SKB_REPOSE_NO_DEPTH,
        ReposeOutcome::JointOutsideImage { .. } => SKB_REPOSE_JOINT_OUTSIDE_IMAGE,
        ReposeOutcome::JointsCoincide { .. } => SKB_REPOSE_JOINTS_COINCIDE,
        ReposeOutcome::Implausible => SKB_REPOSE_IMPLAUSIBLE,
    }
}

/// Runs a re-pose on `result` in place and writes its outcome.
unsafe fn repose_c(
    result: *mut skb_result,
    dict: *const skb_pose_dictionary,
    request: ReposeRequest,
    outcome: *mut u32,
) -> skb_status {
    // SAFETY: forwarded from the callers' header contracts: `result`, `dict`, `outcome` are NULL or valid.
    unsafe {
        let res = match try_mut(result, "result") {
            Ok(r) => r,
            Err(s) => return s,
        };
        let d = match opt_ref(dict) {
            Some(d) => &d.inner,
            None => match dict_io::embedded_shared() {
                Ok(d) => d,
                Err(e) => return super::error::fail(&e),
            },
        };
        match repose(&mut res.inner, d, request) {
            Ok(o) => {
                write_opt(outcome, outcome_code(o));
                skb_status::SKB_OK
            }
            Err(e) => super::error::fail(&e),
        }
    }
}

/// Re-poses the result in place to one of its pose's alternatives: IK and skinning of the
/// fitted rest body, whose shape weights, proportions and rest mesh are kept; the camera and
/// 2-D joints are kept. A few ms. Do not call while another thread uses `result`.
/// @param result the result, changed.
/// @param index the alternative (`skb_pose_estimate_new_from_result` lists them; 0 = the
///              current pose).
/// @param outcome receives `SKB_REPOSE_DONE`; may be NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `index` ≥ the count (nothing changed); argument errors
///         as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_pick_alternative(
    result: *mut skb_result,
    index: u32,
    outcome: *mut u32,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            repose_c(result, std::ptr::null(), ReposeRequest::Alternative(index as usize), outcome)
        }
    }
}

/// Flips the depth of a limb of the result's pose and re-poses the fitted body in place (as
/// `skb_result_pick_alternative`). Do not call while another thread uses `result`.
/// @param result the result, changed.
/// @param limb `SKB_LIMB_*`.
/// @param outcome receives `SKB_REPOSE_DONE`, or `SKB_REPOSE_NO_DEPTH` for a limb lying in the
///                picture plane (nothing changed); may be NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `limb` ≥ `SKB_NUM_LIMBS`; argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_flip_limb(result: *mut skb_result, limb: u32, outcome: *mut u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            let l = try_status!(super::pose::limb_in(limb));
            repose_c(result, std::ptr::null(), ReposeRequest::Flip(l), outcome)
        }
    }
}

/// Re-poses the fitted body in place for moved 2-D joints (issue 50's live correction): the
/// 3-D pose is re-estimated with the run's pose options, without an image depth cue, then IK
/// and skinning of the fitted rest body (shape weights, proportions and rest mesh kept) and the
/// camera's scales refitted to its skeleton. About 5–10 ms (docs/benchmarks.md, "Re-pose").
/// With the result's own given joints the mesh is the run's. Do not call while another thread
/// uses `result`.
/// @param result the result, changed.
/// @param dict the pose dictionary, only read; NULL: the embedded dictionary (pass the one
///             given to `skb_pipeline_run`).
/// @param joints the moved joints, pixels of the result's sketch, only read.
/// @param outcome receives `SKB_REPOSE_DONE`, or, with nothing changed:
///                `SKB_REPOSE_JOINT_OUTSIDE_IMAGE` (a visible joint outside the sketch or not
///                finite), `SKB_REPOSE_JOINTS_COINCIDE` (two visible joints on each other),
///                `SKB_REPOSE_IMPLAUSIBLE` (no plausible body explains them); may be NULL.
/// @return SKB_OK (whatever the outcome); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_repose_joints(
    result: *mut skb_result,
    dict: *const skb_pose_dictionary,
    joints: *const skb_joints2d,
    outcome: *mut u32,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let j = joints_in(try_status!(try_ref(joints, "joints")));
            repose_c(result, dict, ReposeRequest::Joints(&j), outcome)
        }
    }
}

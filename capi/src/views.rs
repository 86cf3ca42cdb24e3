//! Turnarounds (model sheets) from C: `skb_pipeline_run_views` fits one body to the front sketch
//! and extra views of the same character in the same pose (side, other side, back), each with its
//! own image and optional 2-D joints; the result's per-view getters.

use std::ffi::{c_char, c_void};

use sketchbody_core::error::Error;
use sketchbody_core::pipeline::PipelineResult;
use sketchbody_core::view::ViewLabel;

use super::body::skb_context;
use super::error::fail;
use super::fit::{skb_fit_options, skb_progress_fn};
use super::image::skb_image;
use super::mesh_ops::skb_camera;
use super::pipeline::{run, skb_interim_fn, skb_result, write_result_count};
use super::pose::{skb_joints2d, skb_pose_dictionary, skb_pose_options};
use super::ptr::*;
use super::status::skb_status;

/// View label: the front view (yaw 0°), the pipeline's main sketch; not accepted as an extra view.
pub const SKB_VIEW_FRONT: u32 = 0;
/// View label: the side view (yaw +90°), the character's right side, facing image right.
pub const SKB_VIEW_SIDE: u32 = 1;
/// View label: the other side view (yaw −90°), the character's left side, facing image left.
pub const SKB_VIEW_SIDE_LEFT: u32 = 2;
/// View label: the back view (yaw 180°).
pub const SKB_VIEW_BACK: u32 = 3;

/// One extra view of a turnaround for `skb_pipeline_run_views`: its label (`SKB_VIEW_SIDE`,
/// `SKB_VIEW_SIDE_LEFT` or `SKB_VIEW_BACK`), its sketch (1, 3 or 4 channels, dark strokes on light
/// paper; any size: views drawn at another scale are scaled to the front by their joints) and its
/// 2-D joints in that image's pixels (NULL: detected). The pointers are borrowed for the call only.
/// Plain data; its layout is part of the ABI.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct skb_view_input {
    /// `SKB_VIEW_SIDE`, `SKB_VIEW_SIDE_LEFT` or `SKB_VIEW_BACK`.
    pub label: u32,
    /// Set to 0.
    pub reserved: u32,
    /// The view's sketch (not NULL).
    pub sketch: *const skb_image,
    /// The view's 2-D joints, pixels of its sketch; NULL: the context's detector finds them.
    pub joints: *const skb_joints2d,
}

/// What a turnaround run made of one extra view (`skb_result_view`). Plain data; its layout is
/// part of the ABI.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct skb_view_info {
    /// The view's label (`SKB_VIEW_SIDE`, `SKB_VIEW_SIDE_LEFT` or `SKB_VIEW_BACK`).
    pub label: u32,
    /// 1 when the view's joints were detected, 0 when given.
    pub joints_detected: u32,
    /// 1 when the detected joints are the detector's other labelling (left and right swapped),
    /// which fits the shared pose better; 0 otherwise.
    pub joints_swapped: u32,
    /// 0.
    pub reserved: u32,
    /// The 2-D joints used in the view, pixels of its sketch.
    pub joints: skb_joints2d,
    /// The view's camera refitted to the body: projects the result's posed vertices and
    /// `SKB_JOINTS_POSED` onto the view's sketch.
    pub camera: skb_camera,
    /// RMS distance of the view's joints from the shared pose seen through its camera, fraction
    /// of the figure's height (runs refuse views beyond 0.12 and warn beyond 0.05).
    pub residual: f64,
    /// The view's drawn size over the front view's (1: the same scale).
    pub scale_ratio: f64,
    /// Share of the fitted outline in this view within reach of a stroke, 0..1 (NaN for the
    /// mean shape).
    pub edge_support: f64,
    /// A side view: mean angle between its triangulated limbs and the front estimate's, degrees,
    /// as labelled; NaN for a back view or a given pose.
    pub facing_as_labelled_deg: f64,
    /// The same with the view taken as the other side; NaN as above. Much lower than
    /// `facing_as_labelled_deg` means the view is drawn facing the other way (runs refuse it).
    pub facing_other_side_deg: f64,
}

/// The core label of a C view label. Errors: not `SKB_VIEW_*` (`SKB_ERR_OUT_OF_RANGE`).
pub(crate) fn view_label(label: u32) -> Result<ViewLabel, skb_status> {
    let code = |l: ViewLabel| label_code(l) == label;
    ViewLabel::ALL.into_iter().find(|&l| code(l)).ok_or_else(|| {
        fail(&Error::OutOfRange { name: "view label", detail: format!("{label} is not one of SKB_VIEW_*") })
    })
}

/// The `SKB_VIEW_*` code of a label.
fn label_code(label: ViewLabel) -> u32 {
    match label {
        ViewLabel::Front => SKB_VIEW_FRONT,
        ViewLabel::Side => SKB_VIEW_SIDE,
        ViewLabel::SideLeft => SKB_VIEW_SIDE_LEFT,
        ViewLabel::Back => SKB_VIEW_BACK,
    }
}

/// `skb_pipeline_run_progressive` on a turnaround. The views share one body and one pose: every
/// view's joints enter the 3-D pose (depth from a side view), every view's outline the shape
/// fit; each view has the front camera turned by its label's yaw, with its own scale and
/// position. Read each view with `skb_result_view` and the run's warnings (views that agree only
/// roughly, a view little supported by its strokes) with `skb_result_copy_view_warnings`.
/// Ownership, threading, progress and cancel as `skb_pipeline_run_progressive`.
/// @param ctx as in `skb_pipeline_run`.
/// @param sketch the front view, as in `skb_pipeline_run`.
/// @param joints the front view's joints, as in `skb_pipeline_run` (NULL: detected).
/// @param views `view_count` extra views, the same character in the same pose from the side,
///              the other side or the back; their images and joints are only read during the
///              call; NULL when `view_count` is 0.
/// @param view_count the number of extra views; 0 makes this `skb_pipeline_run_progressive`.
/// @param dict as in `skb_pipeline_run` (NULL: the embedded dictionary).
/// @param pose_opts as in `skb_pipeline_run` (NULL: the defaults).
/// @param fit_opts as in `skb_pipeline_run` (NULL: the defaults).
/// @param progress as in `skb_pipeline_run` (may be NULL).
/// @param interim as in `skb_pipeline_run_progressive` (the interim bodies are the front
///                view's; may be NULL).
/// @param user passed unchanged to `progress` and `interim`.
/// @param out as in `skb_pipeline_run`.
/// @return SKB_OK; `skb_pipeline_run`'s errors for any view's image and joints;
///         SKB_ERR_OUT_OF_RANGE for a label not `SKB_VIEW_SIDE`, `SKB_VIEW_SIDE_LEFT` or
///         `SKB_VIEW_BACK`, or one given twice; SKB_ERR_VIEWS_DISAGREE for views that do not
///         show one character in one pose (their joints miss the shared pose by more than 12 %
///         of the figure's height, match it only upside down, or a side view drawn facing the
///         other way than its label; the message names the view and the reason; a turnaround
///         is never silently fitted to the front alone).
#[no_mangle]
pub unsafe extern "C" fn skb_pipeline_run_views(
    ctx: *const skb_context,
    sketch: *const skb_image,
    joints: *const skb_joints2d,
    views: *const skb_view_input,
    view_count: usize,
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
            let views: &[skb_view_input] =
                if view_count == 0 { &[] } else { try_status!(try_slice_of(views, view_count, "views")) };
            run(ctx, sketch, joints, views, dict, pose_opts, fit_opts, progress, interim, user, out)
        }
    }
}

/// The number of extra views of a result.
/// @param result the result, only read.
/// @param out receives the count (0 for a one-view run); not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_view_count(result: *const skb_result, out: *mut usize) -> skb_status {
    unsafe { write_result_count(result, out, |r| r.views.len()) }
}

/// What the run made of one extra view.
/// @param result the result, only read.
/// @param index the view, 0 .. `skb_result_view_count` − 1, in the order given.
/// @param out receives the view's info; not NULL.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `index` out of range; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_view(
    result: *const skb_result,
    index: usize,
    out: *mut skb_view_info,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            let slot = try_status!(try_mut(out, "out"));
            let Some(v) = r.views.get(index) else {
                return fail(&Error::OutOfRange { name: "view index", detail: format!("{index} >= {}", r.views.len()) });
            };
            let c = &v.camera;
            let (labelled, other) = v.facing.map_or((f64::NAN, f64::NAN), |f| (f.as_labelled_deg, f.other_side_deg));
            let info = skb_view_info {
                label: label_code(v.label),
                joints_detected: u32::from(v.joints_source == "detector"),
                joints_swapped: u32::from(v.swapped),
                reserved: 0,
                joints: skb_joints2d { xy: v.joints2d.xy, visible: v.joints2d.visible.map(u8::from), reserved: 0 },
                camera: skb_camera { sx: c.sx, sy: c.sy, r: std::array::from_fn(|i| c.r[(i / 3, i % 3)]), t: c.t },
                residual: v.residual,
                scale_ratio: v.scale_ratio,
                edge_support: v.edge_support,
                facing_as_labelled_deg: labelled,
                facing_other_side_deg: other,
            };
            *slot = info;
            skb_status::SKB_OK
        }
    }
}

/// The byte length (UTF-8, without the terminating NUL) of the run's warnings about its views.
/// Read them with `skb_result_copy_view_warnings`.
/// @param result the result, only read.
/// @param out receives the length: 0 when there are none or for a one-view run; not NULL.
/// @return SKB_OK; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_view_warnings_length(result: *const skb_result, out: *mut usize) -> skb_status {
    unsafe { write_result_count(result, out, |r| warnings_text(r).len()) }
}

/// Copies the run's warnings about its views, one per line.
/// @param result the result, only read.
/// @param dst receives the warnings as NUL-terminated UTF-8, `\n`-separated, no trailing
///            newline; empty when there are none or for a one-view run.
/// @param dst_len the size of `dst` in bytes, at least `skb_result_view_warnings_length` + 1.
/// @return SKB_OK; SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_result_copy_view_warnings(
    result: *const skb_result,
    dst: *mut c_char,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let r = &try_status!(try_ref(result, "result")).inner;
            try_status!(write_c_string(dst, dst_len, &warnings_text(r), "dst"));
            skb_status::SKB_OK
        }
    }
}

/// The view warnings as one `\n`-separated text.
fn warnings_text(r: &PipelineResult) -> String {
    r.view_warnings.join("\n")
}

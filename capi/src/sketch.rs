//! `skb_context_render_sketch`: a synthetic concept sketch of a body for plug-in previews, with its 2-D
//! joints; `skb_sketch_options` chooses the style and camera.

use std::sync::Arc;

use sketchbody_core::body::Gender;
use sketchbody_core::error::Error;
use sketchbody_core::image::ImageView;
use sketchbody_core::render::sketch::{CameraAngles, SketchRenderer, SketchRequest, SketchStyle};
use sketchbody_core::skeleton::NUM_JOINTS;

use super::body::skb_context;
use super::error::{fail, fail_with};
use super::ptr::*;
use super::status::skb_status;

/// Style: a random style drawn from the seed (costume, hair, shading, clutter, proportions).
pub const SKB_SKETCH_STYLE_RANDOM: u32 = 0;
/// Style: clean line art (no costume, hair, shading or clutter, white paper).
pub const SKB_SKETCH_STYLE_CLEAN: u32 = 1;

/// Options of [`skb_context_render_sketch`]: the style and the camera angles. Create with
/// `skb_sketch_options_new` (random style, random near-frontal camera), release with
/// `skb_sketch_options_free`. Setters need exclusive use; a configured handle may be read by
/// several threads at once.
pub struct skb_sketch_options {
    style: u32,
    camera: Option<CameraAngles>,
}

/// Creates sketch options with the defaults (random style, random near-frontal camera).
/// @param out receives a new options handle the caller owns (release with
///            `skb_sketch_options_free`); not NULL.
/// @return SKB_OK; SKB_ERR_NULL_POINTER for a NULL `out`.
#[no_mangle]
pub unsafe extern "C" fn skb_sketch_options_new(out: *mut *mut skb_sketch_options) -> skb_status {
    unsafe {
        ffi_boundary! {
            let out = try_status!(out_slot(out));
            give(out, skb_sketch_options { style: SKB_SKETCH_STYLE_RANDOM, camera: None })
        }
    }
}

/// Releases sketch options.
/// @param opts the options to release; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_sketch_options_free(opts: *mut skb_sketch_options) {
    unsafe { free_box(opts) }
}

/// Sets the sketch style.
/// @param opts the options, changed.
/// @param style `SKB_SKETCH_STYLE_RANDOM` (the default) or `SKB_SKETCH_STYLE_CLEAN`.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_sketch_options_set_style(opts: *mut skb_sketch_options, style: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            let o = try_status!(try_mut(opts, "opts"));
            if style > SKB_SKETCH_STYLE_CLEAN {
                return fail(&Error::OutOfRange { name: "sketch style", detail: format!("{style} (expected 0 random or 1 clean)") });
            }
            o.style = style;
            skb_status::SKB_OK
        }
    }
}

/// Fixes the camera angles (rotation `Rz(roll) Rx(pitch) Ry(yaw)`) instead of random
/// near-frontal ones (yaw ±30°, pitch ±10°, roll ±5°).
/// @param opts the options, changed.
/// @param yaw_deg degrees within ±180° (±180° a back view, −90° a left profile).
/// @param pitch_deg degrees within ±90°.
/// @param roll_deg degrees within ±90°.
/// @return SKB_OK; SKB_ERR_NON_FINITE for a non-finite angle; SKB_ERR_OUT_OF_RANGE for an angle
///         beyond its limit; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_sketch_options_set_camera(
    opts: *mut skb_sketch_options,
    yaw_deg: f64,
    pitch_deg: f64,
    roll_deg: f64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let o = try_status!(try_mut(opts, "opts"));
            let a = CameraAngles { yaw_deg, pitch_deg, roll_deg };
            try_core!(a.rotation());
            o.camera = Some(a);
            skb_status::SKB_OK
        }
    }
}

/// Renders a gray sketch (0 ink … 255 paper) of a body. Every random choice comes from `seed`.
/// Nothing is written on failure. Thread-safe for distinct output buffers; builds its edge
/// tables on each call (a few ms).
/// @param ctx the context, only read.
/// @param gender `SKB_GENDER_*`.
/// @param weights `n_weights` PCA shape weights.
/// @param n_weights the number of weights; 0: a random shape from the model's prior.
/// @param joints3d 15 × x y z metres, +Y up, canonical order (only the bone directions are
///                 used); NULL: a random procedural pose.
/// @param seed the seed of every random choice.
/// @param width the image width in pixels, 1..=4096.
/// @param height the image height in pixels, 1..=4096.
/// @param opts sketch options, only read, or NULL (random style and camera).
/// @param out_pixels receives the image; not NULL.
/// @param out_stride bytes between the starts of consecutive rows, ≥ `width`.
/// @param out_len the size of `out_pixels` in bytes.
/// @param out_joints2d receives the 15 projected joints (15 × x y pixels); may be NULL.
/// @param out_visible receives their visibility (15 bytes: 1 visible, 0 hidden by another body
///                    part); may be NULL.
/// @return SKB_OK; SKB_ERR_NULL_POINTER for a NULL context or pixels; SKB_ERR_OUT_OF_RANGE for
///         an unknown gender or too many weights; SKB_ERR_NON_FINITE for non-finite weights or
///         joints; SKB_ERR_DEGENERATE_BONE for zero-length bones; errors for sizes outside
///         1..=4096, a short stride or buffer; argument errors as docs/c-api.md.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn skb_context_render_sketch(
    ctx: *const skb_context,
    gender: u32,
    weights: *const f32,
    n_weights: usize,
    joints3d: *const f64,
    seed: u64,
    width: u32,
    height: u32,
    opts: *const skb_sketch_options,
    out_pixels: *mut u8,
    out_stride: usize,
    out_len: usize,
    out_joints2d: *mut f64,
    out_visible: *mut u8,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let ctx = try_status!(try_ref(ctx, "ctx"));
            let g = try_core!(Gender::from_index(gender));
            let (w, h) = (width as usize, height as usize);
            try_core!(sketchbody_core::raster::check_size(w, h));
            let needed = try_core!(ImageView::required_len(w, h, 1, out_stride));
            if out_pixels.is_null() {
                return fail_with(skb_status::SKB_ERR_NULL_POINTER, "out_pixels is NULL");
            }
            if out_len < needed {
                return fail(&Error::BufferTooSmall { name: "out_pixels", len: out_len, needed, unit: "bytes" });
            }
            let shape_weights = if n_weights == 0 {
                None
            } else {
                let s = try_status!(try_slice_of(weights, n_weights, "weights"));
                Some(s.iter().map(|&x| x as f64).collect::<Vec<f64>>())
            };
            let joints = if joints3d.is_null() {
                None
            } else {
                let s = try_status!(try_slice_of(joints3d, 3 * NUM_JOINTS, "joints3d"));
                Some(std::array::from_fn(|k| [s[3 * k], s[3 * k + 1], s[3 * k + 2]]))
            };
            let (style, camera) = match opt_ref(opts) {
                Some(o) => ((o.style == SKB_SKETCH_STYLE_CLEAN).then(SketchStyle::default), o.camera),
                None => (None, None),
            };
            let renderer = try_core!(SketchRenderer::new(Arc::clone(&ctx.model), None));
            let req = SketchRequest { seed, width: w, height: h, gender: Some(g), shape_weights, joints, camera, style };
            let sketch = try_core!(renderer.render(&req));
            let px = try_status!(try_slice_mut(out_pixels, out_len, "out_pixels"));
            for (row, src) in sketch.pixels.chunks(w).enumerate() {
                px[row * out_stride..row * out_stride + w].copy_from_slice(src);
            }
            if let Some(j) = try_status!(opt_slice_mut(out_joints2d, 2 * NUM_JOINTS, "out_joints2d")) {
                for (k, p) in sketch.truth.joints2d.iter().enumerate() {
                    j[2 * k] = p[0];
                    j[2 * k + 1] = p[1];
                }
            }
            if let Some(v) = try_status!(opt_slice_mut(out_visible, NUM_JOINTS, "out_visible")) {
                for (k, &vis) in sketch.truth.visible.iter().enumerate() {
                    v[k] = vis as u8;
                }
            }
            skb_status::SKB_OK
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{skb_context_free, skb_context_new};

    #[test]
    fn renders_into_a_strided_buffer_and_rejects_bad_input() {
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        unsafe {
            let mut ctx = std::ptr::null_mut();
            assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
            let mut opts = std::ptr::null_mut();
            assert_eq!(skb_sketch_options_new(&mut opts), skb_status::SKB_OK);
            assert_eq!(skb_sketch_options_set_style(opts, SKB_SKETCH_STYLE_CLEAN), skb_status::SKB_OK);
            assert_eq!(skb_sketch_options_set_style(opts, 7), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_sketch_options_set_camera(opts, 0.0, f64::NAN, 0.0), skb_status::SKB_ERR_NON_FINITE);
            assert_eq!(skb_sketch_options_set_camera(opts, 10.0, 0.0, 0.0), skb_status::SKB_OK);
            let (w, h, stride) = (96u32, 128u32, 100usize);
            let mut px = vec![7u8; stride * h as usize];
            let mut j2 = [0.0f64; 30];
            let mut vis = [9u8; 15];
            let st = skb_context_render_sketch(
                ctx,
                1,
                std::ptr::null(),
                0,
                std::ptr::null(),
                5,
                w,
                h,
                opts,
                px.as_mut_ptr(),
                stride,
                px.len(),
                j2.as_mut_ptr(),
                vis.as_mut_ptr(),
            );
            assert_eq!(st, skb_status::SKB_OK);
            assert!(px.chunks(stride).all(|r| r[96..].iter().all(|&p| p == 7)), "padding untouched");
            assert!(px.iter().any(|&p| p < 100), "some ink");
            assert!(j2.chunks(2).all(|p| p[0] > 0.0 && p[0] < 96.0 && p[1] > 0.0 && p[1] < 128.0));
            assert!(vis.iter().all(|&v| v <= 1) && vis.iter().filter(|&&v| v == 1).count() >= 8);
            let (pp, full) = (px.as_mut_ptr(), px.len());
            let bad = |g: u32, w: u32, len: usize| {
                skb_context_render_sketch(
                    ctx,
                    g,
                    std::ptr::null(),
                    0,
                    std::ptr::null(),
                    5,
                    w,
                    h,
                    opts,
                    pp,
                    stride,
                    len,
                    std::ptr::null_mut(),
                    std::ptr::null_mut(),
                )
            };
            assert_eq!(bad(2, 96, full), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(bad(0, 0, full), skb_status::SKB_ERR_EMPTY_IMAGE);
            assert_eq!(bad(0, 96, 10), skb_status::SKB_ERR_BUFFER_TOO_SMALL);
            assert_eq!(bad(0, 101, full), skb_status::SKB_ERR_BAD_STRIDE);
            let nan_joints = [f64::NAN; 45];
            let st = skb_context_render_sketch(
                ctx,
                0,
                std::ptr::null(),
                0,
                nan_joints.as_ptr(),
                5,
                w,
                h,
                opts,
                px.as_mut_ptr(),
                stride,
                px.len(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            );
            assert_eq!(st, skb_status::SKB_ERR_NON_FINITE);
            let many = [0.0f32; 1000];
            let st = skb_context_render_sketch(
                ctx,
                0,
                many.as_ptr(),
                1000,
                std::ptr::null(),
                5,
                w,
                h,
                opts,
                px.as_mut_ptr(),
                stride,
                px.len(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            );
            assert_eq!(st, skb_status::SKB_ERR_OUT_OF_RANGE);
            let st = skb_context_render_sketch(
                std::ptr::null(),
                0,
                std::ptr::null(),
                0,
                std::ptr::null(),
                5,
                w,
                h,
                opts,
                px.as_mut_ptr(),
                stride,
                px.len(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            );
            assert_eq!(st, skb_status::SKB_ERR_NULL_POINTER);
            skb_sketch_options_free(opts);
            skb_sketch_options_free(std::ptr::null_mut());
            skb_context_free(ctx);
        }
    }
}

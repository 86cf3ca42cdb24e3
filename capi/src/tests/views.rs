//! `skb_pipeline_run_views` and the result's view getters as a C host calls them, on a
//! turnaround the synthetic renderer draws (the same body and pose from the front and the side):
//! the C result equals the core's turnaround run, each view reads back with its label, joints and
//! turned camera, and each bad input has its own status.

use std::ffi::{c_char, CStr};
use std::ptr;
use std::sync::Arc;

use sketchbody_core::body::{BodyModel, Gender};
use sketchbody_core::fit::FitOptions;
use sketchbody_core::image::GrayImage;
use sketchbody_core::pipeline::{run_pipeline_views, GivenJoints, PipelineOptions, ViewInput};
use sketchbody_core::pose::dict_io;
use sketchbody_core::render::sketch::{CameraAngles, Sketch, SketchRenderer, SketchRequest};
use sketchbody_core::view::ViewLabel;

use crate::*;

fn last_error() -> String {
    // SAFETY: skb_last_error_message never returns NULL; the text lives until the next call.
    unsafe { CStr::from_ptr(skb_last_error_message()) }.to_string_lossy().into_owned()
}

/// The same female body and pose drawn from the front (yaw 0°) and the side (yaw 90°).
fn turnaround() -> (Sketch, Sketch) {
    let renderer = SketchRenderer::new(Arc::new(BodyModel::embedded().unwrap()), None).unwrap();
    let render = |yaw_deg: f64| {
        let req = SketchRequest {
            gender: Some(Gender::Female),
            camera: Some(CameraAngles { yaw_deg, pitch_deg: 0.0, roll_deg: 0.0 }),
            ..SketchRequest::random(11, 256)
        };
        renderer.render(&req).unwrap()
    };
    (render(0.0), render(90.0))
}

fn joints(s: &Sketch) -> skb_joints2d {
    skb_joints2d { xy: std::array::from_fn(|k| s.truth.joints2d[k]), visible: [1; 15], reserved: 0 }
}

fn image(s: &Sketch) -> skb_image {
    let (w, h) = (s.truth.width as u32, s.truth.height as u32);
    skb_image { data: s.pixels.as_ptr(), width: w, height: h, stride: w, channels: 1 }
}

/// A context and short fit options (24 samples, 2 iterations, female), freed on drop.
struct Setup {
    ctx: *mut skb_context,
    opts: *mut skb_fit_options,
}

impl Setup {
    fn new() -> Setup {
        // SAFETY: the out-pointers are live locals; the handles are freed once, on drop.
        unsafe {
            let (mut ctx, mut opts) = (ptr::null_mut(), ptr::null_mut());
            assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
            assert_eq!(skb_fit_options_new(&mut opts), skb_status::SKB_OK);
            assert_eq!(skb_fit_options_set_samples(opts, 24), skb_status::SKB_OK);
            assert_eq!(skb_fit_options_set_iterations(opts, 2), skb_status::SKB_OK);
            assert_eq!(skb_fit_options_set_gender(opts, SKB_GENDER_FEMALE), skb_status::SKB_OK);
            Setup { ctx, opts }
        }
    }

    /// `skb_pipeline_run_views` on `front` with `views`; the status and the result (NULL on error).
    fn run(&self, front: &skb_image, joints: &skb_joints2d, views: &[skb_view_input]) -> (skb_status, *mut skb_result) {
        let mut out = ptr::null_mut();
        let views_ptr = if views.is_empty() { ptr::null() } else { views.as_ptr() };
        // SAFETY: every pointer is a live local or handle; `views` holds `views.len()` entries.
        let st = unsafe {
            skb_pipeline_run_views(
                self.ctx,
                front,
                joints,
                views_ptr,
                views.len(),
                ptr::null(),
                ptr::null(),
                self.opts,
                None,
                None,
                ptr::null_mut(),
                &mut out,
            )
        };
        (st, out)
    }
}

impl Drop for Setup {
    fn drop(&mut self) {
        // SAFETY: both handles came from their constructors and are freed once.
        unsafe {
            skb_fit_options_free(self.opts);
            skb_context_free(self.ctx);
        }
    }
}

fn vertices(r: *const skb_result) -> Vec<f32> {
    // SAFETY: `r` is a live result; the buffer holds the vertex count's 3 floats each.
    unsafe {
        let (mut nv, mut nf) = (0usize, 0usize);
        assert_eq!(skb_result_vertex_count(r, &mut nv), skb_status::SKB_OK);
        assert_eq!(skb_result_face_count(r, &mut nf), skb_status::SKB_OK);
        let mut v = vec![0.0f32; 3 * nv];
        assert_eq!(skb_result_copy_vertices(r, true, v.as_mut_ptr(), v.len()), skb_status::SKB_OK);
        v
    }
}

#[test]
fn a_turnaround_through_the_c_api_is_the_core_run_with_each_view_read_back() {
    let (front, side) = turnaround();
    let s = Setup::new();
    let (fj, sj) = (joints(&front), joints(&side));
    let (fi, si) = (image(&front), image(&side));
    let views = [skb_view_input { label: SKB_VIEW_SIDE, reserved: 0, sketch: &si, joints: &sj }];
    let (st, two) = s.run(&fi, &fj, &views);
    assert_eq!(st, skb_status::SKB_OK, "{}", last_error());

    // The core's turnaround run with the same inputs and options gives the same body.
    let model = BodyModel::embedded().unwrap();
    let dict = dict_io::embedded().unwrap();
    let gray = |s: &Sketch| GrayImage::from_vec(s.truth.width, s.truth.height, s.pixels.clone()).unwrap();
    let (front_img, side_img) = (gray(&front), gray(&side));
    let options = PipelineOptions {
        fit: FitOptions { samples: 24, max_iterations: 2, ..FitOptions::default() },
        gender: Some(Gender::Female),
        ..PipelineOptions::default()
    };
    let (cf, cs) = (GivenJoints(crate::pose::joints_in(&fj)), GivenJoints(crate::pose::joints_in(&sj)));
    let core_views = [ViewInput { label: ViewLabel::Side, sketch: &side_img, source: &cs }];
    let core = run_pipeline_views(&model, &dict, &front_img, &cf, &core_views, &options, &mut |_| true, None).unwrap();
    let expected: Vec<f32> = core.posed_vertices.iter().flat_map(|v| *v).collect();
    assert_eq!(vertices(two), expected, "the C API's turnaround body is the core's");

    // SAFETY: `two` is a live result; the out-values are live locals.
    unsafe {
        let mut n = 9usize;
        assert_eq!(skb_result_view_count(two, &mut n), skb_status::SKB_OK);
        assert_eq!(n, 1);
        let mut info: skb_view_info = std::mem::zeroed();
        assert_eq!(skb_result_view(two, 0, &mut info), skb_status::SKB_OK);
        assert_eq!((info.label, info.joints_detected, info.joints_swapped), (SKB_VIEW_SIDE, 0, 0));
        assert_eq!(info.joints.xy, sj.xy, "the view's given joints");
        let mut cam: skb_camera = std::mem::zeroed();
        assert_eq!(skb_result_camera(two, &mut cam), skb_status::SKB_OK);
        let rel = sketchbody_core::camera::WeakPerspective::from(&cam).r.transpose()
            * nalgebra::Matrix3::from_row_slice(&info.camera.r);
        let angle = ((rel.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
        let axis =
            nalgebra::Vector3::new(rel[(2, 1)] - rel[(1, 2)], rel[(0, 2)] - rel[(2, 0)], rel[(1, 0)] - rel[(0, 1)]);
        assert!((angle - 90.0).abs() < 1e-6, "the side camera is the front's turned by 90°, not {angle}°");
        assert!(axis.normalize().y > 0.9, "about the body's (tilted) vertical: {axis:?}");
        assert!(info.residual < 0.05 && (info.scale_ratio - 1.0).abs() < 0.05, "{info:?}");
        assert!(info.edge_support > 0.3, "{info:?}");
        assert!(info.facing_as_labelled_deg < info.facing_other_side_deg, "{info:?}");
        assert_eq!(skb_result_view(two, 1, &mut info), skb_status::SKB_ERR_OUT_OF_RANGE);

        // Warnings: the length first, then the text; a short buffer is refused.
        let mut len = 99usize;
        assert_eq!(skb_result_view_warnings_length(two, &mut len), skb_status::SKB_OK);
        assert_eq!(len, core.view_warnings.join("\n").len());
        let mut buf = vec![1 as c_char; len + 1];
        assert_eq!(skb_result_copy_view_warnings(two, buf.as_mut_ptr(), buf.len()), skb_status::SKB_OK);
        assert_eq!(CStr::from_ptr(buf.as_ptr()).to_str().unwrap(), core.view_warnings.join("\n"));
        assert_eq!(skb_result_copy_view_warnings(two, buf.as_mut_ptr(), len), skb_status::SKB_ERR_BUFFER_TOO_SMALL);
        skb_result_free(two);
    }

    // No views: the one-view run, with no views to read.
    let (st, one) = s.run(&fi, &fj, &[]);
    assert_eq!(st, skb_status::SKB_OK, "{}", last_error());
    // SAFETY: `one` is a live result; the out-value is a live local.
    unsafe {
        let mut n = 9usize;
        assert_eq!(skb_result_view_count(one, &mut n), skb_status::SKB_OK);
        assert_eq!(n, 0);
        skb_result_free(one);
    }
}

#[test]
fn bad_views_each_have_their_own_status_and_leave_no_result() {
    let (front, side) = turnaround();
    let s = Setup::new();
    let (fj, sj) = (joints(&front), joints(&side));
    let (fi, si) = (image(&front), image(&side));
    let view = |label: u32, joints: *const skb_joints2d| skb_view_input { label, reserved: 0, sketch: &si, joints };
    let mut upside_down = sj;
    for p in upside_down.xy.iter_mut() {
        p[1] = 256.0 - p[1];
    }
    let cases: [(&str, Vec<skb_view_input>, skb_status, &str); 5] = [
        ("front as a view", vec![view(SKB_VIEW_FRONT, &sj)], skb_status::SKB_ERR_OUT_OF_RANGE, "front view"),
        ("unknown label", vec![view(7, &sj)], skb_status::SKB_ERR_OUT_OF_RANGE, "SKB_VIEW_"),
        (
            "side twice",
            vec![view(SKB_VIEW_SIDE, &sj), view(SKB_VIEW_SIDE, &sj)],
            skb_status::SKB_ERR_OUT_OF_RANGE,
            "two side",
        ),
        (
            "another figure",
            vec![view(SKB_VIEW_SIDE, &upside_down)],
            skb_status::SKB_ERR_VIEWS_DISAGREE,
            "side view disagrees",
        ),
        (
            "drawn facing the other way",
            vec![view(SKB_VIEW_SIDE_LEFT, &sj)],
            skb_status::SKB_ERR_VIEWS_DISAGREE,
            "label it side",
        ),
    ];
    for (what, views, status, text) in cases {
        let (st, out) = s.run(&fi, &fj, &views);
        assert_eq!(st, status, "{what}: {}", last_error());
        assert!(out.is_null(), "{what}: no result on error");
        assert!(last_error().contains(text), "{what}: {}", last_error());
    }
    // A view count with no views, and a view without its image.
    let mut out = ptr::null_mut();
    // SAFETY: NULL views with a count and a view with a NULL sketch: the library checks both.
    unsafe {
        let st = skb_pipeline_run_views(
            s.ctx,
            &fi,
            &fj,
            ptr::null(),
            1,
            ptr::null(),
            ptr::null(),
            s.opts,
            None,
            None,
            ptr::null_mut(),
            &mut out,
        );
        assert_eq!(st, skb_status::SKB_ERR_NULL_POINTER);
        let no_image = [skb_view_input { label: SKB_VIEW_SIDE, reserved: 0, sketch: ptr::null(), joints: &sj }];
        let (st, out2) = s.run(&fi, &fj, &no_image);
        assert_eq!(st, skb_status::SKB_ERR_NULL_POINTER);
        assert!(out.is_null() && out2.is_null());
    }
}

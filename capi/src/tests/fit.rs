//! `skb_fit_options`, `skb_context_fit_shape` and `skb_pipeline_run` / `skb_result_*` through the C API
//! as a C host would: results, cancellation through the progress callback, and the specific
//! status of each bad input.

use std::ffi::{c_int, c_void, CStr, CString};
use std::ptr;

use crate::*;

const SKETCH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch.png");
const JOINTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch_joints.json");

fn last_error() -> String {
    // SAFETY: skb_last_error_message never returns NULL; the text lives until the next call.
    unsafe { CStr::from_ptr(skb_last_error_message()) }.to_string_lossy().into_owned()
}

fn joints() -> skb_joints2d {
    let j = sketchbody_core::export::joints2d::load_joints2d(std::path::Path::new(JOINTS)).unwrap();
    skb_joints2d { xy: j.xy, visible: [1; 15], reserved: 0 }
}

struct Inputs {
    ctx: *mut skb_context,
    img: *mut skb_gray_image,
    view: skb_image,
    opts: *mut skb_fit_options,
}

impl Inputs {
    fn new() -> Inputs {
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        unsafe {
            let mut ctx = ptr::null_mut();
            assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
            let mut img = ptr::null_mut();
            let path = CString::new(SKETCH).unwrap();
            assert_eq!(skb_gray_image_new_from_file(path.as_ptr(), &mut img), skb_status::SKB_OK, "{}", last_error());
            let mut view: skb_image = std::mem::zeroed();
            assert_eq!(skb_gray_image_view(img, &mut view), skb_status::SKB_OK);
            let mut opts = ptr::null_mut();
            assert_eq!(skb_fit_options_new(&mut opts), skb_status::SKB_OK);
            assert_eq!(skb_fit_options_set_samples(opts, 24), skb_status::SKB_OK);
            assert_eq!(skb_fit_options_set_iterations(opts, 2), skb_status::SKB_OK);
            Inputs { ctx, img, view, opts }
        }
    }
}

impl Drop for Inputs {
    fn drop(&mut self) {
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        unsafe {
            skb_fit_options_free(self.opts);
            skb_gray_image_free(self.img);
            skb_context_free(self.ctx);
        }
    }
}

unsafe extern "C" fn count_calls(user: *mut c_void, fraction: f32) -> c_int {
    // SAFETY: the test passes `user` as a pointer to this local, alive for the whole fit.
    let v = unsafe { &mut *(user as *mut Vec<f32>) };
    v.push(fraction);
    0
}

unsafe extern "C" fn cancel_in_fit(user: *mut c_void, fraction: f32) -> c_int {
    // SAFETY: the test passes `user` as a pointer to this local, alive for the whole fit.
    unsafe { *(user as *mut usize) += 1 };
    (fraction > 0.06) as c_int
}

#[test]
fn options_setters_validate() {
    let i = Inputs::new();
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        assert_eq!(skb_fit_options_set_samples(i.opts, 1), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_iterations(i.opts, 0), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_transition_scale(i.opts, f64::NAN), skb_status::SKB_ERR_NON_FINITE);
        assert_eq!(skb_fit_options_set_temperature(i.opts, -1.0), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert!(last_error().contains("temperature"), "{}", last_error());
        assert_eq!(skb_fit_options_set_joint_weight(i.opts, -0.1), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_joint_weight(i.opts, f64::NAN), skb_status::SKB_ERR_NON_FINITE);
        assert!(last_error().contains("joint weight"), "{}", last_error());
        assert_eq!(skb_fit_options_set_joint_weight(i.opts, 0.0), skb_status::SKB_OK);
        assert_eq!(skb_fit_options_set_inside_cap(i.opts, 0.0), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_inside_cap(i.opts, f64::NAN), skb_status::SKB_ERR_NON_FINITE);
        assert!(last_error().contains("inside cap"), "{}", last_error());
        assert_eq!(skb_fit_options_set_inside_cap(i.opts, 4.0), skb_status::SKB_OK);
        assert_eq!(skb_fit_options_set_height(i.opts, -1.7), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_height(i.opts, 12.0), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_height(i.opts, f64::NAN), skb_status::SKB_ERR_NON_FINITE);
        assert!(last_error().contains("height"), "{}", last_error());
        assert_eq!(skb_fit_options_set_height(ptr::null_mut(), 1.7), skb_status::SKB_ERR_NULL_POINTER);
        assert_eq!(skb_fit_options_set_proportion_sd(i.opts, 0.7), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_proportion_sd(i.opts, f64::NAN), skb_status::SKB_ERR_NON_FINITE);
        assert!(last_error().contains("proportion sd"), "{}", last_error());
        assert_eq!(skb_fit_options_set_tolerance(i.opts, 0.0), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_raster_side(i.opts, 8), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_score(i.opts, 4), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_skinning(i.opts, 2), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_gender(i.opts, 3), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert_eq!(skb_fit_options_set_samples(ptr::null_mut(), 10), skb_status::SKB_ERR_NULL_POINTER);
        assert_eq!(skb_fit_options_set_estimate_proportions(ptr::null_mut(), true), skb_status::SKB_ERR_NULL_POINTER);
        for ok in [
            skb_fit_options_set_score(i.opts, SKB_SCORE_PAPER),
            skb_fit_options_set_score(i.opts, SKB_SCORE_TWO_SIDED_CHAMFER),
            skb_fit_options_set_score(i.opts, SKB_SCORE_CHAMFER),
            skb_fit_options_set_skinning(i.opts, SKB_SKIN_DUAL_QUATERNION),
            skb_fit_options_set_skinning(i.opts, SKB_SKIN_LINEAR),
            skb_fit_options_set_seed(i.opts, 99),
            skb_fit_options_set_dims(i.opts, 0),
            skb_fit_options_set_transition_scale(i.opts, 0.5),
            skb_fit_options_set_temperature(i.opts, 0.05),
            skb_fit_options_set_tolerance(i.opts, 0.01),
            skb_fit_options_set_raster_side(i.opts, 128),
            skb_fit_options_set_gender(i.opts, SKB_GENDER_AUTO),
            skb_fit_options_set_height(i.opts, 1.8),
            skb_fit_options_set_height(i.opts, 0.0),
            skb_fit_options_set_sample_camera(i.opts, true),
            skb_fit_options_set_sample_camera(i.opts, false),
            skb_fit_options_set_proportion_sd(i.opts, 0.0),
            skb_fit_options_set_proportion_sd(i.opts, 0.1),
            skb_fit_options_set_estimate_proportions(i.opts, false),
            skb_fit_options_set_estimate_proportions(i.opts, true),
        ] {
            assert_eq!(ok, skb_status::SKB_OK);
        }
    }
}

#[test]
fn pipeline_result_accessors() {
    let i = Inputs::new();
    let j = joints();
    let mut calls: Vec<f32> = Vec::new();
    let mut r = ptr::null_mut();
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        let st = skb_pipeline_run(
            i.ctx,
            &i.view,
            &j,
            ptr::null(),
            ptr::null(),
            i.opts,
            Some(count_calls),
            &mut calls as *mut _ as *mut c_void,
            &mut r,
        );
        assert_eq!(st, skb_status::SKB_OK, "{}", last_error());
        assert!(calls.windows(2).all(|w| w[0] <= w[1]) && *calls.last().unwrap() == 1.0, "{calls:?}");
        let (mut nv, mut nf) = (0usize, 0usize);
        assert_eq!(skb_result_vertex_count(r, &mut nv), skb_status::SKB_OK);
        assert_eq!(skb_result_face_count(r, &mut nf), skb_status::SKB_OK);
        assert_eq!((nv, nf), (13380, 13378));
        let mut v = vec![0.0f32; 3 * nv];
        assert_eq!(
            skb_result_copy_vertices(r, true, v.as_mut_ptr(), v.len() - 1),
            skb_status::SKB_ERR_BUFFER_TOO_SMALL
        );
        assert_eq!(skb_result_copy_vertices(r, true, v.as_mut_ptr(), v.len()), skb_status::SKB_OK);
        assert!(v.iter().all(|x| x.is_finite()));
        let mut f = vec![0u32; 4 * nf];
        assert_eq!(skb_result_copy_faces(r, f.as_mut_ptr(), f.len()), skb_status::SKB_OK);
        assert!(f.iter().all(|&k| (k as usize) < nv));
        let mut j2: skb_joints2d = std::mem::zeroed();
        assert_eq!(skb_result_joints2d(r, &mut j2), skb_status::SKB_OK);
        assert_eq!(j2.xy, j.xy);
        let (mut posed, mut est) = ([0.0; 45], [0.0; 45]);
        assert_eq!(skb_result_copy_joints3d(r, SKB_JOINTS_POSED, posed.as_mut_ptr(), 45), skb_status::SKB_OK);
        assert_eq!(skb_result_copy_joints3d(r, SKB_JOINTS_ESTIMATED, est.as_mut_ptr(), 45), skb_status::SKB_OK);
        assert_eq!(skb_result_copy_joints3d(r, 3, est.as_mut_ptr(), 45), skb_status::SKB_ERR_OUT_OF_RANGE);
        assert!((posed[24] - est[24]).abs() < 1e-9, "pelvis is the IK root");
        let mut cam: skb_camera = std::mem::zeroed();
        assert_eq!(skb_result_camera(r, &mut cam), skb_status::SKB_OK);
        assert!(cam.sx > 100.0 && cam.sy > 100.0);
        let (mut bones, mut weights) = (vec![0u32; 4 * nv], vec![0.0f32; 4 * nv]);
        assert_eq!(
            skb_result_copy_skin_weights(r, bones.as_mut_ptr(), weights.as_mut_ptr(), bones.len()),
            skb_status::SKB_OK
        );
        assert!(weights.chunks(4).all(|w| (w.iter().sum::<f32>() - 1.0).abs() < 1e-4) && bones.iter().all(|&b| b < 14));
        let (mut g, mut by_score) = (9u32, false);
        assert_eq!(skb_result_gender(r, &mut g, &mut by_score), skb_status::SKB_OK);
        assert!(by_score && g <= 1);
        // One space is fitted (the both-sexes one): its score under the result's gender only.
        let mut sc = 0.0;
        assert_eq!(skb_result_score(r, g, &mut sc), skb_status::SKB_OK);
        assert!(sc.is_finite());
        assert_eq!(skb_result_score(r, 1 - g, &mut sc), skb_status::SKB_ERR_OUT_OF_RANGE);
        let (mut value, mut confidence) = (f64::NAN, f64::NAN);
        assert_eq!(skb_result_gender_value(r, &mut value, &mut confidence), skb_status::SKB_OK);
        assert!((0.0..=1.0).contains(&value) && (0.5..=1.0).contains(&confidence), "{value} {confidence}");
        assert_eq!(g == SKB_GENDER_MALE, value > 0.5);
        let (mut low, mut support) = (true, f64::NAN);
        assert_eq!(skb_result_evidence(r, &mut low, &mut support), skb_status::SKB_OK);
        assert!((0.0..=1.0).contains(&support) && low == (support < 0.5));
        // Per part: shares in 0..=1 (NaN only for a part out of view); the torso is always in
        // view, and the parts' shares bracket the whole outline's.
        let mut parts = [f64::NAN; SKB_NUM_BODY_PARTS as usize];
        assert_eq!(skb_result_copy_part_support(r, parts.as_mut_ptr(), parts.len()), skb_status::SKB_OK);
        assert!(parts.iter().all(|p| p.is_nan() || (0.0..=1.0).contains(p)), "{parts:?}");
        assert!(parts[1].is_finite(), "{parts:?}");
        let seen: Vec<f64> = parts.iter().copied().filter(|p| p.is_finite()).collect();
        assert!(seen.iter().copied().fold(1.0, f64::min) <= support + 1e-9, "{parts:?} {support}");
        assert!(seen.iter().copied().fold(0.0, f64::max) >= support - 1e-9, "{parts:?} {support}");
        let mut n = 0usize;
        assert_eq!(skb_result_shape_weight_count(r, &mut n), skb_status::SKB_OK);
        let mut w = vec![0.0; n];
        assert!(n > 0);
        assert_eq!(skb_result_copy_shape_weights(r, w.as_mut_ptr(), n - 1), skb_status::SKB_ERR_BUFFER_TOO_SMALL);
        assert_eq!(skb_result_copy_shape_weights(r, w.as_mut_ptr(), n), skb_status::SKB_OK);
        // The result as an skb_mesh: same posed vertices, exportable.
        let mut mesh = ptr::null_mut();
        assert_eq!(skb_mesh_new_from_result(r, &mut mesh), skb_status::SKB_OK);
        let mut mv = vec![0.0f32; 3 * nv];
        assert_eq!(skb_mesh_copy_posed_vertices(mesh, mv.as_mut_ptr(), mv.len()), skb_status::SKB_OK);
        assert_eq!(mv, v);
        let mut mw = vec![0.0; n];
        assert_eq!(skb_mesh_copy_shape_weights(mesh, mw.as_mut_ptr(), n), skb_status::SKB_OK);
        assert_eq!(mw, w);
        skb_mesh_free(mesh);
        skb_result_free(r);
        skb_result_free(ptr::null_mut());
        skb_gray_image_free(ptr::null_mut());
        skb_fit_options_free(ptr::null_mut());
    }
}

#[test]
fn pipeline_errors_and_cancel() {
    let i = Inputs::new();
    let j = joints();
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        let mut r = ptr::null_mut();
        let go = |img: &skb_image, jp: *const skb_joints2d, r: &mut *mut skb_result| {
            skb_pipeline_run(i.ctx, img, jp, ptr::null(), ptr::null(), i.opts, None, ptr::null_mut(), r)
        };
        let mut page = vec![255u8; 200 * 200];
        for k in 20..180 {
            page[k * 200 + 100] = 0; // one stroke: edges, but no figure
        }
        let pv = skb_image { data: page.as_ptr(), width: 200, height: 200, stride: 200, channels: 1 };
        assert_eq!(go(&pv, ptr::null(), &mut r), skb_status::SKB_ERR_NO_FIGURE);
        assert!(r.is_null());
        let mut out = j;
        out.xy[7] = [-5.0, 10.0];
        assert_eq!(go(&i.view, &out, &mut r), skb_status::SKB_ERR_JOINT_OUTSIDE_IMAGE);
        let mut nan = j;
        nan.xy[2] = [f64::NAN, 10.0];
        assert_eq!(go(&i.view, &nan, &mut r), skb_status::SKB_ERR_NON_FINITE);
        let blank = vec![200u8; 100 * 100];
        let bv = skb_image { data: blank.as_ptr(), width: 100, height: 100, stride: 100, channels: 1 };
        assert_eq!(go(&bv, &j, &mut r), skb_status::SKB_ERR_BLANK_IMAGE);
        let tv = skb_image { width: 20, height: 20, ..bv };
        assert_eq!(go(&tv, &j, &mut r), skb_status::SKB_ERR_IMAGE_TOO_SMALL);
        assert!(r.is_null(), "no result on error");
        assert_eq!(skb_fit_options_set_iterations(i.opts, 100), skb_status::SKB_OK);
        assert_eq!(skb_fit_options_set_samples(i.opts, 200), skb_status::SKB_OK);
        let mut calls = 0usize;
        let st = skb_pipeline_run(
            i.ctx,
            &i.view,
            &j,
            ptr::null(),
            ptr::null(),
            i.opts,
            Some(cancel_in_fit),
            &mut calls as *mut _ as *mut c_void,
            &mut r,
        );
        assert_eq!(st, skb_status::SKB_ERR_CANCELLED);
        assert!(calls <= 5, "{calls} progress calls: the cancel was not prompt");
        assert!(r.is_null());
        let path = CString::new("/nonexistent/sketch.png").unwrap();
        let mut img = ptr::null_mut();
        assert_eq!(skb_gray_image_new_from_file(path.as_ptr(), &mut img), skb_status::SKB_ERR_IO);
    }
}

#[test]
fn fit_shape_from_c() {
    let i = Inputs::new();
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        // Pose and camera from the pose step, edges from Canny, as a host chaining the steps.
        let mut dict = ptr::null_mut();
        assert_eq!(skb_pose_dictionary_new_default(&mut dict), skb_status::SKB_OK);
        let mut pose: skb_pose3d = std::mem::zeroed();
        assert_eq!(skb_pose3d_estimate(dict, &joints(), ptr::null(), &mut pose), skb_status::SKB_OK);
        skb_pose_dictionary_free(dict);
        let (w, h) = (i.view.width as usize, i.view.height as usize);
        let mut edges = vec![0u8; w * h];
        assert_eq!(
            skb_image_canny(&i.view, 50.0, 150.0, 3, false, edges.as_mut_ptr(), w, edges.len()),
            skb_status::SKB_OK
        );
        let ev = skb_image { data: edges.as_ptr(), width: w as u32, height: h as u32, stride: w as u32, channels: 1 };
        let cam = skb_camera { sx: pose.sx, sy: pose.sy, r: pose.r, t: pose.t };
        let flat: Vec<f64> = pose.joints.iter().flatten().copied().collect();
        assert_eq!(skb_fit_options_set_gender(i.opts, SKB_GENDER_MALE), skb_status::SKB_OK);
        let (mut mesh, mut score) = (ptr::null_mut(), 0.0);
        let st = skb_context_fit_shape(
            i.ctx,
            flat.as_ptr(),
            45,
            &cam,
            &ev,
            i.opts,
            None,
            ptr::null_mut(),
            &mut score,
            &mut mesh,
        );
        assert_eq!(st, skb_status::SKB_OK, "{}", last_error());
        assert!(score.is_finite() && score < 0.0);
        let mut g = 9;
        assert_eq!(skb_mesh_gender(mesh, &mut g), skb_status::SKB_OK);
        assert_eq!(g, SKB_GENDER_MALE);
        let mut n = 0;
        assert_eq!(skb_mesh_shape_weight_count(mesh, &mut n), skb_status::SKB_OK);
        assert!(n > 0);
        let mut pj = [0.0; 45];
        assert_eq!(skb_mesh_copy_posed_joints(mesh, pj.as_mut_ptr(), 45), skb_status::SKB_OK);
        assert!((pj[24] - flat[24]).abs() < 1e-9);
        skb_mesh_free(mesh);
        // Bad input: each its own status, no mesh.
        let mut m2 = ptr::null_mut();
        let mut nan = flat.clone();
        nan[0] = f64::NAN;
        assert_eq!(
            skb_context_fit_shape(
                i.ctx,
                nan.as_ptr(),
                45,
                &cam,
                &ev,
                i.opts,
                None,
                ptr::null_mut(),
                ptr::null_mut(),
                &mut m2
            ),
            skb_status::SKB_ERR_NON_FINITE
        );
        assert_eq!(
            skb_context_fit_shape(
                i.ctx,
                flat.as_ptr(),
                44,
                &cam,
                &ev,
                i.opts,
                None,
                ptr::null_mut(),
                ptr::null_mut(),
                &mut m2
            ),
            skb_status::SKB_ERR_OUT_OF_RANGE
        );
        let bad_cam = skb_camera { sx: -1.0, ..cam };
        assert_eq!(
            skb_context_fit_shape(
                i.ctx,
                flat.as_ptr(),
                45,
                &bad_cam,
                &ev,
                i.opts,
                None,
                ptr::null_mut(),
                ptr::null_mut(),
                &mut m2
            ),
            skb_status::SKB_ERR_OUT_OF_RANGE
        );
        let zero = vec![0u8; w * h];
        let zv = skb_image { data: zero.as_ptr(), ..ev };
        assert_eq!(
            skb_context_fit_shape(
                i.ctx,
                flat.as_ptr(),
                45,
                &cam,
                &zv,
                i.opts,
                None,
                ptr::null_mut(),
                ptr::null_mut(),
                &mut m2
            ),
            skb_status::SKB_ERR_BLANK_IMAGE
        );
        let mut calls = 0usize;
        assert_eq!(skb_fit_options_set_iterations(i.opts, 100), skb_status::SKB_OK);
        unsafe extern "C" fn stop(user: *mut c_void, _f: f32) -> c_int {
            // SAFETY: the test passes `user` as a pointer to this local, alive for the whole fit.
            unsafe { *(user as *mut usize) += 1 };
            1
        }
        assert_eq!(
            skb_context_fit_shape(
                i.ctx,
                flat.as_ptr(),
                45,
                &cam,
                &ev,
                i.opts,
                Some(stop),
                &mut calls as *mut _ as *mut c_void,
                ptr::null_mut(),
                &mut m2
            ),
            skb_status::SKB_ERR_CANCELLED
        );
        assert_eq!(calls, 1, "cancelled at the first iteration");
        assert!(m2.is_null());
    }
}

/// What the interim test's callback records: per call, the stage, the mesh's gender, its
/// shape-weight count and its posed vertices.
type InterimLog = Vec<(u32, u32, usize, Vec<f32>)>;

unsafe extern "C" fn record_interim(user: *mut c_void, stage: u32, mesh: *const skb_mesh) {
    // SAFETY: the test passes `user` as a pointer to its log, alive for the whole run; `mesh`
    // is the library's borrowed mesh, valid during this call.
    unsafe {
        let log = &mut *(user as *mut InterimLog);
        let (mut g, mut nv, mut nk) = (9u32, 0usize, 0usize);
        assert_eq!(skb_mesh_gender(mesh, &mut g), skb_status::SKB_OK);
        assert_eq!(skb_mesh_vertex_count(mesh, &mut nv), skb_status::SKB_OK);
        assert_eq!(skb_mesh_shape_weight_count(mesh, &mut nk), skb_status::SKB_OK);
        let mut v = vec![0.0f32; 3 * nv];
        assert_eq!(skb_mesh_copy_posed_vertices(mesh, v.as_mut_ptr(), v.len()), skb_status::SKB_OK);
        log.push((stage, g, nk, v));
    }
}

/// The progressive run shows the posed mean shape, then the chosen gender's 4-dimension
/// deciding fit, as borrowed meshes, and ends with skb_pipeline_run's result.
#[test]
fn progressive_run_shows_interim_bodies_and_ends_as_the_plain_run() {
    let i = Inputs::new();
    let j = joints();
    let mut log: InterimLog = Vec::new();
    let (mut plain, mut progressive) = (ptr::null_mut(), ptr::null_mut());
    // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
    unsafe {
        let st =
            skb_pipeline_run(i.ctx, &i.view, &j, ptr::null(), ptr::null(), i.opts, None, ptr::null_mut(), &mut plain);
        assert_eq!(st, skb_status::SKB_OK, "{}", last_error());
        let st = skb_pipeline_run_progressive(
            i.ctx,
            &i.view,
            &j,
            ptr::null(),
            ptr::null(),
            i.opts,
            None,
            Some(record_interim),
            &mut log as *mut _ as *mut c_void,
            &mut progressive,
        );
        assert_eq!(st, skb_status::SKB_OK, "{}", last_error());
        let vertices = |r: *mut skb_result| {
            let (mut nv, mut nf) = (0usize, 0usize);
            assert_eq!(skb_result_vertex_count(r, &mut nv), skb_status::SKB_OK);
            assert_eq!(skb_result_face_count(r, &mut nf), skb_status::SKB_OK);
            let mut v = vec![0.0f32; 3 * nv];
            assert_eq!(skb_result_copy_vertices(r, true, v.as_mut_ptr(), v.len()), skb_status::SKB_OK);
            v
        };
        let final_vertices = vertices(progressive);
        assert_eq!(final_vertices, vertices(plain));
        let mut g = 9u32;
        let mut by_score = false;
        assert_eq!(skb_result_gender(progressive, &mut g, &mut by_score), skb_status::SKB_OK);
        let stages: Vec<(u32, usize)> = log.iter().map(|l| (l.0, l.2)).collect();
        assert_eq!(stages, [(SKB_INTERIM_MEAN_SHAPE, 0), (SKB_INTERIM_DECIDING_FIT, 4)]);
        assert_eq!(log[1].1, g, "the deciding fit of the chosen gender");
        assert!(log.iter().all(|l| l.3.len() == final_vertices.len() && l.3 != final_vertices));
        skb_result_free(plain);
        skb_result_free(progressive);
    }
}

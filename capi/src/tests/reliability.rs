//! Regression tests for the reliability audit (issue 20): each bad input ends in a specific
//! status with nothing written, and a panic is reported, not printed.

use std::ffi::{CStr, CString};
use std::ptr;

use crate::*;

fn last_error() -> String {
    // SAFETY: test code; each pointer is NULL or a live local of the documented size.
    unsafe { CStr::from_ptr(skb_last_error_message()) }.to_string_lossy().into_owned()
}

fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("skb-capi-rel-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Finding 1: a stride whose `stride * (height - 1)` wraps is refused before anything is
/// written, in Canny, the blur and the sketch renderer.
#[test]
fn wrapping_strides_are_refused_with_nothing_written() {
    let px = [128u8; 4 * 3];
    let im = skb_image { data: px.as_ptr(), width: 4, height: 3, stride: 4, channels: 1 };
    // (1 << 63) * 2 wraps to 0, so an unchecked length would be just `width` bytes.
    let stride = 1usize << 63;
    let mut dst = [0xA5u8; 64];
    // SAFETY: test code; each pointer is NULL or a live local of the documented size.
    unsafe {
        let s = skb_image_canny(&im, 50.0, 150.0, 3, false, dst.as_mut_ptr(), stride, dst.len());
        assert_eq!(s, skb_status::SKB_ERR_OUT_OF_RANGE, "{}", last_error());
        assert!(last_error().contains("stride"), "{}", last_error());
        let s = skb_image_gaussian_blur(&im, 1.0, dst.as_mut_ptr(), stride, dst.len());
        assert_eq!(s, skb_status::SKB_ERR_OUT_OF_RANGE, "{}", last_error());
        let mut ctx = ptr::null_mut();
        assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
        let s = skb_context_render_sketch(
            ctx,
            SKB_GENDER_MALE,
            ptr::null(),
            0,
            ptr::null(),
            1,
            4,
            3,
            ptr::null(),
            dst.as_mut_ptr(),
            stride,
            dst.len(),
            ptr::null_mut(),
            ptr::null_mut(),
        );
        assert_eq!(s, skb_status::SKB_ERR_OUT_OF_RANGE, "{}", last_error());
        skb_context_free(ctx);
    }
    assert!(dst.iter().all(|&b| b == 0xA5), "canary intact");
}

/// Finding 3: `/dev/zero` and a directory are refused at once (not read until memory runs out).
#[test]
fn image_loader_refuses_special_files() {
    for p in ["/dev/zero", "/tmp"] {
        let path = CString::new(p).unwrap();
        let mut out = ptr::null_mut();
        // SAFETY: test code; each pointer is NULL or a live local of the documented size.
        assert_eq!(unsafe { skb_gray_image_new_from_file(path.as_ptr(), &mut out) }, skb_status::SKB_ERR_IO, "{p}");
        assert!(out.is_null());
        assert!(last_error().contains("not a regular file"), "{}", last_error());
    }
}

/// Finding 4: joints x 1e300 give `SKB_ERR_NON_FINITE`, the mesh keeps its previous pose, and
/// the writers still write only finite vertices.
#[test]
fn overflowing_pose_is_a_status_not_ok() {
    let d = scratch("pose");
    // SAFETY: test code; each pointer is NULL or a live local of the documented size.
    unsafe {
        let mut ctx = ptr::null_mut();
        assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
        let mut mesh = ptr::null_mut();
        assert_eq!(skb_mesh_new_from_shape(ctx, SKB_GENDER_MALE, ptr::null(), 0, &mut mesh), skb_status::SKB_OK);
        let mut joints = [0f64; 45];
        assert_eq!(skb_mesh_copy_joints(mesh, joints.as_mut_ptr(), 45), skb_status::SKB_OK);
        let huge: Vec<f64> = joints.iter().map(|j| j * 1e300).collect();
        let s = skb_mesh_pose(mesh, huge.as_ptr(), 45, 0);
        assert_eq!(s, skb_status::SKB_ERR_NON_FINITE, "{}", last_error());
        let mut nv = 0;
        assert_eq!(skb_mesh_vertex_count(mesh, &mut nv), skb_status::SKB_OK);
        let mut v = vec![0f32; 3 * nv];
        assert_eq!(skb_mesh_copy_posed_vertices(mesh, v.as_mut_ptr(), v.len()), skb_status::SKB_OK);
        assert!(v.iter().all(|c| c.is_finite()), "the failed pose left no trace");
        let obj = CString::new(d.join("m.obj").to_str().unwrap()).unwrap();
        assert_eq!(skb_mesh_write_obj(mesh, obj.as_ptr(), true), skb_status::SKB_OK);
        skb_mesh_free(mesh);
        skb_context_free(ctx);
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// Finding 5: a symlink output path is refused and stays a symlink to the untouched target.
#[test]
fn glb_writer_refuses_a_symlink() {
    let d = scratch("link");
    let target = d.join("t.glb");
    std::fs::write(&target, b"keep").unwrap();
    let link = d.join("l.glb");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    // SAFETY: test code; each pointer is NULL or a live local of the documented size.
    unsafe {
        let mut ctx = ptr::null_mut();
        assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
        let mut mesh = ptr::null_mut();
        assert_eq!(skb_mesh_new_from_shape(ctx, SKB_GENDER_FEMALE, ptr::null(), 0, &mut mesh), skb_status::SKB_OK);
        let p = CString::new(link.to_str().unwrap()).unwrap();
        assert_eq!(skb_mesh_write_glb(mesh, p.as_ptr(), ptr::null()), skb_status::SKB_ERR_IO, "{}", last_error());
        assert!(last_error().contains("not a regular file"), "{}", last_error());
        skb_mesh_free(mesh);
        skb_context_free(ctx);
    }
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    assert_eq!(std::fs::read(&target).unwrap(), b"keep");
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 2, "no temporaries left");
    std::fs::remove_dir_all(&d).unwrap();
}

/// The boundary itself: a panic becomes `SKB_ERR_PANIC` whose message carries the text and the
/// source location, and the library stays usable.
fn panicking_export() -> skb_status {
    ffi_boundary! {
        let v: Vec<u8> = Vec::new();
        if v.is_empty() {
            panic!("deliberate test panic");
        }
        skb_status::SKB_OK
    }
}

/// Finding 8 (panic part): the message is captured for `skb_last_error_message` and the panic
/// is not printed. The printing half runs in a child process whose stderr is inspected.
#[test]
fn panics_are_captured_not_printed() {
    const CHILD: &str = "SKB_PANIC_QUIET_CHILD";
    let status = panicking_export();
    assert_eq!(status, skb_status::SKB_ERR_PANIC);
    let msg = last_error();
    assert!(msg.contains("deliberate test panic") && msg.contains("reliability.rs:"), "{msg}");
    if std::env::var_os(CHILD).is_some() {
        return;
    }
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "tests::reliability::panics_are_captured_not_printed", "--nocapture", "--test-threads=1"])
        .env(CHILD, "1")
        .env("RUST_BACKTRACE", "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "child failed: {stderr}");
    assert!(!stderr.contains("deliberate test panic"), "the panic was printed: {stderr}");
    assert!(String::from_utf8_lossy(&out.stdout).contains("1 passed"), "the child ran the test");
}

/// Progress of one detection: the call that cancels, calls so far and after cancelling.
struct DetectProgress {
    calls: usize,
    cancel_at: usize,
    after_cancel: usize,
}

unsafe extern "C" fn on_detect_progress(user: *mut std::ffi::c_void, _fraction: f32) -> std::ffi::c_int {
    // SAFETY: `user` is the `DetectProgress` the test passes with the call, alive for its duration.
    let p = unsafe { &mut *(user as *mut DetectProgress) };
    if p.calls > p.cancel_at {
        p.after_cancel += 1;
    }
    p.calls += 1;
    std::ffi::c_int::from(p.calls > p.cancel_at)
}

/// Issue 52 finding 10: a detector file with a bias of 1e308 (score +inf, joints outside the
/// image, reported OK) is refused on load; detection with a loaded model is cancellable at every
/// progress point (`SKB_ERR_CANCELLED`, nothing written, no call after the cancelling one).
#[test]
fn detector_models_are_bounded_and_detection_cancellable() {
    use sketchbody_core::detect::model::tiny_model;
    let dir = scratch("detector");
    let mut m = tiny_model();
    m.bias[1] = 1e308;
    let bad = dir.join("bias.skbd");
    // The writer does not validate; the reader does.
    std::fs::write(&bad, m.to_bytes()).unwrap();
    let good = dir.join("tiny.skbd");
    std::fs::write(&good, tiny_model().to_bytes()).unwrap();
    let px: Vec<u8> = (0..96 * 80).map(|i| if (i % 96) / 8 % 3 == 0 { 30 } else { 220 }).collect();
    let im = skb_image { data: px.as_ptr(), width: 96, height: 80, stride: 96, channels: 1 };
    // SAFETY: test code; each pointer is NULL or a live local of the documented size.
    unsafe {
        let mut det = ptr::null_mut();
        let p = CString::new(bad.to_str().unwrap()).unwrap();
        assert_eq!(skb_detector_new_from_file(p.as_ptr(), &mut det), skb_status::SKB_ERR_CORRUPT_DATA);
        assert!(last_error().contains("bias is beyond"), "{}", last_error());
        let p = CString::new(good.to_str().unwrap()).unwrap();
        assert_eq!(skb_detector_new_from_file(p.as_ptr(), &mut det), skb_status::SKB_OK);
        let mut opts = ptr::null_mut();
        assert_eq!(skb_detect_options_new(&mut opts), skb_status::SKB_OK);
        assert_eq!(skb_detect_options_set_threshold(opts, -1e6), skb_status::SKB_OK);
        let run = |cancel_at: usize| {
            let mut pr = DetectProgress { calls: 0, cancel_at, after_cancel: 0 };
            let (mut xy, mut cf, mut score) = ([7.0; 30], [7.0; 15], 7.0);
            let s = skb_detector_detect(
                det,
                &im,
                opts,
                Some(on_detect_progress),
                &mut pr as *mut DetectProgress as *mut std::ffi::c_void,
                xy.as_mut_ptr(),
                30,
                cf.as_mut_ptr(),
                15,
                &mut score,
            );
            let untouched = xy == [7.0; 30] && cf == [7.0; 15] && score == 7.0;
            (s, pr, untouched)
        };
        let (s, whole, _) = run(usize::MAX);
        assert_eq!(s, skb_status::SKB_OK, "{}", last_error());
        assert!(whole.calls >= 2, "{} progress calls", whole.calls);
        for at in 0..whole.calls {
            let (s, pr, untouched) = run(at);
            assert_eq!(s, skb_status::SKB_ERR_CANCELLED, "cancel at {at}");
            assert!(untouched, "cancel at {at}: outputs written");
            assert_eq!((pr.calls, pr.after_cancel), (at + 1, 0), "cancel at {at}");
        }
        skb_detect_options_free(opts);
        skb_detector_free(det);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

//! `skb_detector`: a 2-D pose detector model loaded from a file, and detection with it.
//! (The embedded default detector and `skb_detect` come with the trained sketch model.)

use std::ffi::{c_char, CStr};
use std::path::PathBuf;

use crate::detect::{detect, DetectOptions, Model};
use crate::skeleton::NUM_JOINTS;

use super::body::{out_slice, write_out};
use super::error::fail_with;
use super::image::{skb_image, view_of};
use super::ptr::try_ref;
use super::status::skb_status;

/// A detector model (flexible mixture of parts). Create with `skb_detector_new_from_file`,
/// release with `skb_detector_free`. Immutable: one detector may be used from several threads at
/// once.
pub struct skb_detector {
    model: Model,
}

/// Loads a detector model from `path` (NUL-terminated UTF-8): the binary `.skbd` format
/// (`docs/formats.md`, "Detector model") or the PARSE model JSON. Errors: `SKB_ERR_IO` (cannot
/// read), `SKB_ERR_CORRUPT_DATA` (bad magic, version, checksum, truncated or inconsistent
/// model). On success `*out` receives a new detector the caller owns; on failure it is untouched.
/// Thread-safe.
#[no_mangle]
pub unsafe extern "C" fn skb_detector_new_from_file(path: *const c_char, out: *mut *mut skb_detector) -> skb_status {
    ffi_boundary! {
        if path.is_null() {
            return fail_with(skb_status::SKB_ERR_NULL_POINTER, "path is NULL");
        }
        if out.is_null() {
            return fail_with(skb_status::SKB_ERR_NULL_POINTER, "out is NULL");
        }
        let Ok(p) = CStr::from_ptr(path).to_str() else {
            return fail_with(skb_status::SKB_ERR_INVALID_ARGUMENT, "path is not UTF-8");
        };
        let model = try_core!(Model::load_any(&PathBuf::from(p)));
        *out = Box::into_raw(Box::new(skb_detector { model }));
        skb_status::SKB_OK
    }
}

/// Releases a detector. NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_detector_free(det: *mut skb_detector) {
    if !det.is_null() {
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| drop(Box::from_raw(det))));
    }
}

/// Detects the best-scoring figure in `image` with `det`. `threshold`: score threshold (NaN uses
/// the model's own); `min_cell_px`: skip pyramid levels with cells smaller than this many pixels
/// (0 searches every scale; larger is faster but misses small figures). Images whose longer side
/// exceeds 1024 px are downscaled first (results are in input pixels). Writes the 15 canonical
/// joints as (x, y) pairs in pixels (origin top-left, y down) to `joints_xy[0..30]`, their
/// confidences in (0, 1) to `confidence[0..15]` and the score to `*score`. Errors:
/// `SKB_ERR_IMAGE_TOO_SMALL` (a side < 32 px), `SKB_ERR_NO_FIGURE` (nothing reaches the
/// threshold; the message gives the best score), `SKB_ERR_OUT_OF_RANGE` (negative or infinite
/// `min_cell_px`), `SKB_ERR_BUFFER_TOO_SMALL`, image errors. Nothing is written on failure.
/// Thread-safe.
#[no_mangle]
pub unsafe extern "C" fn skb_detector_detect(
    det: *const skb_detector,
    image: *const skb_image,
    threshold: f64,
    min_cell_px: f64,
    joints_xy: *mut f64,
    joints_len: usize,
    confidence: *mut f64,
    confidence_len: usize,
    score: *mut f64,
) -> skb_status {
    ffi_boundary! {
        let det = try_status!(try_ref(det, "det"));
        let view = try_status!(view_of(image));
        if joints_xy.is_null() || confidence.is_null() || score.is_null() {
            return fail_with(skb_status::SKB_ERR_NULL_POINTER, "joints_xy, confidence and score must not be NULL");
        }
        let threshold = if threshold.is_nan() { None } else { Some(threshold) };
        let opts = DetectOptions { threshold, min_cell_px, ..Default::default() };
        let d = try_core!(detect(&view, &det.model, &opts));
        let best = d.best();
        let xy = try_status!(out_slice(joints_xy, joints_len, 2 * NUM_JOINTS, "joints_xy"));
        let cf = try_status!(out_slice(confidence, confidence_len, NUM_JOINTS, "confidence"));
        for j in 0..NUM_JOINTS {
            xy[2 * j] = best.joints.xy[j][0];
            xy[2 * j + 1] = best.joints.xy[j][1];
            cf[j] = best.confidence[j];
        }
        try_status!(write_out(score, best.score, "score"));
        skb_status::SKB_OK
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::model::tests::tiny_model;
    use std::ffi::CString;
    use std::ptr::{null, null_mut};

    #[test]
    fn load_detect_and_errors() {
        let dir = std::env::temp_dir().join(format!("skb_capi_det_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("m.skbd");
        tiny_model().save(&p).unwrap();
        let cp = CString::new(p.to_str().unwrap()).unwrap();
        unsafe {
            let mut d: *mut skb_detector = null_mut();
            assert_eq!(skb_detector_new_from_file(null(), &mut d), skb_status::SKB_ERR_NULL_POINTER);
            assert_eq!(skb_detector_new_from_file(cp.as_ptr(), null_mut()), skb_status::SKB_ERR_NULL_POINTER);
            let missing = CString::new(dir.join("none.skbd").to_str().unwrap()).unwrap();
            assert_eq!(skb_detector_new_from_file(missing.as_ptr(), &mut d), skb_status::SKB_ERR_IO);
            let bad = dir.join("bad.skbd");
            let mut bytes = tiny_model().to_bytes();
            bytes.truncate(bytes.len() - 3);
            std::fs::write(&bad, bytes).unwrap();
            let cbad = CString::new(bad.to_str().unwrap()).unwrap();
            assert_eq!(skb_detector_new_from_file(cbad.as_ptr(), &mut d), skb_status::SKB_ERR_CORRUPT_DATA);
            assert!(d.is_null());
            assert_eq!(skb_detector_new_from_file(cp.as_ptr(), &mut d), skb_status::SKB_OK);
            assert!(!d.is_null());

            let px: Vec<u8> = (0..64 * 64).map(|i| ((i * 13) % 256) as u8).collect();
            let img = skb_image { data: px.as_ptr(), width: 64, height: 64, stride: 64, channels: 1 };
            let (mut xy, mut cf, mut s) = ([0f64; 30], [0f64; 15], 0f64);
            let st = skb_detector_detect(d, &img, -1e6, 0.0, xy.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s);
            assert_eq!(st, skb_status::SKB_OK);
            assert!(s.is_finite() && cf.iter().all(|&c| c > 0.0 && c < 1.0));
            assert_eq!(skb_detector_detect(d, &img, 1e6, 0.0, xy.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s), skb_status::SKB_ERR_NO_FIGURE);
            assert_eq!(
                skb_detector_detect(d, &img, -1e6, 0.0, xy.as_mut_ptr(), 29, cf.as_mut_ptr(), 15, &mut s),
                skb_status::SKB_ERR_BUFFER_TOO_SMALL
            );
            assert_eq!(
                skb_detector_detect(d, &img, -1e6, -1.0, xy.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s),
                skb_status::SKB_ERR_OUT_OF_RANGE
            );
            assert_eq!(skb_detector_detect(d, &img, -1e6, 0.0, null_mut(), 30, cf.as_mut_ptr(), 15, &mut s), skb_status::SKB_ERR_NULL_POINTER);
            let small = skb_image { data: px.as_ptr(), width: 20, height: 20, stride: 20, channels: 1 };
            assert_eq!(
                skb_detector_detect(d, &small, -1e6, 0.0, xy.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s),
                skb_status::SKB_ERR_IMAGE_TOO_SMALL
            );
            assert_eq!(skb_detector_detect(null(), &img, -1e6, 0.0, xy.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s), skb_status::SKB_ERR_NULL_POINTER);
            skb_detector_free(d);
            skb_detector_free(null_mut());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

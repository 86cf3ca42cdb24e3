//! `skb_detector`: a 2-D pose detector model loaded from a file, and detection with it;
//! `skb_context_detect` / `skb_context_detect_figure`: single-figure detection with the embedded backends (the
//! sketch model trained on synthetic concept sketches, MediaPipe's BlazePose landmark model, or
//! both), configured by an `skb_detect_options` handle; `skb_detector_detect`: a model from a
//! file, alone, with its raw score and threshold.

use std::ffi::c_char;
use std::path::PathBuf;

use sketchbody_core::detect::figure::{Backend, Figure, FigureOptions};
use sketchbody_core::detect::landmark::LandmarkNet;
use sketchbody_core::detect::{detect_with_progress, DetectOptions, Detection, Model, SearchScales};
use sketchbody_core::pipeline::figure::detect_figure;
use sketchbody_core::skeleton::NUM_JOINTS;

use super::body::skb_context;
use super::error::{fail, fail_with};
use super::fit::{progress_closure, skb_progress_fn};
use super::image::{skb_image, view_of};
use super::ptr::*;
use super::status::skb_status;
use sketchbody_core::error::Error;

/// A detector model (flexible mixture of parts). Create with `skb_detector_new_from_file`,
/// release with `skb_detector_free`. Immutable: one detector may be used from several threads at
/// once.
pub struct skb_detector {
    model: Model,
}

/// Loads a detector model from a file: the binary `.skbd` format (`docs/formats.md`, "Detector
/// model") or the PARSE model JSON. Thread-safe.
/// @param path the file path, NUL-terminated UTF-8.
/// @param out receives a new detector the caller owns (release with `skb_detector_free`);
///            untouched on failure; not NULL.
/// @return SKB_OK; SKB_ERR_IO (cannot read); SKB_ERR_CORRUPT_DATA (bad magic, version,
///         checksum, truncated or inconsistent model); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_detector_new_from_file(path: *const c_char, out: *mut *mut skb_detector) -> skb_status {
    unsafe {
        ffi_boundary! {
            let p = try_status!(try_str(path, "path"));
            let out = try_status!(out_slot(out));
            let model = try_core!(Model::load_any(&PathBuf::from(p)));
            give(out, skb_detector { model })
        }
    }
}

/// Releases a detector.
/// @param det the detector to release; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_detector_free(det: *mut skb_detector) {
    unsafe { free_box(det) }
}

/// Detects the best-scoring figure in `image` with the sketch model `det` alone. Images whose
/// longer side exceeds 1024 px are downscaled first (results are in input pixels). Thread-safe.
/// @param det the detector, only read.
/// @param image the sketch.
/// @param opts detection options, or NULL for the defaults of `skb_detect_options_new`; its
///             threshold, scales, figure range and levels per octave apply, the backend and
///             strictness do not.
/// @param progress `progress(user, fraction)`, or NULL: called on the calling thread with the
///                 fraction done (0..=1, non-decreasing) after the feature pyramid is built and
///                 after each group of pyramid levels; a non-zero return stops the search and
///                 the callback is not called again.
/// @param user passed to `progress` unchanged.
/// @param joints_xy receives the 15 canonical joints as (x, y) pairs in pixels (origin top-left,
///                  y down) in `joints_xy[0..30]`; not NULL.
/// @param joints_len the element count of `joints_xy`, at least 30.
/// @param confidence receives the joints' confidences in (0, 1) in `confidence[0..15]`; not NULL.
/// @param confidence_len the element count of `confidence`, at least 15.
/// @param score receives the score; on SKB_ERR_NO_FIGURE the best score found, below the
///              threshold (−infinity when no pyramid level was searched); not NULL.
/// @return SKB_OK; SKB_ERR_NO_FIGURE when no figure reaches the threshold (only `*score`
///         written); other errors write nothing: SKB_ERR_CANCELLED (the callback stopped it),
///         SKB_ERR_IMAGE_TOO_SMALL (a side < 32 px), SKB_ERR_OUT_OF_RANGE (a feature pyramid
///         over 1 GiB, refused before any work), SKB_ERR_NON_FINITE (a score or joint that is
///         not finite), SKB_ERR_BUFFER_TOO_SMALL, image and argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_detector_detect(
    det: *const skb_detector,
    image: *const skb_image,
    opts: *const skb_detect_options,
    progress: skb_progress_fn,
    user: *mut std::ffi::c_void,
    joints_xy: *mut f64,
    joints_len: usize,
    confidence: *mut f64,
    confidence_len: usize,
    score: *mut f64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let det = try_status!(try_ref(det, "det"));
            let view = try_status!(view_of(image));
            let (xy, cf, score) = try_status!(outputs(joints_xy, joints_len, confidence, confidence_len, score));
            let o = opt_ref(opts).map_or_else(DetectOptions::default, |o| o.inner.sketch.clone());
            let mut cb = progress_closure(progress, user);
            detect_into(&view, &det.model, &o, &mut cb, xy, cf, score)
        }
    }
}

/// Backend of `skb_context_detect`: both the sketch model and BlazePose, one candidate per image (the
/// default): on a drawing the sketch model recognises (its score above its own threshold), the
/// one whose proportions the 3-D pose step finds nearer a body's; otherwise the one with the
/// higher calibrated confidence. Each joint the two backends put within 0.08 of the figure's
/// size of each other is their mean. BlazePose, unsure of a figure framed by the ink's box, also
/// tries the sketch model's figure box.
pub const SKB_DETECTOR_AUTO: u32 = 0;
/// Backend of `skb_context_detect`: the flexible-mixture-of-parts sketch model alone.
pub const SKB_DETECTOR_FMP: u32 = 1;
/// Backend of `skb_context_detect`: MediaPipe's BlazePose landmark model alone.
pub const SKB_DETECTOR_BLAZEPOSE: u32 = 2;
/// A figure confidence under this is low: show the joints to the user for correction (the
/// core's `detect::figure::LOW_CONFIDENCE`; a test keeps them equal).
pub const SKB_LOW_CONFIDENCE: f64 = 0.75;

/// What `skb_context_detect_figure` and `skb_result_detection` report beside the joints.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct skb_figure_info {
    /// The backend whose joints were kept: `SKB_DETECTOR_FMP` or `SKB_DETECTOR_BLAZEPOSE`.
    pub backend: u32,
    /// 1 when `confidence` < `SKB_LOW_CONFIDENCE` (look at the joints, correct them), else 0.
    pub low_confidence: u32,
    /// Calibrated figure confidence in [0, 1]: the expected fraction of joints within 0.2 × the
    /// figure's size of the truth (the mean of the per-joint confidences).
    pub confidence: f64,
    /// Calibrated probability in [0, 1] that the image holds a figure.
    pub presence: f64,
    /// Further figures the sketch model found above its threshold.
    pub other_figures: u32,
    /// Zero.
    pub reserved: u32,
}

/// The C value of a backend.
pub(crate) fn backend_code(b: Backend) -> u32 {
    match b {
        Backend::Auto => SKB_DETECTOR_AUTO,
        Backend::Fmp => SKB_DETECTOR_FMP,
        Backend::BlazePose => SKB_DETECTOR_BLAZEPOSE,
    }
}

/// The info struct of a figure.
pub(crate) fn figure_info(f: &Figure) -> skb_figure_info {
    skb_figure_info {
        backend: backend_code(f.backend),
        low_confidence: u32::from(f.low_confidence),
        confidence: f.confidence,
        presence: f.presence,
        other_figures: f.others.len().min(u32::MAX as usize) as u32,
        reserved: 0,
    }
}

/// Options of [`skb_context_detect`]: backend, strictness, the sketch model's score threshold and
/// searched scales. Create with `skb_detect_options_new` (backend `SKB_DETECTOR_AUTO`, not
/// strict, the model's threshold, the sketch search range: figures from 1/2 of the shorter image
/// side to the longer side, at 7 pyramid levels per octave), release with
/// `skb_detect_options_free`. Setters need exclusive use; a configured handle may be read by
/// several threads at once.
pub struct skb_detect_options {
    inner: FigureOptions,
}

/// Creates detection options with the defaults.
/// @param out receives a new options handle the caller owns (release with
///            `skb_detect_options_free`); not NULL.
/// @return SKB_OK; SKB_ERR_NULL_POINTER for a NULL `out`.
#[no_mangle]
pub unsafe extern "C" fn skb_detect_options_new(out: *mut *mut skb_detect_options) -> skb_status {
    unsafe {
        ffi_boundary! {
            let out = try_status!(out_slot(out));
            give(out, skb_detect_options { inner: FigureOptions::default() })
        }
    }
}

/// Releases detection options.
/// @param opts the options to release; NULL is a no-op.
#[no_mangle]
pub unsafe extern "C" fn skb_detect_options_free(opts: *mut skb_detect_options) {
    unsafe { free_box(opts) }
}

/// Sets the detection backend.
/// @param opts the options, changed.
/// @param backend `SKB_DETECTOR_AUTO` (default), `SKB_DETECTOR_FMP` or `SKB_DETECTOR_BLAZEPOSE`.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for another value; SKB_ERR_NULL_POINTER for NULL `opts`.
#[no_mangle]
pub unsafe extern "C" fn skb_detect_options_set_backend(opts: *mut skb_detect_options, backend: u32) -> skb_status {
    unsafe {
        ffi_boundary! {
            let o = try_status!(try_mut(opts, "opts"));
            o.inner.backend = match backend {
                SKB_DETECTOR_AUTO => Backend::Auto,
                SKB_DETECTOR_FMP => Backend::Fmp,
                SKB_DETECTOR_BLAZEPOSE => Backend::BlazePose,
                _ => return fail(&Error::OutOfRange { name: "backend", detail: format!("{backend} not in 0..=2") }),
            };
            skb_status::SKB_OK
        }
    }
}

/// Sets strict detection: "no figure" unless a backend passes its own hard threshold (the
/// sketch model's score threshold, BlazePose's pose flag 0.5).
/// @param opts the options, changed.
/// @param strict true for strict; the default (false) returns the best figure whenever the
///               calibrated presence probability is at least 0.5.
/// @return SKB_OK; SKB_ERR_NULL_POINTER for NULL `opts`.
#[no_mangle]
pub unsafe extern "C" fn skb_detect_options_set_strict(opts: *mut skb_detect_options, strict: bool) -> skb_status {
    unsafe {
        ffi_boundary! {
            let o = try_status!(try_mut(opts, "opts"));
            o.inner.strict = strict;
            skb_status::SKB_OK
        }
    }
}

/// Sets the sketch model's score threshold, used when strict.
/// @param opts the options, changed.
/// @param threshold the score threshold; NaN restores the model's own.
/// @return SKB_OK; SKB_ERR_NON_FINITE for an infinite value; SKB_ERR_NULL_POINTER for NULL
///         `opts`.
#[no_mangle]
pub unsafe extern "C" fn skb_detect_options_set_threshold(opts: *mut skb_detect_options, threshold: f64) -> skb_status {
    unsafe {
        ffi_boundary! {
            let o = try_status!(try_mut(opts, "opts"));
            if threshold.is_infinite() {
                return fail(&Error::NonFinite { name: "threshold", value: threshold });
            }
            o.inner.sketch.threshold = if threshold.is_nan() { None } else { Some(threshold) };
            skb_status::SKB_OK
        }
    }
}

/// Sets the searched scales as the pyramid cell size in pixels of the (possibly downscaled)
/// image; a figure is found at cells of about its standing height / 40. Setting scales replaces
/// the default sketch search range (so 0 and +infinity search every scale).
/// @param opts the options, changed.
/// @param min_cell_px levels with cells smaller than this (which find small figures) are
///                    skipped; 0 ≤ `min_cell_px`, finite.
/// @param max_cell_px levels with cells larger than this (large figures) are skipped;
///                    greater than `min_cell_px`, may be +infinity.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE unless 0 ≤ min < max (NaN is rejected);
///         SKB_ERR_NULL_POINTER for NULL `opts`.
#[no_mangle]
pub unsafe extern "C" fn skb_detect_options_set_scales(
    opts: *mut skb_detect_options,
    min_cell_px: f64,
    max_cell_px: f64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let o = try_status!(try_mut(opts, "opts"));
            if !(min_cell_px >= 0.0 && min_cell_px.is_finite() && max_cell_px > min_cell_px) {
                return fail(&Error::OutOfRange { name: "scales", detail: format!("min {min_cell_px}, max {max_cell_px}: need 0 ≤ min < max") });
            }
            o.inner.sketch.min_cell_px = min_cell_px;
            o.inner.sketch.max_cell_px = max_cell_px;
            o.inner.sketch.search = SearchScales::All;
            skb_status::SKB_OK
        }
    }
}

/// Sets the searched figure sizes as fractions of the image (the default range is 0.5..1).
/// Replaces any cell range set by `skb_detect_options_set_scales`.
/// @param opts the options, changed.
/// @param min_fraction the smallest figure height, as a fraction of the shorter image side.
/// @param max_fraction the largest figure height, as a fraction of the longer image side.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE unless 0 < min < max, both finite (NaN is rejected);
///         SKB_ERR_NULL_POINTER for NULL `opts`.
#[no_mangle]
pub unsafe extern "C" fn skb_detect_options_set_figure_range(
    opts: *mut skb_detect_options,
    min_fraction: f64,
    max_fraction: f64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let o = try_status!(try_mut(opts, "opts"));
            if !(min_fraction > 0.0 && max_fraction > min_fraction && max_fraction.is_finite()) {
                return fail(&Error::OutOfRange { name: "figure range", detail: format!("min {min_fraction}, max {max_fraction}: need 0 < min < max, finite") });
            }
            o.inner.sketch.search = SearchScales::FigureFraction { min: min_fraction, max: max_fraction };
            o.inner.sketch.min_cell_px = 0.0;
            o.inner.sketch.max_cell_px = f64::INFINITY;
            skb_status::SKB_OK
        }
    }
}

/// Sets the pyramid levels per octave. The default is 7 (0.7 of the work of 10, the same
/// accuracy on held-out sketches); 5 scores exactly every other level of 10, about half the
/// work, coarser in scale.
/// @param opts the options, changed.
/// @param levels 1..=100, or 0 for the model's own (10 for the embedded detector and the PARSE
///               family).
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE above 100; SKB_ERR_NULL_POINTER for NULL `opts`.
#[no_mangle]
pub unsafe extern "C" fn skb_detect_options_set_levels_per_octave(
    opts: *mut skb_detect_options,
    levels: u32,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let o = try_status!(try_mut(opts, "opts"));
            if levels > 100 {
                return fail(&Error::OutOfRange { name: "levels_per_octave", detail: format!("{levels} not in 0..=100") });
            }
            o.inner.sketch.levels_per_octave = (levels > 0).then_some(levels as usize);
            skb_status::SKB_OK
        }
    }
}

/// Detects the best figure in `image` with the embedded backends of `ctx`. Large images are
/// normalised first (results are in input pixels). Thread-safe.
/// @param ctx the context, only read.
/// @param image the sketch: 1, 3 or 4 channels (colour helps BlazePose on painted drawings).
/// @param opts detection options, or NULL for the defaults (`SKB_DETECTOR_AUTO`).
/// @param joints_xy receives the 15 canonical joints as (x, y) pairs in pixels (origin top-left,
///                  y down) in `joints_xy[0..30]`; not NULL.
/// @param joints_len the element count of `joints_xy`, at least 30.
/// @param confidence receives the joints' calibrated confidences in [0, 1] (each the estimated
///                   probability that the joint is within 0.2 × the figure's size of the
///                   truth) in `confidence[0..15]`; not NULL.
/// @param confidence_len the element count of `confidence`, at least 15.
/// @param score receives the figure's confidence (the confidences' mean); on
///              SKB_ERR_NO_FIGURE the presence probability, or the best raw score when strict;
///              not NULL.
/// @return SKB_OK; SKB_ERR_NO_FIGURE when the image holds no figure (blank pages, text,
///         clutter; or, when strict, no backend passes its threshold), only `*score` written;
///         other errors write nothing: SKB_ERR_IMAGE_TOO_SMALL (a side < 32 px),
///         SKB_ERR_BUFFER_TOO_SMALL, SKB_ERR_NULL_POINTER, image errors.
#[no_mangle]
pub unsafe extern "C" fn skb_context_detect(
    ctx: *const skb_context,
    image: *const skb_image,
    opts: *const skb_detect_options,
    joints_xy: *mut f64,
    joints_len: usize,
    confidence: *mut f64,
    confidence_len: usize,
    score: *mut f64,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let ctx = try_status!(try_ref(ctx, "ctx"));
            let view = try_status!(view_of(image));
            let (xy, cf, score) = try_status!(outputs(joints_xy, joints_len, confidence, confidence_len, score));
            match figure_of(ctx, &view, opt_ref(opts)) {
                Ok(f) => {
                    write_joints(&f.joints, &f.joint_confidence, xy, cf);
                    *score = f.confidence;
                    skb_status::SKB_OK
                }
                Err(e @ Error::NoFigure { score: s, .. }) => {
                    *score = s;
                    fail(&e)
                }
                Err(e) => fail(&e),
            }
        }
    }
}

/// As `skb_context_detect`, with the backend kept, the confidences, the presence probability
/// and the low-confidence flag in `*info` instead of a score. Thread-safe.
/// @param ctx the context, only read.
/// @param image the sketch, as in `skb_context_detect`.
/// @param opts detection options, or NULL for the defaults.
/// @param joints_xy receives the 15 joints as (x, y) pixel pairs in `joints_xy[0..30]`; not NULL.
/// @param joints_len the element count of `joints_xy`, at least 30.
/// @param confidence receives the 15 joint confidences in `confidence[0..15]`; not NULL.
/// @param confidence_len the element count of `confidence`, at least 15.
/// @param info receives the figure info; not NULL.
/// @return SKB_OK; the errors of `skb_context_detect`, but on SKB_ERR_NO_FIGURE, as on every
///         error, nothing is written.
#[no_mangle]
pub unsafe extern "C" fn skb_context_detect_figure(
    ctx: *const skb_context,
    image: *const skb_image,
    opts: *const skb_detect_options,
    joints_xy: *mut f64,
    joints_len: usize,
    confidence: *mut f64,
    confidence_len: usize,
    info: *mut skb_figure_info,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            detect_figure_into(ctx, image, opts, joints_xy, joints_len, confidence, confidence_len, info, None)
        }
    }
}

/// The body of `skb_context_detect_figure` and of `skb_context_detect_facing` (`facing` `Some`: the figure's
/// facing into it as well, NULL refused). Nothing is written on failure.
///
/// # Safety
/// Each pointer must be NULL or valid for its documented length (the two functions' header
/// contract), with no other live reference to an output.
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn detect_figure_into(
    ctx: *const skb_context,
    image: *const skb_image,
    opts: *const skb_detect_options,
    joints_xy: *mut f64,
    joints_len: usize,
    confidence: *mut f64,
    confidence_len: usize,
    info: *mut skb_figure_info,
    facing: Option<*mut super::facing::skb_facing_info>,
) -> skb_status {
    unsafe {
        let ctx = try_status!(try_ref(ctx, "ctx"));
        let view = try_status!(view_of(image));
        let info = try_status!(try_mut(info, "info"));
        let facing = match facing {
            Some(p) => Some(try_status!(try_mut(p, "facing"))),
            None => None,
        };
        let mut unused = 0.0;
        let (xy, cf, _) = try_status!(outputs(joints_xy, joints_len, confidence, confidence_len, &mut unused));
        let f = try_core!(figure_of(ctx, &view, opt_ref(opts)));
        write_joints(&f.joints, &f.joint_confidence, xy, cf);
        *info = figure_info(&f);
        if let Some(out) = facing {
            *out = super::facing::facing_info(&f.facing);
        }
        skb_status::SKB_OK
    }
}

/// The single-figure detection of `view` with `ctx`'s embedded models and `opts` (`None`:
/// defaults).
fn figure_of(
    ctx: &skb_context,
    view: &sketchbody_core::image::ImageView<'_>,
    opts: Option<&skb_detect_options>,
) -> Result<Figure, Error> {
    let defaults = FigureOptions::default();
    let o = opts.map_or(&defaults, |o| &o.inner);
    let net = LandmarkNet::embedded()?;
    detect_figure(view, embedded_detector(ctx)?, &net, o, None)
}

/// Runs the detection and writes the best figure's joints, confidences and score; on "no
/// figure" writes only the best score found and returns `SKB_ERR_NO_FIGURE`.
fn detect_into(
    view: &sketchbody_core::image::ImageView<'_>,
    model: &Model,
    o: &DetectOptions,
    progress: &mut dyn FnMut(f32) -> bool,
    xy: &mut [f64],
    cf: &mut [f64],
    score: &mut f64,
) -> skb_status {
    match detect_with_progress(view, model, o, progress) {
        Ok(d) => {
            write_best(d.best(), xy, cf, score);
            skb_status::SKB_OK
        }
        Err(e @ Error::NoFigure { score: s, .. }) => {
            *score = s;
            fail(&e)
        }
        Err(e) => fail(&e),
    }
}

/// The context's embedded detector, decoded on first use (thread-safe, once per context).
pub(crate) fn embedded_detector(ctx: &skb_context) -> Result<&Model, Error> {
    ctx.detector
        .get_or_init(|| Model::embedded().map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|msg| Error::CorruptData(msg.clone()))
}

/// The checked output buffers of a detection: 30 joint coordinates, 15 confidences, the score.
///
/// # Safety
/// Each pointer must be NULL or valid for writes of its length, with no other live reference.
unsafe fn outputs<'a>(
    joints_xy: *mut f64,
    joints_len: usize,
    confidence: *mut f64,
    confidence_len: usize,
    score: *mut f64,
) -> Result<(&'a mut [f64], &'a mut [f64], &'a mut f64), skb_status> {
    if joints_xy.is_null() || confidence.is_null() || score.is_null() {
        return Err(fail_with(skb_status::SKB_ERR_NULL_POINTER, "joints_xy, confidence and score must not be NULL"));
    }
    unsafe {
        let xy = out_slice(joints_xy, joints_len, 2 * NUM_JOINTS, "joints_xy")?;
        let cf = out_slice(confidence, confidence_len, NUM_JOINTS, "confidence")?;
        Ok((xy, cf, try_mut(score, "score")?))
    }
}

/// Writes joints and confidences.
fn write_joints(j: &sketchbody_core::skeleton::Joints2, c: &[f64; NUM_JOINTS], xy: &mut [f64], cf: &mut [f64]) {
    for k in 0..NUM_JOINTS {
        xy[2 * k] = j.xy[k][0];
        xy[2 * k + 1] = j.xy[k][1];
        cf[k] = c[k];
    }
}

/// Writes the joints, confidences and score of `best`.
fn write_best(best: &Detection, xy: &mut [f64], cf: &mut [f64], score: &mut f64) {
    write_joints(&best.joints, &best.confidence, xy, cf);
    *score = best.score;
}

#[cfg(test)]
mod tests {
    use super::*;
    use sketchbody_core::detect::model::tiny_model;
    use std::ffi::CString;
    use std::ptr::{null, null_mut};

    #[test]
    fn skb_detect_uses_the_embedded_detector() {
        use crate::{skb_context_free, skb_context_new};
        use sketchbody_core::render::sketch::{SketchRenderer, SketchRequest};
        let r = SketchRenderer::new(std::sync::Arc::new(sketchbody_core::body::BodyModel::embedded().unwrap()), None)
            .unwrap();
        let sk = r.render(&SketchRequest::random(11, 384)).unwrap();
        let truth = &sk.truth.joints2d;
        // PCK@0.2: the share of joints within 0.2 × the longer side of the true joints' box.
        let side = (0..2)
            .map(|a| {
                let (lo, hi) =
                    truth.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[a]), h.max(p[a])));
                hi - lo
            })
            .fold(0.0, f64::max);
        let pck = |xy: &[f64; 30]| {
            let hit = (0..15).filter(|&j| (xy[2 * j] - truth[j][0]).hypot(xy[2 * j + 1] - truth[j][1]) <= 0.2 * side);
            hit.count() as f64 / 15.0
        };
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
        unsafe {
            let mut ctx = null_mut();
            assert_eq!(skb_context_new(&mut ctx), skb_status::SKB_OK);
            let img = skb_image { data: sk.pixels.as_ptr(), width: 384, height: 384, stride: 384, channels: 1 };
            let (mut xy, mut cf, mut s) = ([0f64; 30], [0f64; 15], 0f64);
            assert_eq!(
                skb_context_detect(ctx, &img, null(), xy.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s),
                skb_status::SKB_OK
            );
            assert!(pck(&xy) >= 0.8, "PCK@0.2 {}: {xy:?} vs {truth:?}", pck(&xy));
            assert!(cf.iter().all(|&c| (0.0..=1.0).contains(&c)));
            assert!((s - cf.iter().sum::<f64>() / 15.0).abs() < 1e-12, "score {s} is the mean confidence");

            let mut info = skb_figure_info {
                backend: 9,
                low_confidence: 9,
                confidence: -1.0,
                presence: -1.0,
                other_figures: 0,
                reserved: 0,
            };
            let mut xy_f = [0f64; 30];
            assert_eq!(
                skb_context_detect_figure(ctx, &img, null(), xy_f.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut info),
                skb_status::SKB_OK
            );
            assert_eq!(xy_f, xy);
            assert!(info.backend == SKB_DETECTOR_FMP || info.backend == SKB_DETECTOR_BLAZEPOSE);
            assert_eq!(info.confidence, s);
            assert_eq!(info.low_confidence, u32::from(s < SKB_LOW_CONFIDENCE));
            assert_eq!(SKB_LOW_CONFIDENCE, sketchbody_core::detect::figure::LOW_CONFIDENCE);
            assert!(info.presence >= 0.5 && info.presence <= 1.0, "{}", info.presence);
            assert_eq!(
                skb_context_detect_figure(ctx, &img, null(), xy_f.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, null_mut()),
                skb_status::SKB_ERR_NULL_POINTER
            );

            let mut o = null_mut();
            assert_eq!(skb_detect_options_new(&mut o), skb_status::SKB_OK);
            for (b, want) in [(SKB_DETECTOR_FMP, Backend::Fmp), (SKB_DETECTOR_BLAZEPOSE, Backend::BlazePose)] {
                assert_eq!(skb_detect_options_set_backend(o, b), skb_status::SKB_OK);
                assert_eq!(o.as_ref().unwrap().inner.backend, want);
                let mut xy_b = [0f64; 30];
                assert_eq!(
                    skb_context_detect_figure(ctx, &img, o, xy_b.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut info),
                    skb_status::SKB_OK
                );
                assert_eq!(info.backend, b);
                assert!(pck(&xy_b) >= 0.6, "backend {b}: PCK@0.2 {}", pck(&xy_b));
            }
            assert_eq!(skb_detect_options_set_backend(o, 3), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_detect_options_set_backend(null_mut(), 0), skb_status::SKB_ERR_NULL_POINTER);
            // Strict with an unreachable threshold: no figure, the best raw score reported, the
            // joints untouched.
            assert_eq!(skb_detect_options_set_backend(o, SKB_DETECTOR_FMP), skb_status::SKB_OK);
            assert_eq!(skb_detect_options_set_strict(o, true), skb_status::SKB_OK);
            assert_eq!(skb_detect_options_set_threshold(o, 1e6), skb_status::SKB_OK);
            let (mut xy2, mut s2) = ([-7f64; 30], 0f64);
            assert_eq!(
                skb_context_detect(ctx, &img, o, xy2.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s2),
                skb_status::SKB_ERR_NO_FIGURE
            );
            assert!(s2.is_finite() && s2 < 1e6, "{s2}");
            assert!(xy2.iter().all(|&v| v == -7.0));
            assert_eq!(skb_detect_options_set_strict(o, false), skb_status::SKB_OK);
            assert_eq!(skb_detect_options_set_threshold(o, f64::INFINITY), skb_status::SKB_ERR_NON_FINITE);
            assert_eq!(skb_detect_options_set_threshold(o, f64::NAN), skb_status::SKB_OK);
            assert_eq!(skb_detect_options_set_scales(o, 5.0, 4.0), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_detect_options_set_scales(o, f64::NAN, 4.0), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_detect_options_set_levels_per_octave(o, 5), skb_status::SKB_OK);
            assert_eq!(o.as_ref().unwrap().inner.sketch.levels_per_octave, Some(5));
            assert_eq!(skb_detect_options_set_levels_per_octave(o, 0), skb_status::SKB_OK);
            assert_eq!(o.as_ref().unwrap().inner.sketch.levels_per_octave, None);
            assert_eq!(skb_detect_options_set_levels_per_octave(o, 101), skb_status::SKB_ERR_OUT_OF_RANGE);
            assert_eq!(skb_detect_options_set_levels_per_octave(o, 7), skb_status::SKB_OK);
            assert_eq!(skb_detect_options_set_levels_per_octave(null_mut(), 5), skb_status::SKB_ERR_NULL_POINTER);
            // Figures of at most 0.3 of the side: the sketch model misses the figure (most of the
            // page), and its calibrated confidence says so.
            assert_eq!(skb_detect_options_set_figure_range(o, 0.05, 0.3), skb_status::SKB_OK);
            let mut s4 = 0f64;
            let st = skb_context_detect(ctx, &img, o, xy2.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s4);
            assert!(st == skb_status::SKB_ERR_NO_FIGURE || s4 < s, "{st:?}: small-figure confidence {s4} vs {s}");
            for (lo, hi) in [(0.0, 1.0), (0.5, 0.5), (0.2, f64::INFINITY), (f64::NAN, 1.0)] {
                assert_eq!(
                    skb_detect_options_set_figure_range(o, lo, hi),
                    skb_status::SKB_ERR_OUT_OF_RANGE,
                    "{lo}..{hi}"
                );
            }
            assert_eq!(skb_detect_options_set_scales(o, 0.0, 2.5), skb_status::SKB_OK);
            assert_eq!(o.as_ref().unwrap().inner.sketch.search, SearchScales::All);
            let mut s3 = 0f64;
            assert_eq!(
                skb_context_detect(ctx, &img, o, xy2.as_mut_ptr(), 29, cf.as_mut_ptr(), 15, &mut s3),
                skb_status::SKB_ERR_BUFFER_TOO_SMALL
            );
            assert_eq!(
                skb_context_detect(null(), &img, o, xy2.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s3),
                skb_status::SKB_ERR_NULL_POINTER
            );
            assert_eq!(skb_detect_options_set_threshold(null_mut(), 0.0), skb_status::SKB_ERR_NULL_POINTER);
            let small = skb_image { data: sk.pixels.as_ptr(), width: 20, height: 20, stride: 384, channels: 1 };
            assert_eq!(
                skb_context_detect(ctx, &small, o, xy2.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s3),
                skb_status::SKB_ERR_IMAGE_TOO_SMALL
            );
            // A blank page holds no figure: the presence probability comes back as the score.
            let blank = vec![255u8; 256 * 256];
            let page = skb_image { data: blank.as_ptr(), width: 256, height: 256, stride: 256, channels: 1 };
            let (mut xy3, mut s5) = ([-7f64; 30], 0f64);
            assert_eq!(
                skb_context_detect(ctx, &page, null(), xy3.as_mut_ptr(), 30, cf.as_mut_ptr(), 15, &mut s5),
                skb_status::SKB_ERR_NO_FIGURE
            );
            assert!((0.0..0.5).contains(&s5), "presence {s5}");
            assert!(xy3.iter().all(|&v| v == -7.0));
            skb_detect_options_free(o);
            skb_detect_options_free(null_mut());
            skb_context_free(ctx);
        }
    }

    #[test]
    fn load_detect_and_errors() {
        let dir = std::env::temp_dir().join(format!("skb_capi_det_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("m.skbd");
        tiny_model().save(&p).unwrap();
        let cp = CString::new(p.to_str().unwrap()).unwrap();
        // SAFETY: the pointers are live locals or handles made above and not freed yet; lengths are theirs.
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
            let (mut low, mut high) = (null_mut(), null_mut());
            assert_eq!(skb_detect_options_new(&mut low), skb_status::SKB_OK);
            assert_eq!(skb_detect_options_new(&mut high), skb_status::SKB_OK);
            assert_eq!(skb_detect_options_set_threshold(low, -1e6), skb_status::SKB_OK);
            assert_eq!(skb_detect_options_set_threshold(high, 1e6), skb_status::SKB_OK);
            assert_eq!(skb_detect_options_set_scales(low, -1.0, f64::INFINITY), skb_status::SKB_ERR_OUT_OF_RANGE);
            let detect = |d: *const skb_detector, img: &skb_image, o, xy: &mut [f64], cf: &mut [f64], s: &mut f64| {
                skb_detector_detect(
                    d,
                    img,
                    o,
                    None,
                    null_mut(),
                    xy.as_mut_ptr(),
                    xy.len(),
                    cf.as_mut_ptr(),
                    cf.len(),
                    s,
                )
            };
            let (mut xy, mut cf, mut s) = ([0f64; 30], [0f64; 15], 0f64);
            assert_eq!(detect(d, &img, low, &mut xy, &mut cf, &mut s), skb_status::SKB_OK);
            assert!(s.is_finite() && cf.iter().all(|&c| c > 0.0 && c < 1.0));
            // No figure: only the best score is written (the one found at threshold −1e6).
            let (mut xy2, mut s2) = ([-7f64; 30], 0f64);
            assert_eq!(detect(d, &img, high, &mut xy2, &mut cf, &mut s2), skb_status::SKB_ERR_NO_FIGURE);
            assert_eq!(s2, s);
            assert!(xy2.iter().all(|&v| v == -7.0));
            assert_eq!(detect(d, &img, low, &mut xy[..29], &mut cf, &mut s), skb_status::SKB_ERR_BUFFER_TOO_SMALL);
            assert_eq!(
                skb_detector_detect(d, &img, low, None, null_mut(), null_mut(), 30, cf.as_mut_ptr(), 15, &mut s),
                skb_status::SKB_ERR_NULL_POINTER
            );
            let small = skb_image { data: px.as_ptr(), width: 20, height: 20, stride: 20, channels: 1 };
            assert_eq!(detect(d, &small, low, &mut xy, &mut cf, &mut s), skb_status::SKB_ERR_IMAGE_TOO_SMALL);
            assert_eq!(detect(null(), &img, low, &mut xy, &mut cf, &mut s), skb_status::SKB_ERR_NULL_POINTER);
            skb_detect_options_free(low);
            skb_detect_options_free(high);
            skb_detector_free(d);
            skb_detector_free(null_mut());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

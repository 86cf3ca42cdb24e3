//! The BlazePose landmark backend: MediaPipe's pose landmark model ("full"), converted to ONNX
//! and run in pure Rust by tract-onnx ([`model`]), with MediaPipe's pre- and post-processing:
//! a square ROI ([`roi`]) from the ink's bounding box (1.25 × its larger side, no rotation),
//! the affine 256×256 crop with white padding ([`crop`]), landmark decoding (x, y in crop px; z;
//! visibility and presence logits through a sigmoid), the refinement of x and y from the
//! network's heatmap ([`heatmap`]) and back-projection to image pixels, then
//! a second pass on the ROI from the first pass's own alignment landmarks (hips' midpoint →
//! scale point, rotated upright, 1.25 × twice their distance), and the map to the canonical
//! joints ([`joints`]). Crops that are mostly paper have their strokes lightened first
//! ([`prep`]); when the ink box's ROI leaves the network unsure (pose flag under
//! [`BlazePoseOptions::retry_below`]), other ROI scales are tried ([`roi::retry_rois`]), and
//! then the ink box's ROI once more with the drawing's enclosed regions filled
//! ([`prep::fill_enclosed`]).

pub mod crop;
pub mod definitions;
pub mod heatmap;
pub mod joints;
pub mod model;
pub mod prep;
pub mod roi;

pub use definitions::JointDefinitions;
pub use model::LandmarkNet;
pub use roi::Roi;

use crate::error::{Error, Result};
use crate::image::ImageView;
use crate::skeleton::{Joints2, NUM_JOINTS};

/// Pose landmarks (MediaPipe's order); the network's 6 further outputs are auxiliary.
pub const NUM_POSE_LANDMARKS: usize = 33;
/// Auxiliary landmark at the hips' midpoint: the second pass's ROI centre.
pub const ALIGN_CENTER: usize = 33;
/// Auxiliary landmark whose distance from [`ALIGN_CENTER`] sets the second pass's ROI size.
pub const ALIGN_SCALE: usize = 34;

/// One decoded landmark in image coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landmark {
    /// x, px (continuous image coordinates).
    pub x: f64,
    /// y, px.
    pub y: f64,
    /// Depth relative to the hips, px at the image's scale (smaller is nearer the camera).
    pub z: f64,
    /// Probability that the landmark is visible (not occluded), in (0, 1).
    pub visibility: f64,
    /// Probability that the landmark lies inside the crop, in (0, 1).
    pub presence: f64,
}

/// Landmarks of one network pass on one ROI.
#[derive(Clone, Debug, PartialEq)]
pub struct RoiLandmarks {
    /// The ROI the crop was taken from.
    pub roi: Roi,
    /// All 39 network landmarks (33 pose + 6 auxiliary), image px.
    pub landmarks: Vec<Landmark>,
    /// The network's pose-presence flag in [0, 1].
    pub pose_flag: f64,
}

fn sigmoid(v: f32) -> f64 {
    1.0 / (1.0 + (-(v as f64)).exp())
}

/// Runs `net` on the crop of `image` (1, 3 or 4 channels) inside `roi` and maps the landmarks
/// back to image px, refined from the heatmap first when `refine` ([`heatmap::refine`]).
/// Errors: those of [`landmarks_of_tensor`].
pub fn landmarks_in_roi(net: &LandmarkNet, image: &ImageView<'_>, roi: &Roi, refine: bool) -> Result<RoiLandmarks> {
    landmarks_of_tensor(net, roi, crop::crop_tensor(image, roi), refine)
}

/// Runs `net` on `tensor`, a crop of `roi` ([`crop::crop_tensor`], possibly preprocessed),
/// refines all 39 landmarks from the network's heatmap when `refine` ([`heatmap::refine`], as
/// MediaPipe's pose graph does: the alignment landmarks that place a second pass too), and maps
/// them back to image px. Errors: those of [`LandmarkNet::run`]; `CorruptData` when `refine` and
/// the model has no heatmap output.
pub fn landmarks_of_tensor(net: &LandmarkNet, roi: &Roi, tensor: Vec<f32>, refine: bool) -> Result<RoiLandmarks> {
    let mut raw = net.run(tensor)?;
    if refine {
        let Some(h) = &raw.heatmap else {
            return Err(Error::CorruptData("BlazePose landmark model: no heatmap output to refine from".into()));
        };
        heatmap::refine(&mut raw.landmarks, h)?;
    }
    let n = crop::INPUT_SIDE as f64;
    let landmarks = raw
        .landmarks
        .iter()
        .map(|l| {
            let [x, y] = roi.to_image(l[0] as f64 / n, l[1] as f64 / n);
            let z = l[2] as f64 / n * roi.size;
            Landmark { x, y, z, visibility: sigmoid(l[3]), presence: sigmoid(l[4]) }
        })
        .collect();
    Ok(RoiLandmarks { roi: *roi, landmarks, pose_flag: raw.pose_flag as f64 })
}

/// The second pass's ROI from a pass's alignment landmarks. Errors: `Degenerate` when they
/// coincide.
pub fn roi_from_landmarks(l: &RoiLandmarks) -> Result<Roi> {
    let (c, s) = (l.landmarks[ALIGN_CENTER], l.landmarks[ALIGN_SCALE]);
    Roi::from_alignment([c.x, c.y], [s.x, s.y])
}

/// Options of [`detect_blazepose`]. `Default`: two passes, pose flag threshold 0.5, retry under
/// 0.5.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlazePoseOptions {
    /// Network passes per ROI: 1 (the ROI only) or 2 (then the ROI from the first pass's
    /// landmarks, as MediaPipe tracks). Default 2.
    pub passes: usize,
    /// Smallest pose flag of the last pass accepted as a figure, in [0, 1]; below it the result
    /// is [`Error::NoFigure`]. Default 0.5 (MediaPipe's tracking confidence).
    pub min_pose_flag: f64,
    /// When the ink box's ROI ends with a pose flag under this, in [0, 1], the other ROIs of
    /// [`roi::retry_rois`] are tried as well (each with `passes` passes) and the pass with the
    /// highest pose flag is kept when it reaches [`RETRY_ACCEPT`]; 0 never retries. Default [`DEFAULT_RETRY_BELOW`]: a clean
    /// sketch (pose flag near 1) costs no extra pass.
    pub retry_below: f64,
    /// Lighten the strokes of crops that are mostly paper ([`prep::lighten_drawing`]) before the
    /// network sees them. Default true.
    pub lighten_drawings: bool,
    /// When the retries still end under `retry_below`, try the ink box's ROI once more with the
    /// crops' enclosed regions filled ([`prep::fill_enclosed`]); its pass is kept when its pose
    /// flag is higher and at least [`FILL_ACCEPT`]. Default true.
    pub fill_drawings: bool,
    /// Refine each pass's landmarks from the network's heatmap, as MediaPipe's pose graph does
    /// ([`heatmap::refine`]; [`JointDefinitions::SHIPPED`] was fitted on refined landmarks).
    /// Default true; costs about 3 ms more per pass (docs/benchmarks-history.md, "Landmarks
    /// refined from the heatmap").
    pub refine_from_heatmap: bool,
    /// Shifts from the mapped landmarks to the body model's joints. Default
    /// [`JointDefinitions::SHIPPED`]; [`JointDefinitions::IDENTITY`] keeps the landmarks'
    /// positions (MediaPipe's definitions).
    pub definitions: JointDefinitions,
}

/// The filled pass ([`BlazePoseOptions::fill_drawings`]) replaces the others with a pose flag of
/// at least this (and higher than theirs); 0.5 is the flag at which BlazePose counts a figure.
/// Chosen on PARSE training photos 1–100 through the proxy benchmark's stylisations
/// (`examples/landmark_roi.rs`; docs/benchmarks-history.md, "Filled drawings").
pub const FILL_ACCEPT: f64 = 0.5;

/// A retry ROI's pass replaces the first only with a pose flag of at least this (and higher than
/// the first's), so that retries rarely make BlazePose sure of a page without a figure (chosen
/// on PARSE training photos and the calibration's pages, `examples/landmark_roi.rs`).
pub const RETRY_ACCEPT: f64 = 0.9;

/// The default [`BlazePoseOptions::retry_below`].
pub const DEFAULT_RETRY_BELOW: f64 = 0.5;

impl Default for BlazePoseOptions {
    fn default() -> Self {
        Self {
            passes: 2,
            min_pose_flag: 0.5,
            retry_below: DEFAULT_RETRY_BELOW,
            lighten_drawings: true,
            fill_drawings: true,
            refine_from_heatmap: true,
            definitions: JointDefinitions::SHIPPED,
        }
    }
}

/// A figure found by the landmark backend.
#[derive(Clone, Debug, PartialEq)]
pub struct BlazePoseDetection {
    /// The last pass's pose flag in [0, 1].
    pub score: f64,
    /// The canonical 15 joints (all marked visible), px, on [`BlazePoseOptions::definitions`].
    pub joints: Joints2,
    /// Per canonical joint confidence (visibility × presence), in (0, 1).
    pub confidence: [f64; NUM_JOINTS],
    /// The last pass's landmarks and ROI.
    pub pass: RoiLandmarks,
    /// Starting ROIs tried: 1 (the ink box's) or 1 + the retry ROIs when the first was unsure
    /// (+ 1 for the filled try).
    pub rois_tried: usize,
    /// The kept pass saw the drawing with its enclosed regions filled.
    pub filled: bool,
}

/// One pass on `roi` with the preprocessing `opts` asks for, the enclosed regions filled when
/// `fill`.
fn pass_on(
    net: &LandmarkNet,
    image: &ImageView<'_>,
    roi: &Roi,
    opts: &BlazePoseOptions,
    fill: bool,
) -> Result<RoiLandmarks> {
    let mut t = crop::crop_tensor(image, roi);
    if opts.lighten_drawings {
        prep::lighten_drawing(&mut t);
    }
    if fill {
        prep::fill_enclosed(&mut t, crop::INPUT_SIDE);
    }
    landmarks_of_tensor(net, roi, t, opts.refine_from_heatmap)
}

/// `opts.passes` passes from `start`: the first on `start`, a second on the ROI from its
/// landmarks.
fn passes_from(
    net: &LandmarkNet,
    image: &ImageView<'_>,
    start: &Roi,
    opts: &BlazePoseOptions,
    fill: bool,
) -> Result<RoiLandmarks> {
    let mut pass = pass_on(net, image, start, opts, fill)?;
    if opts.passes == 2 {
        if let Ok(r) = roi_from_landmarks(&pass) {
            pass = pass_on(net, image, &r, opts, fill)?;
        }
    }
    Ok(pass)
}

/// Finds the figure in `image`: first pass on the ink box's ROI, then (with `passes` = 2) a pass
/// on the ROI from its own landmarks; when that pose flag is under `retry_below`, the same from
/// each of [`roi::retry_rois`], keeping the highest pose flag if it reaches [`RETRY_ACCEPT`];
/// still under it, the ink box's ROI with the enclosed regions filled (`fill_drawings`); the joints
/// mapped from the landmarks are moved by `definitions`. Errors: `ImageTooSmall` (either
/// side under `detect::MIN_DETECT_SIDE`), `OutOfRange` for bad options, `NoFigure` for a page
/// without ink or a pose flag under `min_pose_flag`, and the network's errors.
pub fn detect_blazepose(
    net: &LandmarkNet,
    image: &ImageView<'_>,
    opts: &BlazePoseOptions,
) -> Result<BlazePoseDetection> {
    let (w, h) = (image.width(), image.height());
    let min = super::MIN_DETECT_SIDE;
    if w.min(h) < min {
        return Err(Error::ImageTooSmall { width: w, height: h, min });
    }
    if !(1..=2).contains(&opts.passes) {
        return Err(Error::OutOfRange { name: "passes", detail: format!("{} not in 1..=2", opts.passes) });
    }
    opts.definitions.validate()?;
    for (name, v) in [("min_pose_flag", opts.min_pose_flag), ("retry_below", opts.retry_below)] {
        if !(0.0..=1.0).contains(&v) {
            return Err(Error::OutOfRange { name, detail: format!("{v} not in [0, 1]") });
        }
    }
    let no_figure = |score: f64| Error::NoFigure { score, threshold: opts.min_pose_flag };
    let ink = roi::ink_box(image).ok_or_else(|| no_figure(0.0))?;
    let start = Roi::from_box(ink)?;
    let mut pass = passes_from(net, image, &start, opts, false)?;
    let mut rois_tried = 1;
    if pass.pose_flag < opts.retry_below {
        for r in roi::retry_rois(ink) {
            let p = passes_from(net, image, &r, opts, false)?;
            rois_tried += 1;
            if p.pose_flag > pass.pose_flag && p.pose_flag >= RETRY_ACCEPT {
                pass = p;
            }
        }
    }
    let mut filled = false;
    if opts.fill_drawings && pass.pose_flag < opts.retry_below {
        let p = passes_from(net, image, &start, opts, true)?;
        rois_tried += 1;
        if p.pose_flag > pass.pose_flag && p.pose_flag >= FILL_ACCEPT {
            pass = p;
            filled = true;
        }
    }
    if pass.pose_flag < opts.min_pose_flag {
        return Err(no_figure(pass.pose_flag));
    }
    Ok(detection_of(pass, rois_tried, filled, opts))
}

/// The detection of a kept pass: its landmarks mapped to the canonical joints and moved by
/// `opts.definitions`.
fn detection_of(pass: RoiLandmarks, rois_tried: usize, filled: bool, opts: &BlazePoseOptions) -> BlazePoseDetection {
    let xy: Vec<[f64; 2]> = pass.landmarks.iter().map(|l| [l.x, l.y]).collect();
    let conf: Vec<f64> = pass.landmarks.iter().map(|l| l.visibility * l.presence).collect();
    let (mapped, confidence) = joints::to_canonical(&xy[..NUM_POSE_LANDMARKS], &conf[..NUM_POSE_LANDMARKS]);
    let joints = opts.definitions.apply(&mapped);
    BlazePoseDetection { score: pass.pose_flag, joints, confidence, pass, rois_tried, filled }
}

/// Retries `found` ([`detect_blazepose`]'s detection of `image` with `opts`, any pose flag)
/// from further starting ROIs, e.g. the boxes of the sketch model's figures: when its pose flag
/// is under `opts.retry_below`, `opts.passes` passes from each of `rois`, the highest pose flag
/// replacing `found` when it is higher and reaches `accept` (in [0, 1]). `found` is returned as
/// it is (with `rois_tried` counting the ROIs) when its flag is not under `retry_below` or no
/// ROI does better. Errors: `OutOfRange` for `accept` outside [0, 1]; the network's.
pub fn retry_from(
    net: &LandmarkNet,
    image: &ImageView<'_>,
    found: BlazePoseDetection,
    rois: &[Roi],
    accept: f64,
    opts: &BlazePoseOptions,
) -> Result<BlazePoseDetection> {
    if !(0.0..=1.0).contains(&accept) {
        return Err(Error::OutOfRange { name: "accept", detail: format!("{accept} not in [0, 1]") });
    }
    if found.score >= opts.retry_below {
        return Ok(found);
    }
    let mut best: Option<RoiLandmarks> = None;
    for r in rois {
        let p = passes_from(net, image, r, opts, false)?;
        if p.pose_flag >= accept && p.pose_flag > best.as_ref().map_or(found.score, |b| b.pose_flag) {
            best = Some(p);
        }
    }
    let tried = found.rois_tried + rois.len();
    Ok(match best {
        Some(p) => detection_of(p, tried, false, opts),
        None => BlazePoseDetection { rois_tried: tried, ..found },
    })
}

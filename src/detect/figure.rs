//! Single-figure detection, the product's default: the best figure in a drawing with calibrated
//! confidences, from the sketch model ([`super::detect`], trained on concept sketches), the
//! BlazePose landmark backend ([`super::landmark`], trained on photos) or both (`Auto`, which
//! keeps per image one candidate: the one the caller's [`Referee`] picks when the sketch model
//! recognises the drawing — the pipeline's is the 3-D pose step — else the one whose calibrated
//! joint confidences are higher; [`Fusion`]).
//!
//! Semantics: the best figure is returned whenever the evidence says the image plausibly holds
//! one (presence probability ≥ [`FigureOptions::min_presence`]); "no figure" is left for blank
//! pages, text and clutter. `strict` restores hard thresholds (the sketch model's own threshold,
//! BlazePose's pose flag ≥ 0.5). Confidences come from [`super::calibration`]: a joint's
//! confidence estimates the probability that it lies within 0.2 × the figure's size of the truth
//! (PCK@0.2), and the figure's confidence is their mean, the expected fraction of correct joints.

use super::calibration::{clamp_score, joint_features, log_odds, predict, presence_features, sigmoid, Calibration};
use super::facing::{self, FacingEstimate, FacingInput, FacingModel};
use super::landmark::roi::Roi;
use super::landmark::{detect_blazepose, retry_from, BlazePoseDetection, BlazePoseOptions, LandmarkNet};
use super::tone;
use super::{detect, DetectOptions, Detection, Model};
use crate::error::{Error, Result};
use crate::image::ImageView;
use crate::skeleton::{Joints2, NUM_JOINTS};

/// `Auto`: how many of the sketch model's best figures give BlazePose a further starting ROI
/// when it is unsure from the ink box ([`crate::detect::landmark::retry_from`]). Chosen with
/// [`SKETCH_ROI_ACCEPT`] on images the benchmark does not test (docs/benchmarks-history.md,
/// "BlazePose from the sketch model's box").
pub const SKETCH_ROIS: usize = 1;

/// `Auto`: the pose flag a pass from the sketch model's box needs to replace BlazePose's own
/// (the flag at which BlazePose counts a figure; the ink box's scale retries need
/// [`crate::detect::landmark::RETRY_ACCEPT`], as they are tried on every unsure page).
pub const SKETCH_ROI_ACCEPT: f64 = 0.5;

/// Which 2-D joint detector runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backend {
    /// Both backends; per image one candidate chosen as [`Fusion::PerImage`] says (default).
    #[default]
    Auto,
    /// The flexible-mixture-of-parts sketch model (the embedded or a given `.skbd`).
    Fmp,
    /// MediaPipe's BlazePose landmark model.
    BlazePose,
}

impl Backend {
    /// The name used by the CLI, the JSON and the report: `auto`, `fmp`, `blazepose`.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Auto => "auto",
            Backend::Fmp => "fmp",
            Backend::BlazePose => "blazepose",
        }
    }

    /// Every backend, in CLI order.
    pub const ALL: [Backend; 3] = [Backend::Auto, Backend::Fmp, Backend::BlazePose];
}

impl std::str::FromStr for Backend {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Backend::ALL.into_iter().find(|b| b.name() == s).ok_or_else(|| Error::OutOfRange {
            name: "detector backend",
            detail: format!("{s:?}: expected auto, fmp or blazepose"),
        })
    }
}

/// The default presence probability under which an image is "no figure".
pub const DEFAULT_MIN_PRESENCE: f64 = 0.5;

/// A figure confidence under this is flagged as low: the user should look at the overlay and
/// correct the joints (`--joints`, the paper's user step).
pub const LOW_CONFIDENCE: f64 = 0.75;

/// How `Auto` combines the two backends' candidates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Fusion {
    /// One whole candidate per image (default): when both backends answered and the sketch
    /// model's figure passes the sketch model's own threshold (a drawing it recognises), the
    /// candidate whose joints the 3-D pose step explains with drawn proportions nearest the
    /// body model's (the [`Referee`] the caller gives); otherwise, without a referee, or when
    /// the pose step fails on either, the one with the higher mean calibrated confidence.
    #[default]
    PerImage,
    /// One whole candidate per image, always the one with the higher mean calibrated
    /// confidence, whatever the 3-D pose step makes of the two.
    Confidence,
    /// Per limb ([`LIMB_GROUPS`]), the candidate whose calibrated confidences over the limb are
    /// higher; the figure's backend is `Auto` when the limbs come from both.
    PerLimb,
}

/// The joint groups [`Fusion::PerLimb`] takes from one backend each: head and neck, each arm,
/// the hips with the pelvis, each lower leg.
pub const LIMB_GROUPS: [&[usize]; 6] = [&[0, 1], &[2, 3, 4], &[5, 6, 7], &[8, 9, 12], &[10, 11], &[13, 14]];

/// Options of [`detect_figure`]. `Default`: `Auto` per image, the sketch search defaults, two
/// BlazePose passes, presence ≥ [`DEFAULT_MIN_PRESENCE`], not strict.
#[derive(Clone, Debug, PartialEq)]
pub struct FigureOptions {
    /// The backend(s) to run.
    pub backend: Backend,
    /// The sketch model's search. Its `threshold` is used only when `strict`.
    pub sketch: DetectOptions,
    /// BlazePose's passes (its `min_pose_flag` is used only when `strict`).
    pub blazepose: BlazePoseOptions,
    /// Hard thresholds instead of the calibrated presence: a backend's figure counts only when it
    /// passes the backend's own threshold.
    pub strict: bool,
    /// Smallest presence probability accepted as a figure, in [0, 1] (not strict).
    pub min_presence: f64,
    /// How `Auto` combines the backends.
    pub fusion: Fusion,
    /// Where both backends answered: each joint of the chosen figure whose other-backend joint
    /// lies within this fraction of the figure's size becomes the two joints' mean
    /// ([`Figure::averaged`]); 0 = off ([`detect_figure`] refuses a negative or non-finite
    /// value). Default [`AVERAGE_AGREEMENT`].
    pub average_agreement: f64,
    /// Label left and right by the decided facing ([`facing::target_handedness`]): a candidate
    /// labelled as seen from behind without evidence of a back view is swapped to the front's
    /// labelling, one labelled as facing the viewer of a figure decided as seen from behind to
    /// the back's. `false` keeps the backends' labellings (the facing is still reported).
    /// Default `true`.
    pub facing_rule: bool,
    /// The facing model; `None` (default) the embedded one ([`FacingModel::embedded`]).
    pub facing_model: Option<FacingModel>,
}

impl Default for FigureOptions {
    fn default() -> Self {
        Self {
            backend: Backend::Auto,
            sketch: DetectOptions::default(),
            blazepose: BlazePoseOptions::default(),
            strict: false,
            min_presence: DEFAULT_MIN_PRESENCE,
            fusion: Fusion::PerImage,
            average_agreement: AVERAGE_AGREEMENT,
            facing_rule: true,
            facing_model: None,
        }
    }
}

/// What the backends found in one image, before any decision: the raw material of
/// [`decide`] and of the calibration (`sketchbody-lab calibrate-detector`).
#[derive(Clone, Debug)]
pub struct Evidence {
    /// The sketch model's best figures (best first; any score), `None` when it did not run or
    /// no pyramid level fit the search range.
    pub sketch: Option<Vec<Detection>>,
    /// The sketch model's own threshold.
    pub sketch_threshold: f64,
    /// BlazePose's figure (any pose flag), `None` when it did not run or found no ink.
    pub blazepose: Option<BlazePoseDetection>,
    /// The ink inside the head ([`facing::head_ink`] at BlazePose's
    /// head, else the sketch model's), `None` without a candidate: evidence of the facing.
    pub head_ink: Option<facing::HeadInk>,
    /// The image's tone around the same candidate ([`tone::image_tone`]), `None` without a
    /// candidate (or when it cannot be measured): a sign of a photo. `None` counts as a drawing.
    pub tone: Option<tone::ImageTone>,
}

/// The candidate the image evidence of `e` is measured at: BlazePose's figure, else the sketch
/// model's best.
fn measured_candidate(e: &Evidence) -> Option<&Joints2> {
    e.blazepose.as_ref().map(|b| &b.joints).or_else(|| e.sketch.as_ref().and_then(|v| v.first()).map(|d| &d.joints))
}

/// The head ink of `image` for the candidates of `e` ([`Evidence::head_ink`]).
pub fn head_ink_of(image: &ImageView<'_>, e: &Evidence) -> Option<facing::HeadInk> {
    measured_candidate(e).and_then(|j| facing::head_ink(image, j))
}

/// `e` with its head ink and tone measured on `image` ([`Evidence::head_ink`],
/// [`Evidence::tone`]).
pub fn with_image_evidence(image: &ImageView<'_>, mut e: Evidence) -> Evidence {
    e.head_ink = head_ink_of(image, &e);
    e.tone = measured_candidate(&e).and_then(|j| tone::image_tone(image, j).ok());
    e
}

/// Runs the backends `backend` names on `image` (1, 3 or 4 channels) and collects their
/// candidates without thresholds. Errors: `ImageTooSmall`, bad options, the models' errors.
pub fn gather(
    image: &ImageView<'_>,
    model: &Model,
    net: &LandmarkNet,
    backend: Backend,
    options: &FigureOptions,
) -> Result<Evidence> {
    // The two backends are independent: BlazePose (one thread) runs beside the sketch model
    // (which spreads over the pool), so `auto` costs little more wall time than the slower one.
    let run_sketch = || -> Result<Option<Vec<Detection>>> {
        if backend == Backend::BlazePose {
            return Ok(None);
        }
        let o = DetectOptions { threshold: Some(f64::MIN), ..options.sketch.clone() };
        match detect(image, model, &o) {
            Ok(d) => Ok(Some(d.all)),
            Err(Error::NoFigure { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    };
    let run_blazepose = || -> Result<Option<BlazePoseDetection>> {
        if backend == Backend::Fmp {
            return Ok(None);
        }
        let o = BlazePoseOptions { min_pose_flag: 0.0, ..options.blazepose };
        match detect_blazepose(net, image, &o) {
            Ok(d) => Ok(Some(d)),
            Err(Error::NoFigure { .. } | Error::Degenerate(_)) => Ok(None),
            Err(e) => Err(e),
        }
    };
    let (sketch, blazepose) = rayon::join(run_sketch, run_blazepose);
    let (sketch, blazepose) = (sketch?, blazepose?);
    let evidence = Evidence { sketch, sketch_threshold: model.thresh, blazepose, head_ink: None, tone: None };
    if backend == Backend::Auto {
        return retry_blazepose_from_sketch(image, net, evidence, options);
    }
    Ok(with_image_evidence(image, evidence))
}

/// `Auto`'s last step of [`gather`]: BlazePose unsure from the ink box (pose flag under
/// `retry_below`) retries from the boxes of the sketch model's [`SKETCH_ROIS`] best figures
/// ([`crate::detect::landmark::retry_from`], kept at a pose flag ≥ [`SKETCH_ROI_ACCEPT`]): a
/// figure small on a busy page, which the ink box frames loosely, is framed by the sketch model's
/// search. The evidence is returned as it is without both backends' candidates; its head ink
/// is measured at the candidates returned. Errors: the network's.
pub fn retry_blazepose_from_sketch(
    image: &ImageView<'_>,
    net: &LandmarkNet,
    evidence: Evidence,
    options: &FigureOptions,
) -> Result<Evidence> {
    let Evidence { sketch, sketch_threshold, blazepose, .. } = evidence;
    let blazepose = match (blazepose, &sketch) {
        (Some(b), Some(s)) => {
            let rois: Vec<Roi> = s.iter().take(SKETCH_ROIS).filter_map(|d| Roi::from_box(d.bbox).ok()).collect();
            Some(retry_from(net, image, b, &rois, SKETCH_ROI_ACCEPT, &options.blazepose)?)
        }
        (b, _) => b,
    };
    Ok(with_image_evidence(image, Evidence { sketch, sketch_threshold, blazepose, head_ink: None, tone: None }))
}

/// The figure [`detect_figure`] returns.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// The backend whose joints these are (`Fmp` or `BlazePose`; `Auto` when [`Fusion::PerLimb`]
    /// took limbs from both).
    pub backend: Backend,
    /// The canonical 15 joints, px.
    pub joints: Joints2,
    /// Calibrated per-joint confidence: the estimated probability that the joint is correct at
    /// PCK@0.2, in [0, 1].
    pub joint_confidence: [f64; NUM_JOINTS],
    /// The figure's confidence, the mean of `joint_confidence`: the expected fraction of correct
    /// joints, in [0, 1].
    pub confidence: f64,
    /// The calibrated probability that the image holds a figure, in [0, 1] (with both backends,
    /// the higher of the two-backend model's and BlazePose's own: [`presence_log_odds`]).
    pub presence: f64,
    /// `confidence` < [`LOW_CONFIDENCE`]: look at the overlay and correct the joints.
    pub low_confidence: bool,
    /// The backend's raw score (the sketch model's score or BlazePose's pose flag).
    pub raw_score: f64,
    /// Other figures the sketch model found above its threshold (its NMS list after its best,
    /// which is the figure itself or overlaps it), best first.
    pub others: Vec<Detection>,
    /// BlazePose's relative depth of each joint (px at the image's scale, smaller is nearer the
    /// camera, relative to the hips) where its 2-D joint lies within [`DEPTH_AGREEMENT`] of the
    /// figure's size from the chosen joint (`None` at the others), whichever backend's joints
    /// were chosen; all `None` when BlazePose did not run. A cue for the pose step
    /// (the pose module's `DepthHint`).
    pub landmark_depth: [Option<f64>; NUM_JOINTS],
    /// Joints that are the mean of both backends' ([`FigureOptions::average_agreement`]); all
    /// `false` when one backend answered.
    pub averaged: [bool; NUM_JOINTS],
    /// BlazePose's own 15 joints (px) with all their depths, when it ran and its joints agree
    /// with the chosen ones (median distance ≤ [`DEPTH_AGREEMENT`] of the figure's size); `None`
    /// otherwise. The same figure as `joints`, read by the network that also gives depths.
    pub landmark_joints: Option<(Joints2, [f64; NUM_JOINTS])>,
    /// The figure's facing, its probabilities, whether the labelling rule swapped the joints,
    /// and the other labelling with its score.
    pub facing: FacingEstimate,
}

/// [`FigureOptions::average_agreement`]'s default: two backends' joints closer than this fraction
/// of the figure's size are averaged. Where both find the same joint their errors are largely
/// independent, so their mean is nearer the truth than either (docs/benchmarks-history.md,
/// "Averaging the backends where they agree").
pub const AVERAGE_AGREEMENT: f64 = 0.08;

/// Largest distance, as a fraction of the figure's size, between BlazePose's 2-D joint and the
/// chosen joint for BlazePose's depth of that joint to count ([`Figure::landmark_depth`]).
pub const DEPTH_AGREEMENT: f64 = 0.1;

/// BlazePose's depths as seen from `chosen`: per joint where its 2-D joint agrees
/// ([`Figure::landmark_depth`]) and its whole figure when most joints do
/// ([`Figure::landmark_joints`]), its sides swapped first when `swapped` (the labelling rule
/// swapped its candidate). Both empty without a BlazePose pass.
#[allow(clippy::type_complexity)]
fn landmark_view(
    evidence: &Evidence,
    chosen: &Joints2,
    swapped: bool,
) -> ([Option<f64>; NUM_JOINTS], Option<(Joints2, [f64; NUM_JOINTS])>) {
    let none = ([None; NUM_JOINTS], None);
    let Some(b) = &evidence.blazepose else { return none };
    let z: Vec<f64> = b.pass.landmarks.iter().map(|l| l.z).collect();
    if z.len() < super::landmark::NUM_POSE_LANDMARKS {
        return none;
    }
    let mut depth = super::landmark::joints::canonical_depth(&z);
    let mut joints = b.joints;
    if swapped {
        (depth, joints) = (facing::mirror_values(&depth), facing::swap_sides(&joints));
    }
    let (dist, median) = agreement(chosen, &joints);
    let per_joint = std::array::from_fn(|j| (dist[j] <= DEPTH_AGREEMENT && depth[j].is_finite()).then_some(depth[j]));
    let whole = (median <= DEPTH_AGREEMENT && depth.iter().all(|d| d.is_finite())).then_some((joints, depth));
    (per_joint, whole)
}

/// Distances between the two backends' joints over the figure's size (the longer side of the
/// BlazePose joints' bounding box, at least 1 px), and their median.
fn agreement(a: &Joints2, b: &Joints2) -> ([f64; NUM_JOINTS], f64) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &b.xy {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0);
    let mut d = [0.0; NUM_JOINTS];
    for j in 0..NUM_JOINTS {
        d[j] = (a.xy[j][0] - b.xy[j][0]).hypot(a.xy[j][1] - b.xy[j][1]) / size;
    }
    let mut s = d;
    s.sort_by(f64::total_cmp);
    (d, s[NUM_JOINTS / 2])
}

/// One backend's candidate with the inputs of the calibration's joint models.
#[derive(Clone, Debug, PartialEq)]
pub struct CandidateFeatures {
    /// `Fmp` or `BlazePose`.
    pub backend: Backend,
    /// The candidate's joints, px.
    pub joints: Joints2,
    /// The backend's raw score (sketch model score or pose flag).
    pub raw_score: f64,
    /// Per joint, the features of the backend-alone model.
    pub alone: Vec<Vec<f64>>,
    /// Per joint, the features of the both-backends model (`None` when only one backend found a
    /// candidate).
    pub auto: Option<Vec<Vec<f64>>>,
}

/// Everything [`decide`] and the calibration read from one image's evidence.
#[derive(Clone, Debug, PartialEq)]
pub struct EvidenceFeatures {
    /// The candidates (sketch model first).
    pub candidates: Vec<CandidateFeatures>,
    /// Presence features from the sketch model alone (when it found a candidate).
    pub presence_fmp: Option<Vec<f64>>,
    /// Presence features from BlazePose alone.
    pub presence_blazepose: Option<Vec<f64>>,
    /// Presence features from both (when both found a candidate).
    pub presence_auto: Option<Vec<f64>>,
}

/// The calibration features of `evidence`: the sketch score enters relative to the model's
/// threshold, the agreement as distances over the figure's size.
pub fn features(evidence: &Evidence) -> EvidenceFeatures {
    let sketch = evidence.sketch.as_ref().and_then(|v| v.first());
    let bp = evidence.blazepose.as_ref();
    let sketch_score = sketch.map(|d| clamp_score(d.score - evidence.sketch_threshold));
    let agree = match (sketch, bp) {
        (Some(s), Some(b)) => Some(agreement(&s.joints, &b.joints)),
        _ => None,
    };
    let rows = |raw: &[f64; NUM_JOINTS], score: f64, with: bool| -> Vec<Vec<f64>> {
        (0..NUM_JOINTS)
            .map(|j| joint_features(raw[j], score, if with { agree.as_ref().map(|(d, m)| (d[j], *m)) } else { None }))
            .collect()
    };
    let mut candidates = Vec::new();
    if let (Some(s), Some(score)) = (sketch, sketch_score) {
        candidates.push(CandidateFeatures {
            backend: Backend::Fmp,
            joints: s.joints,
            raw_score: s.score,
            alone: rows(&s.confidence, score, false),
            auto: agree.as_ref().map(|_| rows(&s.confidence, score, true)),
        });
    }
    if let Some(b) = bp {
        candidates.push(CandidateFeatures {
            backend: Backend::BlazePose,
            joints: b.joints,
            raw_score: b.score,
            alone: rows(&b.confidence, b.score, false),
            auto: agree.as_ref().map(|_| rows(&b.confidence, b.score, true)),
        });
    }
    EvidenceFeatures {
        candidates,
        presence_fmp: sketch_score.map(|s| presence_features(Some(s), None, None)),
        presence_blazepose: bp.map(|b| presence_features(None, Some(b.score), None)),
        presence_auto: match (sketch_score, bp, &agree) {
            (Some(s), Some(b), Some(a)) => Some(presence_features(Some(s), Some(b.score), Some(a.1))),
            _ => None,
        },
    }
}

fn mean(c: &[f64; NUM_JOINTS]) -> f64 {
    c.iter().sum::<f64>() / NUM_JOINTS as f64
}

/// The referee of [`Fusion::PerImage`] between the two backends' candidates of one drawing:
/// which joint set (0 or 1) to keep, `Ok(None)` for no preference (the higher mean calibrated
/// confidence then decides). The product's referee is the 3-D pose step (the `pipeline` module's
/// `proportion_choice`, which sees both steps); detection alone has none.
pub type Referee<'a> = &'a dyn Fn(&Joints2, &Joints2) -> Result<Option<usize>>;

/// A candidate of one backend with its calibrated confidences.
#[derive(Clone, Copy)]
struct Scored {
    backend: Backend,
    joints: Joints2,
    conf: [f64; NUM_JOINTS],
    raw_score: f64,
    /// The labelling rule swapped its sides.
    swapped: bool,
}

/// The facing features of `evidence` ([`facing::facing_features`] of its candidates).
pub fn evidence_facing_features(evidence: &Evidence) -> [f64; facing::NUM_FEATURES] {
    let input = FacingInput {
        sketch: evidence.sketch.as_ref().and_then(|v| v.first()).map(|d| &d.joints),
        blazepose: evidence.blazepose.as_ref().map(|b| &b.joints),
        landmarks: evidence.blazepose.as_ref().map(|b| b.pass.landmarks.as_slice()),
        head_ink: evidence.head_ink,
    };
    facing::facing_features(&input)
}

/// The facing the labelling rule acts on: the decided one ([`facing::decided`]), except that
/// on a photo-like image ([`tone::ImageTone::photo_like`]) a back view is not decided (the
/// facing model knows drawings; on photos its "back" is as often a person facing the camera).
pub fn facing_acted_on(evidence: &Evidence, probabilities: &[f64; 4]) -> facing::Facing {
    let decided = facing::decided(probabilities);
    let photo = evidence.tone.is_some_and(|t| t.photo_like());
    if photo && decided == facing::Facing::Back {
        facing::Facing::Unknown
    } else {
        decided
    }
}

/// The facing probabilities of `evidence` under `model`.
pub fn facing_probabilities(evidence: &Evidence, model: &FacingModel) -> [f64; 4] {
    model.probabilities(&evidence_facing_features(evidence))
}

/// The log-odds of a figure that [`decide`] thresholds for features `f`: when both backends
/// found a candidate, the higher of the two-backend presence model's and BlazePose's own (a
/// figure BlazePose alone is sure of is not refused because the sketch model, which does not
/// read photo-like styles, disagrees; the sketch model's own presence is not taken, as it
/// answers most clutter pages), else the model of the one backend that did; `None` when neither
/// did. Measured in docs/benchmarks-history.md ("Either presence"). Errors: `CorruptData` for a
/// calibration of the wrong shape.
pub fn presence_log_odds(f: &EvidenceFeatures, cal: &Calibration) -> Result<Option<f64>> {
    match (&f.presence_auto, &f.presence_fmp, &f.presence_blazepose) {
        (Some(x), _, Some(b)) => Ok(Some(log_odds(&cal.presence.auto, x)?.max(log_odds(&cal.presence.blazepose, b)?))),
        (Some(x), _, None) => log_odds(&cal.presence.auto, x).map(Some),
        (None, Some(x), _) => log_odds(&cal.presence.fmp, x).map(Some),
        (None, None, Some(x)) => log_odds(&cal.presence.blazepose, x).map(Some),
        (None, None, None) => Ok(None),
    }
}

/// Decides the figure from `evidence` with calibration `cal`; `referee` (when given) picks
/// between the two backends' candidates under [`Fusion::PerImage`]. Errors: `NoFigure` (with the
/// presence probability as its score and `min_presence` as its threshold, or the backend's own
/// score and threshold when strict) when no candidate counts as a figure; `CorruptData` for a
/// calibration of the wrong shape; the referee's errors.
pub fn decide(
    evidence: &Evidence,
    cal: &Calibration,
    options: &FigureOptions,
    referee: Option<Referee<'_>>,
) -> Result<Figure> {
    let f = features(evidence);
    let mut cands = Vec::new();
    for c in &f.candidates {
        let (w, rows) = match (c.backend, &c.auto) {
            (Backend::Fmp, Some(r)) => (&cal.joints.fmp_auto, r),
            (Backend::Fmp, None) => (&cal.joints.fmp, &c.alone),
            (_, Some(r)) => (&cal.joints.blazepose_auto, r),
            (_, None) => (&cal.joints.blazepose, &c.alone),
        };
        let mut conf = [0.0; NUM_JOINTS];
        for j in 0..NUM_JOINTS {
            conf[j] = predict(w, &rows[j])?;
        }
        cands.push(Scored { backend: c.backend, joints: c.joints, conf, raw_score: c.raw_score, swapped: false });
    }
    let model = match &options.facing_model {
        Some(m) => m,
        None => FacingModel::embedded()?,
    };
    let probabilities = facing_probabilities(evidence, model);
    let acted = facing_acted_on(evidence, &probabilities);
    if options.facing_rule {
        let target = facing::target_handedness(acted, &probabilities);
        for c in &mut cands {
            if facing::needs_swap(&c.joints, target) {
                (c.joints, c.conf, c.swapped) = (facing::swap_sides(&c.joints), facing::mirror_values(&c.conf), true);
            }
        }
    }
    let blazepose_swapped = cands.iter().any(|c| c.backend == Backend::BlazePose && c.swapped);
    let presence = presence_log_odds(&f, cal)?.map_or(0.0, sigmoid);
    let sketch_threshold = options.sketch.threshold.unwrap_or(evidence.sketch_threshold);
    if options.strict {
        cands.retain(|c| match c.backend {
            Backend::Fmp => c.raw_score >= sketch_threshold,
            _ => c.raw_score >= options.blazepose.min_pose_flag,
        });
    } else if presence < options.min_presence {
        cands.clear();
    }
    if options.fusion == Fusion::PerLimb && cands.len() == 2 {
        let mut mixed = Scored { backend: cands[0].backend, ..cands[0] };
        let mut from = [0usize; 2];
        for g in LIMB_GROUPS {
            let sum = |c: &Scored| g.iter().map(|&j| c.conf[j]).sum::<f64>();
            let k = usize::from(sum(&cands[1]) > sum(&cands[0]));
            from[k] += 1;
            for &j in g {
                mixed.joints.xy[j] = cands[k].joints.xy[j];
                mixed.joints.visible[j] = cands[k].joints.visible[j];
                mixed.conf[j] = cands[k].conf[j];
            }
        }
        if from[0] > 0 && from[1] > 0 {
            mixed.backend = Backend::Auto;
            mixed.swapped = cands[0].swapped || cands[1].swapped;
        } else if from[1] > 0 {
            mixed = Scored { ..cands[1] };
        }
        cands = vec![mixed];
    }
    let sketch_passes = cands.iter().any(|c| c.backend == Backend::Fmp && c.raw_score >= sketch_threshold);
    let by_proportions = match referee {
        Some(choose) if options.fusion == Fusion::PerImage && cands.len() == 2 && sketch_passes => {
            choose(&cands[0].joints, &cands[1].joints)?
        }
        _ => None,
    };
    let pick = match by_proportions {
        Some(k) => Some(k),
        None => (0..cands.len()).max_by(|&a, &b| mean(&cands[a].conf).total_cmp(&mean(&cands[b].conf))),
    };
    let other = match (pick, cands.len()) {
        (Some(k), 2) => Some((cands[1 - k].backend, cands[1 - k].joints)),
        _ => None,
    };
    let best = pick.map(|k| cands.swap_remove(k));
    let Some(mut best) = best else {
        return Err(if options.strict {
            let sketch = evidence.sketch.as_ref().and_then(|v| v.first());
            match (sketch, &evidence.blazepose) {
                (Some(s), _) => Error::NoFigure { score: s.score, threshold: sketch_threshold },
                (None, Some(b)) => Error::NoFigure { score: b.score, threshold: options.blazepose.min_pose_flag },
                (None, None) => Error::NoFigure { score: f64::NEG_INFINITY, threshold: sketch_threshold },
            }
        } else {
            Error::NoFigure { score: presence, threshold: options.min_presence }
        });
    };
    let others = evidence.sketch.iter().flatten().skip(1).filter(|d| d.score >= sketch_threshold).cloned().collect();
    let averaged = match other {
        Some((backend, joints)) => average_agreeing(&mut best.joints, &joints, backend, options.average_agreement),
        None => [false; NUM_JOINTS],
    };
    let confidence = mean(&best.conf);
    let (landmark_depth, landmark_joints) = landmark_view(evidence, &best.joints, blazepose_swapped);
    let facing = FacingEstimate { facing: acted, ..facing::estimate(&best.joints, probabilities, best.swapped) };
    Ok(Figure {
        backend: best.backend,
        joints: best.joints,
        joint_confidence: best.conf,
        confidence,
        presence,
        low_confidence: confidence < LOW_CONFIDENCE,
        raw_score: best.raw_score,
        others,
        averaged,
        landmark_depth,
        landmark_joints,
        facing,
    })
}

/// Replaces each joint of `chosen` that lies within `within` of the figure's size (the BlazePose
/// candidate's, as [`agreement`] measures it) from the same joint of `other` (the other
/// backend's candidate, `other_backend`) by the two joints' mean; returns which joints were.
fn average_agreeing(chosen: &mut Joints2, other: &Joints2, other_backend: Backend, within: f64) -> [bool; NUM_JOINTS] {
    let mut averaged = [false; NUM_JOINTS];
    if !(within > 0.0) {
        return averaged;
    }
    let (dist, _) =
        if other_backend == Backend::BlazePose { agreement(chosen, other) } else { agreement(other, chosen) };
    for j in 0..NUM_JOINTS {
        if dist[j] < within {
            for k in 0..2 {
                chosen.xy[j][k] = 0.5 * (chosen.xy[j][k] + other.xy[j][k]);
            }
            averaged[j] = true;
        }
    }
    averaged
}

/// The best figure of `image` (1, 3 or 4 channels) by `options.backend`, with calibrated
/// confidences (the embedded calibration) and `referee` as in [`decide`]. Errors:
/// `ImageTooSmall`, `OutOfRange` / `NonFinite` for bad options, `NoFigure` (see [`decide`]), the
/// models' errors.
pub fn detect_figure(
    image: &ImageView<'_>,
    model: &Model,
    net: &LandmarkNet,
    options: &FigureOptions,
    referee: Option<Referee<'_>>,
) -> Result<Figure> {
    if !(0.0..=1.0).contains(&options.min_presence) {
        return Err(Error::OutOfRange {
            name: "min_presence",
            detail: format!("{} not in [0, 1]", options.min_presence),
        });
    }
    if !(options.average_agreement >= 0.0 && options.average_agreement.is_finite()) {
        return Err(Error::OutOfRange {
            name: "average_agreement",
            detail: format!("{} is not a finite fraction >= 0", options.average_agreement),
        });
    }
    let evidence = gather(image, model, net, options.backend, options)?;
    decide(&evidence, Calibration::embedded()?, options, referee)
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;

    use super::*;
    use crate::detect::calibration::{JointModels, PresenceModels};
    use crate::detect::landmark::{Landmark, RoiLandmarks};
    use crate::detect::NUM_PARSE_JOINTS;
    use crate::skeleton::joint;

    /// The sketch model's threshold in these tests.
    const THRESH: f64 = -0.7;

    /// A calibration that keeps the evidence readable: each joint's confidence is its raw one
    /// (σ(logit p) = p), the presence σ(score − threshold) from the sketch model (alone or with
    /// BlazePose) and σ(10 · flag − 5) from BlazePose (0.5 at a flag of 0.5).
    fn plain_calibration() -> Calibration {
        Calibration {
            format: "sketchbody-detector-calibration".into(),
            version: 1,
            provenance: "test".into(),
            joints: JointModels {
                fmp: vec![0.0, 1.0, 0.0],
                blazepose: vec![0.0, 1.0, 0.0],
                fmp_auto: vec![0.0, 1.0, 0.0, 0.0, 0.0],
                blazepose_auto: vec![0.0, 1.0, 0.0, 0.0, 0.0],
            },
            presence: PresenceModels {
                fmp: vec![0.0, 1.0],
                blazepose: vec![-5.0, 10.0],
                auto: vec![0.0, 1.0, 0.0, 0.0],
            },
        }
    }

    /// A standing figure 420 px tall (the standing prior's, its left ankle level with the
    /// right), shifted right by `dx` px.
    fn standing(dx: f64) -> Joints2 {
        let mut xy = crate::pose::plausibility::tests::standing_uv();
        xy[joint::L_ANKLE][1] = xy[joint::R_ANKLE][1];
        for p in &mut xy {
            p[0] += dx;
        }
        Joints2 { xy, visible: [true; NUM_JOINTS] }
    }

    fn sketch(score: f64, joints: Joints2, confidence: [f64; NUM_JOINTS]) -> Detection {
        Detection {
            score,
            joints,
            confidence,
            parse_joints: [[0.0; 2]; NUM_PARSE_JOINTS],
            parts: Vec::new(),
            bbox: [0.0, 0.0, 1.0, 1.0],
            cell_px: 8.0,
        }
    }

    /// BlazePose's figure; landmark `i` at depth `i` px.
    fn blazepose(flag: f64, joints: Joints2, confidence: [f64; NUM_JOINTS]) -> BlazePoseDetection {
        let landmarks =
            (0..39).map(|i| Landmark { x: 0.0, y: 0.0, z: i as f64, visibility: 0.9, presence: 0.9 }).collect();
        BlazePoseDetection {
            score: flag,
            joints,
            confidence,
            pass: RoiLandmarks { roi: Roi { cx: 0.0, cy: 0.0, size: 1.0, rotation: 0.0 }, landmarks, pose_flag: flag },
            rois_tried: 1,
            filled: false,
        }
    }

    fn both(score: f64, fmp_conf: f64, flag: f64, bp_conf: f64) -> Evidence {
        Evidence {
            sketch: Some(vec![sketch(score, standing(0.0), [fmp_conf; NUM_JOINTS])]),
            sketch_threshold: THRESH,
            blazepose: Some(blazepose(flag, standing(50.0), [bp_conf; NUM_JOINTS])),
            head_ink: None,
            tone: None,
        }
    }

    /// The sketch model's figure `fmp` (confidence 0.9) above BlazePose's `bp` (0.6).
    fn sketch_over(fmp: Joints2, bp: Joints2) -> Evidence {
        Evidence {
            sketch: Some(vec![sketch(THRESH + 1.0, fmp, [0.9; NUM_JOINTS])]),
            sketch_threshold: THRESH,
            blazepose: Some(blazepose(0.9, bp, [0.6; NUM_JOINTS])),
            head_ink: None,
            tone: None,
        }
    }

    fn no_figure(r: Result<Figure>) -> (f64, f64) {
        match r {
            Err(Error::NoFigure { score, threshold }) => (score, threshold),
            other => panic!("expected NoFigure, got {other:?}"),
        }
    }

    /// Issue 51: on a photo-like image a back view is not acted on (its labelling falls back to
    /// the front's default); on a drawing, or without a tone, it is; other facings are as decided.
    #[test]
    fn a_back_view_is_acted_on_only_on_drawings() {
        let tone =
            |paper: f64, edges: f64| tone::ImageTone { paper, mid: 0.0, saturation: 0.0, edges, edges_outside: 0.0 };
        let with = |t: Option<tone::ImageTone>| Evidence { tone: t, ..both(THRESH, 0.9, 0.9, 0.9) };
        let back = [0.1, 0.8, 0.05, 0.05];
        let front = [0.8, 0.1, 0.05, 0.05];
        let (drawing, photo, stylised) = (tone(0.96, 0.04), tone(0.3, 0.2), tone(0.85, 0.3));
        assert!(!drawing.photo_like() && photo.photo_like() && stylised.photo_like());
        assert_eq!(facing_acted_on(&with(Some(drawing)), &back), facing::Facing::Back);
        assert_eq!(facing_acted_on(&with(None), &back), facing::Facing::Back);
        assert_eq!(facing_acted_on(&with(Some(photo)), &back), facing::Facing::Unknown);
        assert_eq!(facing_acted_on(&with(Some(stylised)), &back), facing::Facing::Unknown);
        assert_eq!(facing_acted_on(&with(Some(photo)), &front), facing::Facing::Front);
        let even = [0.3, 0.3, 0.2, 0.2];
        assert_eq!(facing_acted_on(&with(Some(drawing)), &even), facing::Facing::Unknown);
    }

    /// Issue 52 finding 13 (`decide`'s `>=` → `<`): per image, the referee chooses between the
    /// two candidates when the sketch model's figure passes its own threshold (exactly at it
    /// counts), and is not asked otherwise; without it the surer candidate wins.
    #[test]
    fn the_referee_decides_only_when_the_sketch_model_recognises_the_drawing() {
        let cal = plain_calibration();
        let o = FigureOptions::default();
        let calls = Cell::new(0);
        let pick_sketch = |_: &Joints2, _: &Joints2| -> Result<Option<usize>> {
            calls.set(calls.get() + 1);
            Ok(Some(0))
        };
        for (score, want, asked) in
            [(THRESH, Backend::Fmp, 1), (THRESH + 1.0, Backend::Fmp, 1), (THRESH - 0.01, Backend::BlazePose, 0)]
        {
            calls.set(0);
            let f = decide(&both(score, 0.6, 0.9, 0.9), &cal, &o, Some(&pick_sketch)).unwrap();
            assert_eq!((f.backend, calls.get()), (want, asked), "sketch score {score}");
            assert_eq!(f.joints, standing(if want == Backend::Fmp { 0.0 } else { 50.0 }));
        }
        let e = both(THRESH + 1.0, 0.6, 0.9, 0.9);
        assert_eq!(decide(&e, &cal, &o, None).unwrap().backend, Backend::BlazePose);
        let confidence = FigureOptions { fusion: Fusion::Confidence, ..o.clone() };
        assert_eq!(decide(&e, &cal, &confidence, Some(&pick_sketch)).unwrap().backend, Backend::BlazePose);
        let undecided = |_: &Joints2, _: &Joints2| -> Result<Option<usize>> { Ok(None) };
        assert_eq!(decide(&e, &cal, &o, Some(&undecided)).unwrap().backend, Backend::BlazePose);
        let e = both(THRESH + 1.0, 0.9, 0.9, 0.6);
        let pick_blazepose = |_: &Joints2, _: &Joints2| -> Result<Option<usize>> { Ok(Some(1)) };
        assert_eq!(decide(&e, &cal, &o, Some(&pick_blazepose)).unwrap().backend, Backend::BlazePose);
        let failing = |_: &Joints2, _: &Joints2| -> Result<Option<usize>> { Err(Error::Degenerate("referee".into())) };
        assert!(matches!(decide(&e, &cal, &o, Some(&failing)), Err(Error::Degenerate(_))));
    }

    /// `strict`: a candidate counts only at or above its backend's own threshold (the sketch
    /// model's, BlazePose's pose flag 0.5), whatever its confidence; with none, `NoFigure`
    /// reports the sketch model's score and threshold, else BlazePose's.
    #[test]
    fn strict_keeps_only_candidates_passing_their_backends_own_threshold() {
        let cal = plain_calibration();
        let o = FigureOptions { strict: true, ..FigureOptions::default() };
        assert_eq!(decide(&both(THRESH - 0.1, 0.9, 0.5, 0.6), &cal, &o, None).unwrap().backend, Backend::BlazePose);
        assert_eq!(decide(&both(THRESH, 0.6, 0.49, 0.9), &cal, &o, None).unwrap().backend, Backend::Fmp);
        assert_eq!(no_figure(decide(&both(THRESH - 0.1, 0.9, 0.3, 0.9), &cal, &o, None)), (THRESH - 0.1, THRESH));
        let bp_only = Evidence { sketch: None, ..both(0.0, 0.9, 0.3, 0.9) };
        assert_eq!(no_figure(decide(&bp_only, &cal, &o, None)), (0.3, 0.5));
        let neither = Evidence { sketch: None, sketch_threshold: THRESH, blazepose: None, head_ink: None, tone: None };
        assert_eq!(no_figure(decide(&neither, &cal, &o, None)), (f64::NEG_INFINITY, THRESH));
        // Not strict, the low-flag BlazePose figure is kept when the presence says so.
        let lenient = FigureOptions { min_presence: 0.0, ..FigureOptions::default() };
        assert_eq!(decide(&bp_only, &cal, &lenient, None).unwrap().backend, Backend::BlazePose);
    }

    /// Not strict: the calibrated presence (the surer of the two-backend model and BlazePose's
    /// own when both ran) decides "no figure", at `min_presence` and above a figure.
    #[test]
    fn a_presence_under_the_minimum_is_no_figure() {
        let cal = plain_calibration();
        let o = FigureOptions::default();
        let bp_only = |flag: f64| Evidence { sketch: None, ..both(0.0, 0.9, flag, 0.9) };
        let f = decide(&bp_only(0.5), &cal, &o, None).unwrap();
        assert_eq!(f.presence, 0.5);
        let (score, threshold) = no_figure(decide(&bp_only(0.45), &cal, &o, None));
        assert!((score - sigmoid(-0.5)).abs() < 1e-12 && threshold == 0.5, "{score} {threshold}");
        let low = FigureOptions { min_presence: 0.3, ..o.clone() };
        assert!((decide(&bp_only(0.45), &cal, &low, None).unwrap().presence - sigmoid(-0.5)).abs() < 1e-12);
        let sketch_only = Evidence { blazepose: None, ..both(THRESH + 2.0, 0.9, 0.0, 0.0) };
        assert!((decide(&sketch_only, &cal, &o, None).unwrap().presence - sigmoid(2.0)).abs() < 1e-12);
        // Both: the two-backend model says σ(−1), BlazePose's own σ(4), and the reverse.
        assert!(
            (decide(&both(THRESH - 1.0, 0.9, 0.9, 0.6), &cal, &o, None).unwrap().presence - sigmoid(4.0)).abs() < 1e-12
        );
        assert!(
            (decide(&both(THRESH + 3.0, 0.9, 0.2, 0.6), &cal, &o, None).unwrap().presence - sigmoid(3.0)).abs() < 1e-12
        );
        assert!(no_figure(decide(&both(THRESH - 1.0, 0.9, 0.3, 0.6), &cal, &o, None)).0 < 0.5);
    }

    /// `PerLimb`: each limb group whole from the backend whose confidences over it sum higher
    /// (the sketch model's on a tie); `Auto` when the limbs come from both, else that backend.
    #[test]
    fn per_limb_fusion_takes_each_limb_from_the_surer_backend() {
        let cal = plain_calibration();
        let o = FigureOptions { fusion: Fusion::PerLimb, average_agreement: 0.0, ..FigureOptions::default() };
        let mut fmp_conf = [0.5; NUM_JOINTS];
        for j in [2, 3, 4, 13, 14] {
            fmp_conf[j] = 0.9;
        }
        fmp_conf[0] = 0.7;
        fmp_conf[1] = 0.7;
        let mut e = both(THRESH + 1.0, 0.0, 0.9, 0.7);
        e.sketch.as_mut().unwrap()[0].confidence = fmp_conf;
        let f = decide(&e, &cal, &o, None).unwrap();
        assert_eq!(f.backend, Backend::Auto);
        let (a, b) = (standing(0.0), standing(50.0));
        for j in 0..NUM_JOINTS {
            let from_fmp = [0, 1, 2, 3, 4, 13, 14].contains(&j);
            assert_eq!(f.joints.xy[j], if from_fmp { a.xy[j] } else { b.xy[j] }, "joint {j}");
            let want = if from_fmp { fmp_conf[j] } else { 0.7 };
            assert!((f.joint_confidence[j] - want).abs() < 1e-9, "joint {j}: {}", f.joint_confidence[j]);
        }
        assert!((f.confidence - f.joint_confidence.iter().sum::<f64>() / 15.0).abs() < 1e-12);
        let f = decide(&both(THRESH + 1.0, 0.9, 0.9, 0.6), &cal, &o, None).unwrap();
        assert_eq!((f.backend, f.joints), (Backend::Fmp, a));
        let f = decide(&both(THRESH + 1.0, 0.6, 0.9, 0.9), &cal, &o, None).unwrap();
        assert_eq!((f.backend, f.joints, f.raw_score), (Backend::BlazePose, b, 0.9));
    }

    /// Joints of the chosen candidate within `average_agreement` of the figure's size (the
    /// BlazePose joints' box, 420 px here) of the other backend's become the two joints' mean;
    /// the others, every joint with the option at 0, and a lone backend's stay.
    #[test]
    fn joints_the_backends_agree_on_are_averaged() {
        let cal = plain_calibration();
        let o = FigureOptions::default();
        let bp = standing(0.0);
        let mut fmp = bp;
        fmp.xy[joint::R_WRIST][0] += 30.0; // 0.071 of 420 px
        fmp.xy[joint::L_WRIST][0] += 36.0; // 0.086
        let e = sketch_over(fmp, bp);
        let f = decide(&e, &cal, &o, None).unwrap();
        assert_eq!(f.backend, Backend::Fmp);
        for j in 0..NUM_JOINTS {
            assert_eq!(f.averaged[j], j != joint::L_WRIST, "joint {j}");
        }
        assert_eq!(f.joints.xy[joint::R_WRIST], [bp.xy[joint::R_WRIST][0] + 15.0, bp.xy[joint::R_WRIST][1]]);
        assert_eq!(f.joints.xy[joint::L_WRIST], fmp.xy[joint::L_WRIST]);
        let off = FigureOptions { average_agreement: 0.0, ..o.clone() };
        let f = decide(&e, &cal, &off, None).unwrap();
        assert_eq!((f.joints, f.averaged), (fmp, [false; NUM_JOINTS]));
        let alone = Evidence { blazepose: None, ..e };
        assert_eq!(decide(&alone, &cal, &o, None).unwrap().averaged, [false; NUM_JOINTS]);
    }

    /// BlazePose's depth of a joint rides along where its 2-D joint lies within
    /// [`DEPTH_AGREEMENT`] of the chosen one, its whole figure when the median joint does; none
    /// without a BlazePose pass of all 33 landmarks.
    #[test]
    fn blazepose_depths_ride_along_where_its_joints_agree() {
        let cal = plain_calibration();
        let o = FigureOptions { average_agreement: 0.0, ..FigureOptions::default() };
        let fmp = standing(0.0);
        let mut bp = fmp;
        bp.xy[joint::R_WRIST][1] += 42.0; // exactly 0.1 of 420 px: agrees
        bp.xy[joint::L_WRIST][1] += 50.0;
        let depth = crate::detect::landmark::joints::canonical_depth(&(0..39).map(f64::from).collect::<Vec<_>>());
        let e = sketch_over(fmp, bp);
        let f = decide(&e, &cal, &o, None).unwrap();
        assert_eq!(f.backend, Backend::Fmp);
        for j in 0..NUM_JOINTS {
            assert_eq!(f.landmark_depth[j], (j != joint::L_WRIST).then_some(depth[j]), "joint {j}");
        }
        assert_eq!(f.landmark_joints, Some((bp, depth)));
        // Most joints off by more than a tenth of the figure: no whole figure, no depths there.
        let far = sketch_over(fmp, standing(50.0));
        let f = decide(&far, &cal, &o, None).unwrap();
        assert_eq!((f.landmark_depth, f.landmark_joints), ([None; NUM_JOINTS], None));
        let mut short = e.clone();
        short.blazepose.as_mut().unwrap().pass.landmarks.truncate(32);
        let f = decide(&short, &cal, &o, None).unwrap();
        assert_eq!((f.landmark_depth, f.landmark_joints), ([None; NUM_JOINTS], None));
    }

    /// The sketch model's further figures at or above its threshold are reported as `others`,
    /// best first; a figure whose confidence is under [`LOW_CONFIDENCE`] is flagged.
    #[test]
    fn other_figures_and_low_confidence_are_reported() {
        let cal = plain_calibration();
        let o = FigureOptions::default();
        let list = [THRESH + 1.0, THRESH + 0.2, THRESH, THRESH - 0.1]
            .map(|s| sketch(s, standing(0.0), [0.76; NUM_JOINTS]))
            .to_vec();
        let e = Evidence {
            sketch: Some(list.clone()),
            sketch_threshold: THRESH,
            blazepose: None,
            head_ink: None,
            tone: None,
        };
        let f = decide(&e, &cal, &o, None).unwrap();
        assert_eq!(f.others, list[1..3].to_vec());
        assert_eq!(f.raw_score, THRESH + 1.0);
        assert!(!f.low_confidence && (f.confidence - 0.76).abs() < 1e-9, "{}", f.confidence);
        let mut unsure = e;
        unsure.sketch.as_mut().unwrap()[0].confidence = [0.74; NUM_JOINTS];
        assert!(decide(&unsure, &cal, &o, None).unwrap().low_confidence);
    }
}

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
use super::landmark::roi::Roi;
use super::landmark::{detect_blazepose, retry_from, BlazePoseDetection, BlazePoseOptions, LandmarkNet};
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
    let evidence = Evidence { sketch, sketch_threshold: model.thresh, blazepose };
    if backend == Backend::Auto {
        return retry_blazepose_from_sketch(image, net, evidence, options);
    }
    Ok(evidence)
}

/// `Auto`'s last step of [`gather`]: BlazePose unsure from the ink box (pose flag under
/// `retry_below`) retries from the boxes of the sketch model's [`SKETCH_ROIS`] best figures
/// ([`crate::detect::landmark::retry_from`], kept at a pose flag ≥ [`SKETCH_ROI_ACCEPT`]): a
/// figure small on a busy page, which the ink box frames loosely, is framed by the sketch model's
/// search. The evidence is returned as it is without both backends' candidates. Errors: the
/// network's.
pub fn retry_blazepose_from_sketch(
    image: &ImageView<'_>,
    net: &LandmarkNet,
    evidence: Evidence,
    options: &FigureOptions,
) -> Result<Evidence> {
    let Evidence { sketch, sketch_threshold, blazepose } = evidence;
    let blazepose = match (blazepose, &sketch) {
        (Some(b), Some(s)) => {
            let rois: Vec<Roi> = s.iter().take(SKETCH_ROIS).filter_map(|d| Roi::from_box(d.bbox).ok()).collect();
            Some(retry_from(net, image, b, &rois, SKETCH_ROI_ACCEPT, &options.blazepose)?)
        }
        (b, _) => b,
    };
    Ok(Evidence { sketch, sketch_threshold, blazepose })
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
/// ([`Figure::landmark_joints`]). Both empty without a BlazePose pass.
#[allow(clippy::type_complexity)]
fn landmark_view(
    evidence: &Evidence,
    chosen: &Joints2,
) -> ([Option<f64>; NUM_JOINTS], Option<(Joints2, [f64; NUM_JOINTS])>) {
    let none = ([None; NUM_JOINTS], None);
    let Some(b) = &evidence.blazepose else { return none };
    let z: Vec<f64> = b.pass.landmarks.iter().map(|l| l.z).collect();
    if z.len() < super::landmark::NUM_POSE_LANDMARKS {
        return none;
    }
    let depth = super::landmark::joints::canonical_depth(&z);
    let (dist, median) = agreement(chosen, &b.joints);
    let per_joint = std::array::from_fn(|j| (dist[j] <= DEPTH_AGREEMENT && depth[j].is_finite()).then_some(depth[j]));
    let whole = (median <= DEPTH_AGREEMENT && depth.iter().all(|d| d.is_finite())).then_some((b.joints, depth));
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
        cands.push(Scored { backend: c.backend, joints: c.joints, conf, raw_score: c.raw_score });
    }
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
    let (landmark_depth, landmark_joints) = landmark_view(evidence, &best.joints);
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

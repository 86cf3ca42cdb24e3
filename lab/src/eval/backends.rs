//! Evaluation and calibration of the detector backends ([`sketchbody::detect::figure`]) on labelled
//! image sets: rendered sketches, PARSE photos (plain or stylised) and pages without a figure.
//! Each image's evidence is gathered once (both backends, each timed); every backend choice is
//! then scored from it: PCK@0.1 / @0.2 of the returned figure (0 when none), the no-figure rate,
//! and the reliability of the calibrated confidences.

use crate::detect::calibration_fit::fit_logistic;
use sketchbody::detect::calibration::{Calibration, JointModels, PresenceModels};
use sketchbody::detect::facing::{swap_sides, Facing};
use sketchbody::detect::figure::{
    features, gather, presence_log_odds, retry_blazepose_from_sketch, Backend, Evidence, FigureOptions,
};
use sketchbody::detect::landmark::{BlazePoseDetection, LandmarkNet};
use sketchbody::detect::Model;
use sketchbody::error::{Error, Result};
use sketchbody::image::ImageView;
use sketchbody::pipeline::figure::decide;
use sketchbody::skeleton::{Joints2, NUM_JOINTS};

use super::metrics::{pck, pck_normaliser};

/// One image's evidence, its ground truth and the backends' times.
#[derive(Clone, Debug)]
pub struct Sample {
    /// Both backends' candidates, as `Auto` gathers them (BlazePose retried from the sketch
    /// model's box when unsure: [`retry_blazepose_from_sketch`]).
    pub evidence: Evidence,
    /// BlazePose's candidate as the BlazePose backend alone gathers it.
    pub blazepose_alone: Option<BlazePoseDetection>,
    /// The true canonical joints, px; `None` for a page without a figure.
    pub truth: Option<[[f64; 2]; NUM_JOINTS]>,
    /// Wall time on this image of the sketch model, of BlazePose alone and of `Auto`'s retry
    /// of BlazePose from the sketch model's box, s.
    pub seconds: [f64; 3],
    /// The yaw of a rendered figure's torso as the camera sees it, degrees
    /// ([`super::facing::torso_yaw_deg`]; its true facing:
    /// [`sketchbody::detect::facing::Facing::of_yaw`]); `None` when unknown.
    pub yaw_deg: Option<f64>,
}

/// Runs both backends on `image` (timing each) and keeps their evidence with `truth`.
/// Errors: as [`gather`].
pub fn gather_sample(
    image: &ImageView<'_>,
    truth: Option<[[f64; 2]; NUM_JOINTS]>,
    model: &Model,
    net: &LandmarkNet,
    options: &FigureOptions,
) -> Result<Sample> {
    let t0 = std::time::Instant::now();
    let fmp = gather(image, model, net, Backend::Fmp, options)?;
    let t1 = std::time::Instant::now();
    let bp = gather(image, model, net, Backend::BlazePose, options)?;
    let t2 = std::time::Instant::now();
    let blazepose_alone = bp.blazepose.clone();
    let evidence = Evidence {
        sketch: fmp.sketch,
        sketch_threshold: fmp.sketch_threshold,
        blazepose: bp.blazepose,
        head_ink: None,
        tone: None,
    };
    let evidence = retry_blazepose_from_sketch(image, net, evidence, options)?;
    let t3 = std::time::Instant::now();
    let seconds = [t1 - t0, t2 - t1, t3 - t2].map(|d| d.as_secs_f64());
    Ok(Sample { evidence, blazepose_alone, truth, seconds, yaw_deg: None })
}

/// The evidence `backend` would have gathered on sample `s` (the head ink as `Auto` measured
/// it).
fn restricted(s: &Sample, backend: Backend) -> Evidence {
    let e = &s.evidence;
    Evidence {
        sketch: if backend == Backend::BlazePose { None } else { e.sketch.clone() },
        sketch_threshold: e.sketch_threshold,
        blazepose: match backend {
            Backend::Fmp => None,
            Backend::BlazePose => s.blazepose_alone.clone(),
            Backend::Auto => e.blazepose.clone(),
        },
        head_ink: e.head_ink,
        tone: e.tone,
    }
}

/// Per-joint correctness at PCK@0.2 of `joints` against `truth`.
fn correct(truth: &[[f64; 2]; NUM_JOINTS], joints: &[[f64; 2]; NUM_JOINTS]) -> [bool; NUM_JOINTS] {
    let thr = 0.2 * pck_normaliser(truth);
    let mut c = [false; NUM_JOINTS];
    for j in 0..NUM_JOINTS {
        c[j] = (truth[j][0] - joints[j][0]).hypot(truth[j][1] - joints[j][1]) <= thr;
    }
    c
}

/// Joints wrong by this many or more make a sketch a gross failure ([`SetScore::gross`]).
pub const GROSS_JOINTS: usize = 4;

/// Whether `joints` is a left/right swap of `truth`: the labelling with left and right swapped
/// puts at least [`GROSS_JOINTS`] more joints within 0.2 × the figure's size of the truth.
pub fn is_swap(truth: &[[f64; 2]; NUM_JOINTS], joints: &Joints2) -> bool {
    let count = |j: &[[f64; 2]; NUM_JOINTS]| correct(truth, j).iter().filter(|&&c| c).count();
    count(&swap_sides(joints).xy) >= count(&joints.xy) + GROSS_JOINTS
}

/// Fits every model of a [`Calibration`] on `samples` (images with a figure and pages without):
/// joint models on the candidates' per-joint correctness at PCK@0.2, presence models on whether
/// the image holds a figure. `ridge`: the L2 penalty. Errors: `OutOfRange` when a model has no
/// rows or only one outcome, and [`fit_logistic`]'s.
pub fn fit_calibration(samples: &[Sample], ridge: f64, provenance: &str) -> Result<Calibration> {
    #[derive(Default)]
    struct Rows {
        x: Vec<Vec<f64>>,
        y: Vec<bool>,
    }
    let mut joints: [Rows; 4] = Default::default();
    let mut presence: [Rows; 3] = Default::default();
    for s in samples {
        // Each model learns from the evidence its decision reads: the single-backend models
        // from what that backend gathers alone, the two-backend ones from `Auto`'s.
        let (f, fmp, bp) = (
            features(&s.evidence),
            features(&restricted(s, Backend::Fmp)),
            features(&restricted(s, Backend::BlazePose)),
        );
        let has = s.truth.is_some();
        for (k, x) in [&fmp.presence_fmp, &bp.presence_blazepose, &f.presence_auto].into_iter().enumerate() {
            if let Some(x) = x {
                presence[k].x.push(x.clone());
                presence[k].y.push(has);
            }
        }
        let Some(truth) = &s.truth else { continue };
        for c in fmp.candidates.iter().chain(&bp.candidates) {
            let ok = correct(truth, &c.joints.xy);
            let k = if c.backend == Backend::Fmp { 0 } else { 1 };
            for j in 0..NUM_JOINTS {
                joints[k].x.push(c.alone[j].clone());
                joints[k].y.push(ok[j]);
            }
        }
        for c in &f.candidates {
            let ok = correct(truth, &c.joints.xy);
            let k = if c.backend == Backend::Fmp { 2 } else { 3 };
            for (j, a) in c.auto.iter().flatten().enumerate() {
                joints[k].x.push(a.clone());
                joints[k].y.push(ok[j]);
            }
        }
    }
    let fit = |r: &Rows, name: &'static str| -> Result<Vec<f64>> {
        let pos = r.y.iter().filter(|&&v| v).count();
        if pos == 0 || pos == r.y.len() {
            return Err(Error::OutOfRange {
                name,
                detail: format!("{} rows with {pos} positive: need both outcomes", r.y.len()),
            });
        }
        fit_logistic(&r.x, &r.y, ridge)
    };
    Ok(Calibration {
        format: "sketchbody-detector-calibration".into(),
        version: 1,
        provenance: provenance.into(),
        joints: JointModels {
            fmp: fit(&joints[0], "fmp joint rows")?,
            blazepose: fit(&joints[1], "blazepose joint rows")?,
            fmp_auto: fit(&joints[2], "fmp_auto joint rows")?,
            blazepose_auto: fit(&joints[3], "blazepose_auto joint rows")?,
        },
        presence: PresenceModels {
            fmp: fit(&presence[0], "fmp presence rows")?,
            blazepose: fit(&presence[1], "blazepose presence rows")?,
            auto: fit(&presence[2], "auto presence rows")?,
        },
    })
}

/// Makes the presence models of `cal` stricter, if needed, so that the default decision
/// (`auto`, [`decide`] with `min_presence` 0.5) refuses at least a fraction `refuse` of every set
/// in `negative_sets` (pages without a figure, one set per kind): the three presence intercepts
/// are lowered by one amount until at most `⌊(1 − refuse) · n⌋` pages of each set reach
/// presence ≥ 0.5 with the model `decide` uses for the page. The presence models then give a
/// decision score rather than a calibrated probability of a figure (the joint confidences are
/// untouched). Returns the change of the intercepts (≤ 0). Errors: `OutOfRange` for `refuse`
/// outside [0, 1]; `CorruptData` for a calibration whose models do not fit the features.
pub fn refuse_negatives(cal: &mut Calibration, negative_sets: &[&[Sample]], refuse: f64) -> Result<f64> {
    if !(0.0..=1.0).contains(&refuse) {
        return Err(Error::OutOfRange { name: "refuse", detail: format!("{refuse} not in [0, 1]") });
    }
    let mut shift: f64 = 0.0;
    for set in negative_sets {
        // The presence log-odds of each page with evidence, from the model `decide` uses.
        let mut z = Vec::new();
        for sample in set.iter() {
            z.extend(presence_log_odds(&features(&sample.evidence), cal)?);
        }
        z.sort_by(|a, b| b.total_cmp(a));
        let allowed = ((1.0 - refuse) * set.len() as f64 + 1e-9).floor() as usize;
        if let Some(&kth) = z.get(allowed) {
            // Pages z[..allowed] may stay at or above 0; z[allowed] must fall below it.
            shift = shift.min(-kth - 1e-6);
        }
    }
    for w in [&mut cal.presence.fmp, &mut cal.presence.blazepose, &mut cal.presence.auto] {
        if let Some(w0) = w.first_mut() {
            *w0 += shift;
        }
    }
    Ok(shift)
}

/// One backend's score on one set.
#[derive(Clone, Debug, PartialEq)]
pub struct SetScore {
    /// Images in the set.
    pub n: usize,
    /// Mean PCK@0.1 and @0.2 over the images with a figure (0 for an image answered "no
    /// figure"); NaN for a set without figures.
    pub pck: [f64; 2],
    /// Fraction of images answered "no figure".
    pub no_figure: f64,
    /// Mean wall time of the backend(s) per image, s (`auto`: both, and its retry of BlazePose
    /// from the sketch model's box).
    pub seconds: f64,
    /// How often the answer came from fmp, blazepose, or limbs of both, as fractions of the
    /// answered images.
    pub chosen: [f64; 3],
    /// Fraction of the images with a figure that have [`GROSS_JOINTS`] or more joints beyond
    /// 0.2 × the figure's size (an image answered "no figure" counts); NaN without figures.
    pub gross: f64,
    /// Fraction of the images with a figure whose answer is a left/right swap ([`is_swap`]).
    pub swaps: f64,
    /// Over the images with a known yaw and an answer: the fractions whose reported facing is
    /// the true one ([`Facing::of_yaw`]), `unknown`, and another facing; NaN without them.
    pub facing: [f64; 3],
}

/// One bin of a reliability table: figures whose confidence fell in `[lo, hi)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReliabilityBin {
    /// Lower edge of the bin.
    pub lo: f64,
    /// Upper edge.
    pub hi: f64,
    /// Figures in the bin.
    pub n: usize,
    /// Their mean confidence.
    pub mean_confidence: f64,
    /// Their mean observed PCK@0.2.
    pub observed: f64,
}

/// Scores `options` (backend, strictness, fusion) on `samples` (one set). Errors: the metrics'
/// (degenerate ground truth) and a calibration of the wrong shape.
pub fn score_set(samples: &[Sample], cal: &Calibration, options: &FigureOptions) -> Result<SetScore> {
    let backend = options.backend;
    let (mut p1, mut p2, mut with, mut none, mut secs, mut chosen, mut answered) =
        (0.0, 0.0, 0usize, 0usize, 0.0, [0usize; 3], 0usize);
    let (mut gross, mut swaps, mut facing, mut with_yaw) = (0usize, 0usize, [0usize; 3], 0usize);
    for s in samples {
        secs += match backend {
            Backend::Fmp => s.seconds[0],
            Backend::BlazePose => s.seconds[1],
            Backend::Auto => s.seconds.iter().sum(),
        };
        let fig = match decide(&restricted(s, backend), cal, options, None) {
            Ok(f) => Some(f),
            Err(Error::NoFigure { .. }) => None,
            Err(e) => return Err(e),
        };
        none += usize::from(fig.is_none());
        if let Some(f) = &fig {
            answered += 1;
            match f.backend {
                Backend::Fmp => chosen[0] += 1,
                Backend::BlazePose => chosen[1] += 1,
                Backend::Auto => chosen[2] += 1,
            }
        }
        if let Some(t) = &s.truth {
            with += 1;
            match &fig {
                Some(f) => {
                    p1 += pck(t, &f.joints.xy, 0.1)?;
                    p2 += pck(t, &f.joints.xy, 0.2)?;
                    gross += usize::from(correct(t, &f.joints.xy).iter().filter(|&&c| !c).count() >= GROSS_JOINTS);
                    swaps += usize::from(is_swap(t, &f.joints));
                }
                None => gross += 1,
            }
        }
        if let (Some(yaw), Some(f)) = (s.yaw_deg, &fig) {
            with_yaw += 1;
            let k = if f.facing.facing == Facing::of_yaw(yaw) {
                0
            } else if f.facing.facing == Facing::Unknown {
                1
            } else {
                2
            };
            facing[k] += 1;
        }
    }
    let n = samples.len().max(1) as f64;
    let a = answered.max(1) as f64;
    Ok(SetScore {
        n: samples.len(),
        pck: if with == 0 { [f64::NAN; 2] } else { [p1 / with as f64, p2 / with as f64] },
        no_figure: none as f64 / n,
        seconds: secs / n,
        chosen: chosen.map(|c| c as f64 / a),
        gross: if with == 0 { f64::NAN } else { gross as f64 / with as f64 },
        swaps: if with == 0 { f64::NAN } else { swaps as f64 / with as f64 },
        facing: facing.map(|c| if with_yaw == 0 { f64::NAN } else { c as f64 / with_yaw as f64 }),
    })
}

/// The reliability table of the figure confidence of `options`' backend on the images with a figure: `bins`
/// equal bins of [0, 1], each with its mean confidence and observed PCK@0.2. Errors: as
/// [`score_set`].
pub fn reliability(
    samples: &[Sample],
    cal: &Calibration,
    options: &FigureOptions,
    bins: usize,
) -> Result<Vec<ReliabilityBin>> {
    let bins = bins.max(1);
    let backend = options.backend;
    let mut acc = vec![(0usize, 0.0, 0.0); bins];
    for s in samples {
        let Some(t) = &s.truth else { continue };
        let f = match decide(&restricted(s, backend), cal, options, None) {
            Ok(f) => f,
            Err(Error::NoFigure { .. }) => continue,
            Err(e) => return Err(e),
        };
        let k = ((f.confidence * bins as f64) as usize).min(bins - 1);
        acc[k].0 += 1;
        acc[k].1 += f.confidence;
        acc[k].2 += pck(t, &f.joints.xy, 0.2)?;
    }
    Ok(acc
        .iter()
        .enumerate()
        .map(|(k, &(n, c, o))| ReliabilityBin {
            lo: k as f64 / bins as f64,
            hi: (k + 1) as f64 / bins as f64,
            n,
            mean_confidence: if n == 0 { f64::NAN } else { c / n as f64 },
            observed: if n == 0 { f64::NAN } else { o / n as f64 },
        })
        .collect())
}

/// Expected calibration error of a reliability table: the bins' |confidence − observed|
/// weighted by their counts.
pub fn expected_calibration_error(table: &[ReliabilityBin]) -> f64 {
    let n: usize = table.iter().map(|b| b.n).sum();
    if n == 0 {
        return f64::NAN;
    }
    table.iter().filter(|b| b.n > 0).map(|b| b.n as f64 * (b.mean_confidence - b.observed).abs()).sum::<f64>()
        / n as f64
}

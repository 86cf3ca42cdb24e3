//! The main job end to end (paper Fig. 1): sketch → Canny edges → 2-D joints → 3-D pose and
//! camera ([`crate::pose::estimate_pose`]) → shape fit ([`crate::fit::fit_shape`]) → a rigged
//! rest mesh posed to the estimate. [`run_pipeline`] does it in memory; the CLI's `run` writes
//! the files.
//!
//! - [`joints`]: the 2-D joints source (the caller's joints, or the detector's).
//! - [`figure`]: the single-figure detector refereed by the pose step.
//! - [`overlay`]: the overlay picture (sketch, joints, bones, fitted silhouette outline).
//! - [`repose`]: re-posing a finished result (a depth reading, a flipped limb, moved joints) without re-fitting its shape.
//!
//! Gender: given a gender ([`PipelineOptions::gender`]), that gender's space is fitted. Without
//! one, with given joints the default fits both gendered spaces and a classifier chooses
//! ([`PipelineOptions::classify_gender`]); with detected joints it fits the space the
//! detected-joints gender classifier picks ([`DetectedJointsFit::classifier_gender`]). With
//! both switched off the both-sexes space is fitted ([`crate::body::BlendedSpace`]: gender is a
//! continuous shape weight, 0 female … 1 male, fitted with the others) and the result reports
//! the fitted gender value and the posterior probability of its half.

pub mod body_fit;
mod detected;
pub mod figure;
pub mod interim;
pub mod joints;
pub mod overlay;
pub mod repose;
pub mod shape_keys;
pub mod views;

use std::time::Instant;

use crate::body::ik::Pose;
use crate::body::rig::RiggedMesh;
use crate::body::{BodyModel, Gender, ShapeChoice};
use crate::error::{Error, Result};
use crate::fit::{
    gender_evidence, FitCalibration, FitOptions, GenderClassifier, GenderEvidence, MarginCombination, PartSupport,
};
use crate::image::{canny, CannyParams, GrayImage};
use crate::pose::views::{side_facing, triangulate, view_pose_for};
use crate::pose::{estimate_pose_hinted, Dictionary, PoseEstimate, PoseOptions};
use crate::skeleton::Joints2;

pub use body_fit::{
    calibrated_weights, fit_body, fit_body_views, refit_camera, rest_body, BodyChoice, BodyView, FittedBody, GenderFit,
};
pub use detected::{DetectedJointsFit, DEFAULT_DEPTH_HINT};
pub use interim::{InterimBody, InterimStage};
pub use joints::{DetectedJoints, FigureJoints, GivenJoints, JointsSource};
pub use repose::{repose, Posing, ReposeOutcome, ReposeRequest};
pub use views::{ViewInput, ViewResult};

/// Smallest accepted sketch side, pixels (smaller sketches give [`Error::ImageTooSmall`]).
pub const MIN_SKETCH_SIDE: usize = 32;

/// Options of [`run_pipeline`]. `Default` gives the library defaults of every stage and
/// automatic gender.
#[derive(Clone, Debug, PartialEq)]
pub struct PipelineOptions {
    /// Edge detector settings (default: 50/150, aperture 3, L1).
    pub canny: CannyParams,
    /// 3-D pose solver options.
    pub pose: PoseOptions,
    /// Shape-fit options (samples, iterations, score, seed, skinning, ...).
    pub fit: FitOptions,
    /// The shape space to fit: a gender's, or with `None` (the default) automatic: a classifier's
    /// choice of gendered space, or the both-sexes space with gender as a fitted continuous
    /// weight when the classifiers are switched off (module doc).
    pub gender: Option<Gender>,
    /// Skip the fit and use the gender's mean shape, posed the same way (the baseline of the
    /// benchmark). Needs `gender`.
    pub mean_shape: bool,
    /// Keep the pose solver's camera (fitted to a 1.75 m person of the dictionary's proportions)
    /// instead of refitting its scales and translation to each gender's mean skeleton (see
    /// [`refit_camera`]). Default `false` (refit).
    pub keep_pose_scale: bool,
    /// Skip the pose solver and use this 3-D pose and camera (a diagnostic: the benchmark's
    /// `--oracle-pose` passes the ground truth to show what the fit reaches when the pose is
    /// right). Default `None` (estimate the pose).
    pub given_pose: Option<PoseEstimate>,
    /// Weight of the landmark network's relative joint depths in the pose step's choices
    /// ([`crate::pose::DepthHint::weight`]; px² of depth residual per px² of reprojection), used
    /// when the joints come from the single-figure detector and BlazePose agrees with them
    /// ([`crate::detect::figure::Figure::landmark_depth`]); 0 = off. It replaces the pose
    /// step's learned depths ([`crate::pose::PoseOptions::depth_prior`], which given joints and
    /// joints without BlazePose's depths get). Default [`DEFAULT_DEPTH_HINT`].
    pub depth_hint: f64,
    /// How the shape fit treats joints that came from the detector rather than from the user
    /// (a detector's joints are a few percent of the figure off, enough to skew the bone
    /// lengths the fit would read proportions from). Given joints use `fit` as is.
    pub detected: DetectedJointsFit,
    /// With automatic gender, set the both-sexes fit's prior mass on the male end
    /// ([`FitOptions::male_prior`]) to the gender classifier's probability
    /// ([`crate::fit::GenderClassifier::SHIPPED`], or `SHIPPED_DETECTED` for detected joints, on
    /// the sketch's joints and outline, [`crate::fit::gender_evidence`]) instead of 0.5. Ignored when `fit.male_prior` is set,
    /// a gender is given, the joints were detected or [`PipelineOptions::classify_gender`]
    /// applies. Default `true`.
    pub gender_evidence: bool,
    /// With automatic gender and given (not detected) joints, fit both gendered spaces instead
    /// of the both-sexes space and keep the one [`MarginCombination::SHIPPED`] chooses from the
    /// gender classifier's log-odds and the two fits' score margin; the result's confidence is
    /// then that combination's probability of the chosen gender. With detected joints the
    /// margin misleads and [`DetectedJointsFit::classifier_gender`] applies instead. Default
    /// `true`.
    pub classify_gender: bool,
    /// PCA dimensions of the two gendered fits whose score margin decides the gender under
    /// [`PipelineOptions::classify_gender`] (`None`: each space's 96%-energy dimension, 4 in
    /// the shipped model, which [`MarginCombination::SHIPPED`] was trained on). When
    /// `fit.dims` searches other dimensions, the chosen gender is fitted once more with them
    /// (a third fit): fits of every dimension the prior covers follow the sketch more closely
    /// but tell the genders apart less well.
    pub gender_decision_dims: Option<usize>,
    /// Pairs of deciding fits under [`PipelineOptions::classify_gender`], with fit seeds
    /// `fit.seed`, `fit.seed + 1`, …: their score margins are averaged (a best score is a noisy
    /// maximum over the samples, and the margin of one pair flips the gender of a few sketches
    /// between seeds). Each further pair adds two fits to `run`'s time. Default 1 (the choice:
    /// docs/benchmarks-history.md, "Two deciding seeds"). In 1..=16.
    pub gender_decision_seeds: usize,
    /// Samples per iteration of each deciding fit under [`PipelineOptions::classify_gender`]
    /// (`None`: the fit's [`FitOptions::samples`]). Only the score margin is read from them, so
    /// they may be cheaper than the fit of the chosen gender. In 2..=100000.
    pub gender_decision_samples: Option<usize>,
    /// Most SIR iterations of each deciding fit under [`PipelineOptions::classify_gender`], at
    /// most the fit's [`FitOptions::max_iterations`] (`None`: the fit's). A deciding fit's best
    /// score has settled enough to choose the gender after 5 of 8 iterations, which
    /// [`MarginCombination::SHIPPED`] was trained on (docs/benchmarks-history.md, "Five-iteration
    /// deciding fits"). Default `Some(5)`. In 1..=1000.
    pub gender_decision_iterations: Option<usize>,
    /// When the character's height is unknown (`fit.height` is `None`) and the 2-D joints are
    /// given, calibrate the fitted body with [`FitCalibration::SHIPPED`]: map a gendered fit's
    /// shape weights, then scale the rest body to the calibrated height. The fit alone draws
    /// the body toward the prior's mean (docs/benchmarks.md, "Shape calibration", "Height
    /// calibration"). Not applied to detected joints nor to the mean shape. Default `true`.
    pub calibrate_fit: bool,
}

impl Default for PipelineOptions {
    fn default() -> Self {
        Self {
            canny: CannyParams::default(),
            pose: PoseOptions::default(),
            fit: FitOptions::default(),
            gender: None,
            mean_shape: false,
            keep_pose_scale: false,
            given_pose: None,
            depth_hint: DEFAULT_DEPTH_HINT,
            detected: DetectedJointsFit::default(),
            gender_evidence: true,
            classify_gender: true,
            gender_decision_dims: None,
            gender_decision_seeds: 1,
            gender_decision_samples: None,
            gender_decision_iterations: Some(5),
            calibrate_fit: true,
        }
    }
}

/// Wall-clock seconds of each stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// Canny edges.
    pub edges: f64,
    /// 2-D joints.
    pub joints: f64,
    /// 3-D pose and camera.
    pub pose: f64,
    /// Every shape fit together.
    pub fit: f64,
    /// Posing the chosen shape (IK and skinning).
    pub posing: f64,
    /// The whole call.
    pub total: f64,
}

/// Everything [`run_pipeline`] produces. Owns its data.
#[derive(Clone, Debug)]
pub struct PipelineResult {
    /// The sketch's Canny edge map (255 edge, 0 not).
    pub edges: GrayImage,
    /// The 2-D joints used, pixels.
    pub joints2d: Joints2,
    /// Name of the joints source ([`JointsSource::name`]).
    pub joints_source: String,
    /// The single-figure detection behind the joints (backend, calibrated confidences, the
    /// low-confidence flag), when the source is [`FigureJoints`].
    pub detection: Option<crate::detect::figure::Figure>,
    /// 3-D joints (metres of a 1.75 m person, model frame) and camera (pixels) used for the
    /// chosen gender: the camera refitted to that gender's mean skeleton (scaled to
    /// `fit.height` when given; unless `keep_pose_scale`), and with `fit.sample_camera` then to
    /// the chosen body's own skeleton.
    pub pose: PoseEstimate,
    /// The fits: one (the given gender's space, or the blended one), or with
    /// [`PipelineOptions::classify_gender`] both gendered ones (female first) per deciding seed
    /// ([`PipelineOptions::gender_decision_seeds`]), followed by the
    /// chosen gender's refit when [`PipelineOptions::gender_decision_dims`] differs from the
    /// fit's dimensions, the fit's [`FitOptions::initial_factor`] is not 1 (the deciding fits
    /// use a flat population) or [`PipelineOptions::gender_decision_samples`] or
    /// [`PipelineOptions::gender_decision_iterations`] differs from the fit's samples or
    /// iterations. The result's fit is [`PipelineResult::chosen_fit`].
    pub fits: Vec<GenderFit>,
    /// The space of the result (the chosen fit's).
    pub space: ShapeChoice,
    /// The chosen gender.
    pub gender: Gender,
    /// Gender value, 0 = female mean … 1 = male mean ([`FittedBody::gender_value`]; 0 or 1 when a
    /// gendered space was fitted).
    pub gender_value: f64,
    /// Probability that [`PipelineResult::gender`] is right: 1 when given; with
    /// [`PipelineOptions::classify_gender`] the [`MarginCombination`]'s; with detected joints and
    /// [`DetectedJointsFit::classifier_gender`] the detected-joints classifier's; else the blended
    /// fit's posterior mass of that half ([`FittedBody::gender_confidence`]).
    pub gender_confidence: f64,
    /// `true` when the gender was fitted, `false` when the caller gave it.
    pub gender_fitted: bool,
    /// The sketch's geometric gender evidence and the classifier's probability (measured
    /// whether or not it was used; see [`PipelineOptions::gender_evidence`]).
    pub gender_evidence: GenderEvidence,
    /// The prior mass on the male end the both-sexes fit used (`None` when a gendered space was
    /// fitted or the mean shape was used; 0.5 without the classifier).
    pub male_prior: Option<f64>,
    /// Fraction of the fitted outline the sketch supports ([`FittedBody::edge_support`]).
    pub edge_support: f64,
    /// The fit is low-evidence ([`FittedBody::low_evidence`]).
    pub low_evidence: bool,
    /// Per body part, the share of the fitted outline the sketch supports
    /// ([`FittedBody::part_support`]; `None` for the mean shape).
    pub part_support: Option<PartSupport>,
    /// PCA weights of the chosen body ([`FittedBody::weights`]: Y* of the SIR, mapped when
    /// [`PipelineResult::calibrated`]; empty for the mean shape), metres.
    pub weights: Vec<f64>,
    /// Best match score of the chosen fit (NaN for the mean shape).
    pub score: f64,
    /// The rest mesh with its joints, UVs and skin weights.
    pub mesh: RiggedMesh,
    /// Height of the fitted rest body before it was scaled to a given or calibrated height,
    /// metres ([`FittedBody::fit_height`]; for the mean shape, its own height).
    pub fit_height: f64,
    /// `true` when the fitted body was calibrated ([`PipelineOptions::calibrate_fit`],
    /// [`FittedBody::calibrated`]).
    pub calibrated: bool,
    /// The IK pose taking `mesh.joints` to the estimated 3-D joints.
    pub ik_pose: Pose,
    /// The posed vertices (model frame, metres); project with `pose.camera`.
    pub posed_vertices: Vec<[f32; 3]>,
    /// Posed joints of the mesh (model frame, metres).
    pub posed_joints: crate::skeleton::Joints3,
    /// The options of the pose and posing steps, for [`repose`].
    pub posing_options: Posing,
    /// Stage timings.
    pub timings: Timings,
    /// A turnaround's extra views, in the order given ([`run_pipeline_views`]; empty for one
    /// view).
    pub views: Vec<ViewResult>,
    /// What the run warns about its views (they agree only roughly, different scales, an
    /// outline little supported); empty for one view.
    pub view_warnings: Vec<String>,
}

impl PipelineResult {
    /// The fit behind the result: the last of [`PipelineResult::fits`] in the result's space
    /// (`None` only for a result built without fits).
    pub fn chosen_fit(&self) -> Option<&GenderFit> {
        self.fits.iter().rev().find(|g| g.space == self.space)
    }
}

/// Maps a stage's progress to the whole run's and forwards it; `false` from the caller cancels.
struct Progress<'a> {
    callback: &'a mut dyn FnMut(f32) -> bool,
}

impl Progress<'_> {
    fn report(&mut self, fraction: f32) -> Result<()> {
        if (self.callback)(fraction.clamp(0.0, 1.0)) {
            Ok(())
        } else {
            Err(Error::Cancelled)
        }
    }
}

/// Runs the pipeline on a gray sketch (0 ink … 255 paper). `progress(fraction)` is called from
/// the calling thread after each stage and each fit iteration with the fraction of the whole
/// run done (0..=1, non-decreasing); returning `false` stops with [`Error::Cancelled`] within
/// one fit iteration.
///
/// Errors: a side below [`MIN_SKETCH_SIDE`] ([`Error::ImageTooSmall`]); no edges
/// ([`Error::BlankImage`]); the joints source's error ([`Error::NoFigure`] for
/// [`DetectedJoints`] on a sketch without a figure); a visible joint non-finite or outside the image
/// ([`Error::NonFinite`], [`Error::JointOutsideImage`]); the pose solver's and the fit's
/// errors; `mean_shape` without a gender, a `depth_hint` weight that is not finite and ≥ 0 or a
/// `detected.joint_weight_scale` outside 0..=1 ([`Error::OutOfRange`]).
pub fn run_pipeline(
    model: &BodyModel,
    dict: &Dictionary,
    sketch: &GrayImage,
    source: &dyn JointsSource,
    options: &PipelineOptions,
    progress: &mut dyn FnMut(f32) -> bool,
) -> Result<PipelineResult> {
    run_pipeline_views(model, dict, sketch, source, &[], options, progress, None)
}

/// [`run_pipeline`] that also hands `interim` (called from the calling thread) the bodies it has
/// before the final one: [`InterimStage::MeanShape`] right after the pose step (the mean shape
/// of the expected gender in the estimated pose; a few ms of posing), then, when the gender is
/// decided by fitting, [`InterimStage::DecidingFit`] before the final fit. With `interim` `None`
/// the run is [`run_pipeline`]'s; with it the result is the same. Errors: [`run_pipeline`]'s and
/// the interim body's posing errors.
pub fn run_pipeline_progressive(
    model: &BodyModel,
    dict: &Dictionary,
    sketch: &GrayImage,
    source: &dyn JointsSource,
    options: &PipelineOptions,
    progress: &mut dyn FnMut(f32) -> bool,
    interim: Option<&mut dyn FnMut(&InterimBody)>,
) -> Result<PipelineResult> {
    run_pipeline_views(model, dict, sketch, source, &[], options, progress, interim)
}

/// [`run_pipeline_progressive`] on a turnaround: `sketch` is the front view, `views` the same
/// character in the same pose from the side or the back (module [`views`]). Every view's joints
/// enter the 3-D pose ([`crate::pose::views::triangulate`]; with [`PipelineOptions::given_pose`]
/// only the views' cameras are fitted to it) and every view's outline the shape fit
/// ([`fit_body_views`]). The result's [`PipelineResult::views`] hold each view's joints, edges
/// and camera; [`PipelineResult::view_warnings`] what the run warns about them. With no views
/// this is [`run_pipeline_progressive`]. The interim bodies are the front view's.
///
/// Errors: [`run_pipeline`]'s, for every view's sketch and joints too; a front or repeated view
/// label ([`Error::OutOfRange`] `view label`); views whose joints disagree beyond
/// [`views::VIEWS_REFUSE`], or only upside down, or a side view whose depth comes out mirrored
/// (drawn facing the other way than its label: [`crate::pose::views::SideFacing::mirrored`])
/// ([`Error::ViewsDisagree`]); a view's joints with fewer than two
/// visible or no height ([`Error::Degenerate`]).
#[allow(clippy::too_many_arguments)]
pub fn run_pipeline_views(
    model: &BodyModel,
    dict: &Dictionary,
    sketch: &GrayImage,
    source: &dyn JointsSource,
    views: &[ViewInput],
    options: &PipelineOptions,
    progress: &mut dyn FnMut(f32) -> bool,
    mut interim: Option<&mut dyn FnMut(&InterimBody)>,
) -> Result<PipelineResult> {
    let t0 = Instant::now();
    let mut p = Progress { callback: progress };
    let mut timings = Timings::default();
    if !(options.depth_hint.is_finite() && options.depth_hint >= 0.0) {
        return Err(Error::OutOfRange {
            name: "depth_hint",
            detail: format!("{} is not a finite weight ≥ 0", options.depth_hint),
        });
    }
    let detected_fit = options.detected.apply(&options.fit)?;
    let (w, h) = (sketch.width(), sketch.height());
    if w < MIN_SKETCH_SIDE || h < MIN_SKETCH_SIDE {
        return Err(Error::ImageTooSmall { width: w, height: h, min: MIN_SKETCH_SIDE });
    }
    p.report(0.0)?;
    let t = Instant::now();
    let edges = canny(&sketch.view(), &options.canny)?;
    if edges.as_bytes().iter().all(|&e| e == 0) {
        let (a, b) = (options.canny.threshold1, options.canny.threshold2);
        return Err(Error::BlankImage { width: w, height: h, low: a.min(b), high: a.max(b) });
    }
    timings.edges = t.elapsed().as_secs_f64();
    p.report(0.02)?;

    let t = Instant::now();
    let (joints2d, detection) = source.figure(sketch, &edges, dict)?;
    joints::check_in_image(&joints2d, w, h)?;
    let mut prepared = views::prepare(views, &options.canny, dict)?;
    timings.joints = t.elapsed().as_secs_f64();
    p.report(0.04)?;

    let t = Instant::now();
    let pose = match &options.given_pose {
        Some(given) => given.clone(),
        None => {
            let (pose_joints, hint) = match &detection {
                Some(f) => detected::pose_input(f, &joints2d, options.depth_hint, &options.detected),
                None => (joints2d, None),
            };
            estimate_pose_hinted(dict, &pose_joints, &options.pose, hint.as_ref())?
        }
    };
    let (pose, views_pose, view_warnings) = if prepared.is_empty() {
        (pose, None, Vec::new())
    } else {
        match &options.given_pose {
            Some(_) => views::choose_labelling(&mut prepared, |vj| view_pose_for(&pose, &joints2d, vj)),
            None => views::choose_labelling(&mut prepared, |vj| triangulate(&pose, &joints2d, vj)),
        }
        let vj = views::view_joints(&prepared);
        let (vp, facing) = match &options.given_pose {
            Some(_) => (view_pose_for(&pose, &joints2d, &vj)?, vec![None; vj.len()]),
            None => {
                let vp = triangulate(&pose, &joints2d, &vj)?;
                let facing = side_facing(&pose, &joints2d, &vj, &vp)?;
                (vp, facing)
            }
        };
        let warnings = views::agreement(&prepared, &vp, &facing)?;
        // The views measure depth: the front estimate's depth readings do not apply to it.
        let joints = vp.joints;
        (PoseEstimate { joints, alternatives: Vec::new(), depth_costs: None, ..pose }, Some((vp, facing)), warnings)
    };
    let body_views: Vec<BodyView> = prepared
        .iter()
        .zip(views_pose.iter().flat_map(|(vp, _)| &vp.cameras))
        .map(|(v, camera)| BodyView { camera, edges: &v.edges, joints2d: &v.joints2d })
        .collect();
    timings.pose = t.elapsed().as_secs_f64();
    p.report(0.06)?;

    let mut fit = if detection.is_some() { detected_fit } else { options.fit.clone() };
    let classifier = if detection.is_some() { GenderClassifier::SHIPPED_DETECTED } else { GenderClassifier::SHIPPED };
    let evidence = gender_evidence(&joints2d, &edges, &pose.joints, &pose.camera, &classifier)?;
    // The score margin decides well only with the user's joints; with detected joints the
    // classifier's prior measured worse than none (docs/benchmarks-history.md, "The fully
    // automatic path, as a user meets it").
    let classify = options.gender.is_none() && options.classify_gender && !options.mean_shape && detection.is_none();
    if options.gender.is_none()
        && !classify
        && options.gender_evidence
        && detection.is_none()
        && fit.male_prior.is_none()
    {
        fit.male_prior = Some(evidence.male_probability);
    }
    // With detected joints the both-sexes fit's gender is no better than chance; the
    // detected-joints classifier picks the gendered space instead.
    let detected_gender = match (&detection, options.gender) {
        (Some(_), None) if !options.mean_shape => options.detected.gender(evidence.male_probability),
        _ => None,
    };
    let male_prior =
        (options.gender.is_none() && !classify && detected_gender.is_none()).then(|| fit.male_prior.unwrap_or(0.5));
    // Detected joints keep the fitted body (a height calibration measured worse there).
    let calibration = (options.calibrate_fit && detection.is_none()).then_some(FitCalibration::SHIPPED);
    let choice = BodyChoice {
        gender: options.gender.or(detected_gender),
        mean_shape: options.mean_shape,
        keep_pose_scale: options.keep_pose_scale,
        calibration,
        widths: Some(evidence.features),
    };
    if let Some(show) = interim.as_deref_mut() {
        let gender =
            choice.gender.unwrap_or(if evidence.male_probability > 0.5 { Gender::Male } else { Gender::Female });
        let mean = BodyChoice { gender: Some(gender), mean_shape: true, ..choice };
        let body = fit_body(model, &pose.joints, &pose.camera, &edges, Some(&joints2d), &fit, &mean, &mut |_| true)?;
        show(&interim_of(&body, InterimStage::MeanShape)?);
    }
    let (body, classified) = if classify {
        let mut cb = |f: f32| (p.callback)((0.06 + 0.9 * f).clamp(0.0, 1.0));
        let sketch = SketchInputs { pose: &pose, edges: &edges, joints2d: &joints2d, views: &body_views };
        let log_odds = classifier.log_odds(&evidence.features);
        let decision = Decision {
            dims: options.gender_decision_dims,
            seeds: options.gender_decision_seeds,
            samples: options.gender_decision_samples,
            iterations: options.gender_decision_iterations,
        };
        let (body, male) = classify_and_fit(model, &sketch, &fit, &choice, decision, log_odds, &mut cb, interim)?;
        (body, Some(male.max(1.0 - male)))
    } else {
        let mut cb = |f: f32| (p.callback)((0.06 + 0.9 * f).clamp(0.0, 1.0));
        let (j, c) = (&pose.joints, &pose.camera);
        let body = fit_body_views(model, j, c, &edges, Some(&joints2d), &body_views, &fit, &choice, &mut cb)?;
        let male = evidence.male_probability;
        (body, detected_gender.map(|_| male.max(1.0 - male)))
    };
    timings.fit = body.fit_seconds;
    timings.posing = body.posing_seconds;
    let mesh = RiggedMesh::from_rest(model, &body.rest);
    let view_support = body.fits.iter().rev().find(|g| g.space == body.space).and_then(|g| g.fit.as_ref());
    let mut view_warnings = view_warnings;
    let view_results: Vec<ViewResult> = prepared
        .into_iter()
        .enumerate()
        .map(|(k, v)| {
            let (vp, facing) = views_pose.as_ref().expect("views have a pose");
            let support = view_support.and_then(|f| f.view_support.get(k).copied()).unwrap_or(f64::NAN);
            if support < crate::fit::LOW_EVIDENCE_SUPPORT {
                view_warnings.push(format!(
                    "the {} view's strokes support only {:.0}% of the fitted outline in that view",
                    v.label.name(),
                    100.0 * support
                ));
            }
            ViewResult {
                label: v.label,
                edges: v.edges,
                joints2d: v.joints2d,
                joints_source: v.joints_source,
                camera: body.view_cameras[k],
                residual: vp.residual[k + 1],
                scale_ratio: vp.scale_ratio[k],
                facing: facing[k],
                edge_support: support,
                swapped: v.swapped,
            }
        })
        .collect();
    timings.total = t0.elapsed().as_secs_f64();
    p.report(1.0)?;
    Ok(PipelineResult {
        edges,
        joints2d,
        joints_source: source.name().to_string(),
        detection,
        pose: PoseEstimate { camera: body.camera, ..pose },
        fits: body.fits,
        space: body.space,
        gender: body.gender,
        gender_value: body.gender_value,
        gender_confidence: classified.unwrap_or(body.gender_confidence),
        gender_fitted: options.gender.is_none(),
        gender_evidence: evidence,
        male_prior,
        edge_support: body.edge_support,
        low_evidence: body.low_evidence,
        part_support: body.part_support,
        weights: body.weights,
        score: body.score,
        mesh,
        posed_joints: body.ik_pose.joints,
        fit_height: body.fit_height,
        calibrated: body.calibrated,
        ik_pose: body.ik_pose,
        posed_vertices: body.posed_vertices,
        posing_options: Posing { pose: options.pose, retarget: fit.retarget, skinning: fit.skinning },
        timings,
        views: view_results,
        view_warnings,
    })
}

/// The interim view of a fitted `body` at `stage`.
fn interim_of(body: &FittedBody, stage: InterimStage) -> Result<InterimBody<'_>> {
    Ok(InterimBody {
        stage,
        gender: body.gender,
        rest: &body.rest,
        shape: shape_keys::ShapeOrigin::of_fit(body)?,
        pose: &body.ik_pose,
        posed_vertices: &body.posed_vertices,
        camera: &body.camera,
    })
}

/// What the gender decision's fits read of the sketch: the estimated pose and camera, the
/// edge map and the 2-D joints.
struct SketchInputs<'a> {
    pose: &'a PoseEstimate,
    edges: &'a GrayImage,
    joints2d: &'a Joints2,
    /// A turnaround's extra views (empty for one view).
    views: &'a [BodyView<'a>],
}

/// How [`classify_and_fit`] decides: the deciding fits' dimensions
/// ([`PipelineOptions::gender_decision_dims`]) and seeds ([`PipelineOptions::gender_decision_seeds`]).
#[derive(Clone, Copy)]
struct Decision {
    dims: Option<usize>,
    seeds: usize,
    /// [`PipelineOptions::gender_decision_samples`].
    samples: Option<usize>,
    /// [`PipelineOptions::gender_decision_iterations`].
    iterations: Option<usize>,
}

/// [`PipelineOptions::classify_gender`]: both gendered fits in the decision's dimensions
/// (`decision.dims`, `None` = each space's default; a flat population,
/// [`FitOptions::initial_factor`] 1, as the combination was trained with) for each of
/// `decision.seeds` fit seeds, the [`MarginCombination::SHIPPED`] of the classifier's `log_odds`
/// and their mean score margin choosing, then the chosen gender refitted with `fit` when that
/// searches other dimensions or another population schedule (else the last seed's fit is the
/// body). Returns the chosen body (its `fits`: the deciding fits, female then male per seed,
/// then the refit if any; `fit_seconds` their sum) and P(male). `progress` sees 0..=1 over all
/// the fits; `interim` gets the chosen gender's deciding body before a refit. Errors: `decision.seeds` outside 1..=16 ([`Error::OutOfRange`]) and the fits'.
fn classify_and_fit(
    model: &BodyModel,
    sketch: &SketchInputs,
    fit: &FitOptions,
    choice: &BodyChoice,
    decision: Decision,
    log_odds: f64,
    progress: &mut dyn FnMut(f32) -> bool,
    interim: Option<&mut dyn FnMut(&InterimBody)>,
) -> Result<(FittedBody, f64)> {
    if !(1..=16).contains(&decision.seeds) {
        return Err(Error::OutOfRange {
            name: "gender decision seeds",
            detail: format!("{} not in 1..=16", decision.seeds),
        });
    }
    let space = |g: Gender| model.shape_space(ShapeChoice::Gendered(g));
    let decision_dims = |g: Gender| -> Result<usize> { Ok(decision.dims.unwrap_or(space(g)?.default_dim())) };
    let decision_samples = decision.samples.unwrap_or(fit.samples);
    let decision_iterations = decision.iterations.map_or(fit.max_iterations, |n| n.min(fit.max_iterations));
    let refit = |g: Gender| -> Result<bool> {
        Ok(fit.initial_factor != 1
            || decision_samples != fit.samples
            || decision_iterations != fit.max_iterations
            || decision_dims(g)? != fit.dims.unwrap_or(space(g)?.gmm().dims()))
    };
    let deciding_fits = 2 * decision.seeds;
    let steps = deciding_fits as f32 + if refit(Gender::Female)? || refit(Gender::Male)? { 1.0 } else { 0.0 };
    let mut fit_one = |g: Gender, o: &FitOptions, step: f32| {
        let c = BodyChoice { gender: Some(g), ..*choice };
        let mut cb = |f: f32| progress((step + f) / steps);
        let (pose, camera, j2) = (&sketch.pose.joints, &sketch.pose.camera, Some(sketch.joints2d));
        fit_body_views(model, pose, camera, sketch.edges, j2, sketch.views, o, &c, &mut cb)
    };
    let mut bodies = Vec::with_capacity(deciding_fits);
    for k in 0..decision.seeds {
        for (i, g) in Gender::ALL.into_iter().enumerate() {
            let seed = fit.seed.wrapping_add(k as u64);
            let deciding = FitOptions {
                dims: Some(decision_dims(g)?),
                initial_factor: 1,
                samples: decision_samples,
                max_iterations: decision_iterations,
                seed,
                ..fit.clone()
            };
            bodies.push(fit_one(g, &deciding, (2 * k + i) as f32)?);
        }
    }
    let margin = bodies.chunks(2).map(|pair| pair[1].score - pair[0].score).sum::<f64>() / decision.seeds as f64;
    let male = MarginCombination::SHIPPED.male_probability(log_odds, margin);
    let mut seconds: f64 = bodies.iter().map(|b| b.fit_seconds).sum();
    let mut fits: Vec<GenderFit> = bodies.iter().flat_map(|b| b.fits.iter().cloned()).collect();
    let chosen = Gender::ALL[usize::from(male > 0.5)];
    // Without a refit the body is the last seed's fit (the last of its space in `fits`).
    let mut last_pair = bodies.split_off(deciding_fits - 2);
    let mut body = if refit(chosen)? {
        if let Some(show) = interim {
            show(&interim_of(&last_pair[chosen.index()], InterimStage::DecidingFit)?);
        }
        let body = fit_one(chosen, fit, deciding_fits as f32)?;
        fits.extend(body.fits.iter().cloned());
        seconds += body.fit_seconds;
        body
    } else {
        last_pair.swap_remove(chosen.index())
    };
    body.fits = fits;
    body.fit_seconds = seconds;
    Ok((body, male))
}

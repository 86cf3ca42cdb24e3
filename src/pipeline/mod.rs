//! The main job end to end (paper Fig. 1): sketch → Canny edges → 2-D joints → 3-D pose and
//! camera ([`crate::pose::estimate_pose`]) → shape fit ([`crate::fit::fit_shape`]) → a rigged
//! rest mesh posed to the estimate. [`run_pipeline`] does it in memory; the CLI's `run` writes
//! the files.
//!
//! - [`joints`]: the 2-D joints source (the caller's joints, or the detector's).
//! - [`overlay`]: the overlay picture (sketch, joints, bones, fitted silhouette outline).
//!
//! Gender: when [`PipelineOptions::gender`] is `None` the both-sexes space is fitted
//! ([`crate::body::BlendedSpace`]: gender is a continuous shape weight, 0 female … 1 male, fitted
//! with the others), so there is no hard gender choice to get wrong; the result reports the
//! fitted gender value and the posterior probability of its half. Given a gender, that gender's
//! space is fitted.

pub mod joints;
pub mod overlay;

use std::time::Instant;

use crate::body::ik::{self, IkOptions, Pose};
use crate::body::rig::RiggedMesh;
use crate::body::skin::skin;
use crate::body::{BodyModel, Gender, ShapeChoice};
use crate::error::{Error, Result};
use crate::fit::{fit_shape, FitOptions, FitProblem, FitResult};
use crate::image::{canny, CannyParams, GrayImage};
use crate::pose::{estimate_pose, Dictionary, PoseEstimate, PoseOptions};
use crate::skeleton::{Joints2, Joints3};

pub use joints::{DetectedJoints, GivenJoints, JointsSource};

/// Smallest accepted sketch side, pixels (smaller sketches give [`Error::ImageTooSmall`]).
pub const MIN_SKETCH_SIDE: usize = 32;

/// Options of [`run_pipeline`]. `Default` gives the library defaults of every stage and
/// automatic gender.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PipelineOptions {
    /// Edge detector settings (default: 50/150, aperture 3, L1).
    pub canny: CannyParams,
    /// 3-D pose solver options.
    pub pose: PoseOptions,
    /// Shape-fit options (samples, iterations, score, seed, skinning, ...).
    pub fit: FitOptions,
    /// The shape space to fit: a gender's, or with `None` (the default) the both-sexes space
    /// with gender as a fitted continuous weight.
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
}

/// The pose estimate with its camera refitted to a body's skeleton: the body's rest joints
/// `rest` are posed to the estimate's bone directions by IK (its own bone lengths), rotated by
/// the estimate's R, and `sx, tx` / `sy, ty` are the least-squares fit of their projections to
/// the visible 2-D joints. The pose solver reports a 1.75 m person of its dictionary's
/// proportions, and a single weak-perspective view cannot tell a small near figure from a large
/// far one; without this the shape fit spends shape weights on the solver's arbitrary scale.
/// Errors: IK's; [`Error::Degenerate`] when a scale comes out non-positive.
pub fn refit_camera(pose: &PoseEstimate, rest: &Joints3, joints2d: &Joints2) -> Result<PoseEstimate> {
    let posed = ik::solve(rest, &pose.joints, &IkOptions { retarget: false })?.joints;
    let targets: Vec<(usize, [f64; 2])> =
        (0..posed.len()).filter(|&k| joints2d.visible[k]).map(|k| (k, joints2d.xy[k])).collect();
    let camera = pose.camera.refit_scale(&posed, &targets)?;
    Ok(PoseEstimate { camera, ..pose.clone() })
}

/// The space's mean rest skeleton, scaled about its pelvis to `height` metres when given
/// ([`crate::fit::FitOptions::height`]).
fn mean_skeleton(model: &BodyModel, choice: ShapeChoice, height: Option<f64>) -> Result<Joints3> {
    let space = model.shape_space(choice)?;
    let mut joints = *space.mean_joints();
    if let Some(h) = height {
        crate::body::rig::scale_to_height(&mut space.mean().to_vec(), &mut joints, h)?;
    }
    Ok(joints)
}

/// One shape space's fit.
#[derive(Clone, Debug, PartialEq)]
pub struct GenderFit {
    /// The shape space fitted.
    pub space: ShapeChoice,
    /// The SIR's result (`None` for the mean shape).
    pub fit: Option<FitResult>,
    /// Best sample's match score (higher is better); NaN for the mean shape.
    pub score: f64,
    /// Wall-clock seconds of this fit.
    pub seconds: f64,
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
    /// 3-D joints (metres of a 1.75 m person, model frame) and camera (pixels) used for the
    /// chosen gender: the camera refitted to that gender's mean skeleton (scaled to
    /// `fit.height` when given; unless `keep_pose_scale`), and with `fit.sample_camera` then to
    /// the chosen body's own skeleton.
    pub pose: PoseEstimate,
    /// The fit (one: the given gender's space, or the blended one).
    pub fits: Vec<GenderFit>,
    /// The space fitted.
    pub space: ShapeChoice,
    /// The nearer gender: the given one, or for the blended space male when
    /// [`PipelineResult::gender_value`] > 0.5.
    pub gender: Gender,
    /// Gender value, 0 = female mean … 1 = male mean: 0 or 1 when given, else the fit's
    /// posterior mean ([`crate::fit::FitResult::gender_value`]).
    pub gender_value: f64,
    /// Probability that [`PipelineResult::gender`] is the right half (gender value on its side
    /// of 0.5) under the fit's posterior: 1 when the gender was given, 0.5..=1 when fitted.
    pub gender_confidence: f64,
    /// `true` when the gender was fitted, `false` when the caller gave it.
    pub gender_fitted: bool,
    /// PCA weights of the fitted shape in [`PipelineResult::space`] (Y* of the SIR; empty for
    /// the mean shape), metres; weight 0 of the blended space is its gender axis.
    pub weights: Vec<f64>,
    /// Fraction of the fitted silhouette's boundary the sketch's strokes support
    /// ([`crate::fit::FitResult::edge_support`]; NaN for the mean shape).
    pub edge_support: f64,
    /// The fit is low-evidence ([`crate::fit::FitResult::low_evidence`]): the body is mostly the
    /// prior's (e.g. a figure under a cloak to the ground). `false` for the mean shape.
    pub low_evidence: bool,
    /// Best match score of the chosen fit (NaN for the mean shape).
    pub score: f64,
    /// The rest mesh with its joints, UVs and skin weights.
    pub mesh: RiggedMesh,
    /// The IK pose taking `mesh.joints` to the estimated 3-D joints.
    pub ik_pose: Pose,
    /// The posed vertices (model frame, metres); project with `pose.camera`.
    pub posed_vertices: Vec<[f32; 3]>,
    /// Posed joints of the mesh (model frame, metres).
    pub posed_joints: crate::skeleton::Joints3,
    /// Stage timings.
    pub timings: Timings,
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
/// errors; `mean_shape` without a gender ([`Error::OutOfRange`]).
pub fn run_pipeline(
    model: &BodyModel,
    dict: &Dictionary,
    sketch: &GrayImage,
    source: &dyn JointsSource,
    options: &PipelineOptions,
    progress: &mut dyn FnMut(f32) -> bool,
) -> Result<PipelineResult> {
    let t0 = Instant::now();
    let mut p = Progress { callback: progress };
    let mut timings = Timings::default();
    let (w, h) = (sketch.width(), sketch.height());
    if w < MIN_SKETCH_SIDE || h < MIN_SKETCH_SIDE {
        return Err(Error::ImageTooSmall { width: w, height: h, min: MIN_SKETCH_SIDE });
    }
    if options.mean_shape && options.gender.is_none() {
        return Err(Error::OutOfRange {
            name: "gender",
            detail: "the mean-shape baseline needs a gender (nothing to choose by)".into(),
        });
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
    let joints2d = source.joints(sketch, &edges)?;
    joints::check_in_image(&joints2d, w, h)?;
    timings.joints = t.elapsed().as_secs_f64();
    p.report(0.04)?;

    let t = Instant::now();
    let pose = match &options.given_pose {
        Some(given) => given.clone(),
        None => estimate_pose(dict, &joints2d, &options.pose)?,
    };
    timings.pose = t.elapsed().as_secs_f64();
    p.report(0.06)?;

    let choice = options.gender.map_or(ShapeChoice::Blended, ShapeChoice::Gendered);
    let t = Instant::now();
    let pose = if options.keep_pose_scale {
        pose.clone()
    } else {
        refit_camera(&pose, &mean_skeleton(model, choice, options.fit.height)?, &joints2d)?
    };
    let fit = if options.mean_shape {
        GenderFit { space: choice, fit: None, score: f64::NAN, seconds: 0.0 }
    } else {
        let problem = FitProblem {
            model,
            gender: choice,
            pose: &pose.joints,
            camera: &pose.camera,
            edges: &edges,
            joints2d: Some(&joints2d),
        };
        let mut cb = |f: f32| (p.callback)((0.06 + 0.9 * f).clamp(0.0, 1.0));
        let fit = fit_shape(&problem, &options.fit, &mut cb)?;
        GenderFit { space: choice, score: fit.best_score, fit: Some(fit), seconds: t.elapsed().as_secs_f64() }
    };
    timings.fit = t.elapsed().as_secs_f64();
    let weights = fit.fit.as_ref().map_or_else(Vec::new, |f| f.weights.clone());
    let score = fit.score;
    let (gender, gender_value, gender_confidence) = match (options.gender, fit.fit.as_ref()) {
        (Some(g), _) => (g, g.index() as f64, 1.0),
        (None, Some(f)) => {
            let value = f.gender_value.unwrap_or(0.5);
            let male = f.male_probability.unwrap_or(0.5);
            if value > 0.5 {
                (Gender::Male, value, male.max(1.0 - male))
            } else {
                (Gender::Female, value, male.max(1.0 - male))
            }
        }
        (None, None) => {
            return Err(Error::OutOfRange { name: "gender", detail: "the mean-shape baseline needs a gender".into() })
        }
    };
    let (edge_support, low_evidence) =
        fit.fit.as_ref().map_or((f64::NAN, false), |f| (f.edge_support, f.low_evidence()));
    let fits = vec![fit];

    let t = Instant::now();
    let mut mesh = RiggedMesh::from_rest(model, &model.shape_space(choice)?.synthesize(&weights)?);
    if let Some(props) = fits[0].fit.as_ref().and_then(|f| f.proportions.as_ref()) {
        crate::fit::proportions::apply_in_place(&mut mesh.vertices, &mut mesh.joints, &mesh.weights, props)?;
    }
    if let Some(h) = options.fit.height {
        mesh = mesh.scaled_to_height(h)?;
    }
    // With per-sample cameras the chosen body's own skeleton sets the image scale.
    let pose = if options.fit.sample_camera && !options.mean_shape {
        refit_camera(&pose, &mesh.joints, &joints2d)?
    } else {
        pose
    };
    let ik_pose = ik::solve(&mesh.joints, &pose.joints, &IkOptions { retarget: options.fit.retarget })?;
    let posed_vertices = skin(&mesh.vertices, &mesh.weights, &ik_pose, options.fit.skinning)?;
    let posed_joints = ik_pose.joints;
    timings.posing = t.elapsed().as_secs_f64();
    timings.total = t0.elapsed().as_secs_f64();
    p.report(1.0)?;
    Ok(PipelineResult {
        edges,
        joints2d,
        joints_source: source.name().to_string(),
        pose,
        fits,
        space: choice,
        gender,
        gender_value,
        gender_confidence,
        gender_fitted: options.gender.is_none(),
        weights,
        edge_support,
        low_evidence,
        score,
        mesh,
        ik_pose,
        posed_vertices,
        posed_joints,
        timings,
    })
}

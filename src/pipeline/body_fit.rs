//! The shape stage in one place: fit the shape space the caller asks for (a gender's, or without
//! one the both-sexes space with gender as a continuous weight, [`crate::body::BlendedSpace`]),
//! apply its bone-length factors, scale it to the height, pose it by IK and skin it. [`super::run_pipeline`]
//! and the C API's `skb_context_fit_shape` both call [`fit_body`].

use std::time::Instant;

use crate::body::ik::{self, IkOptions, Pose};
use crate::body::proportions::Proportions;
use crate::body::skin::skin;
use crate::body::{BodyModel, Gender, RestShape, ShapeChoice};
use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::fit::{
    fit_shape, FitCalibration, FitOptions, FitProblem, FitResult, FitView, GenderFeatures, HeightEvidence, PartSupport,
    PRIOR_RANGE_SD,
};
use crate::image::GrayImage;
use crate::pose::PoseEstimate;
use crate::skeleton::{Joints2, Joints3};

/// The pose estimate with its camera refitted to a body's skeleton: the body's rest joints
/// `rest` are posed to the estimate's bone directions by IK (its own bone lengths), rotated by
/// the estimate's R, and `sx, tx` / `sy, ty` are the least-squares fit of their projections to
/// the visible 2-D joints. The pose solver reports a 1.75 m person of its dictionary's
/// proportions, and a single weak-perspective view cannot tell a small near figure from a large
/// far one; without this the shape fit spends shape weights on the solver's arbitrary scale.
/// Errors: IK's; [`Error::Degenerate`] when a scale comes out non-positive.
pub fn refit_camera(pose: &PoseEstimate, rest: &Joints3, joints2d: &Joints2) -> Result<PoseEstimate> {
    let camera = refit_scale(&pose.joints, &pose.camera, rest, joints2d)?;
    Ok(PoseEstimate { camera, ..pose.clone() })
}

/// [`refit_camera`] on a bare pose and camera: the refitted camera.
fn refit_scale(
    pose: &Joints3,
    camera: &WeakPerspective,
    rest: &Joints3,
    joints2d: &Joints2,
) -> Result<WeakPerspective> {
    let posed = ik::solve(rest, pose, &IkOptions { retarget: false })?.joints;
    let targets: Vec<(usize, [f64; 2])> =
        (0..posed.len()).filter(|&k| joints2d.visible[k]).map(|k| (k, joints2d.xy[k])).collect();
    camera.refit_scale(&posed, &targets)
}

/// The space's mean rest skeleton, scaled about its pelvis to `height` metres when given
/// ([`FitOptions::height`]).
fn mean_skeleton(model: &BodyModel, choice: ShapeChoice, height: Option<f64>) -> Result<Joints3> {
    let space = model.shape_space(choice)?;
    let mut joints = *space.mean_joints();
    if let Some(h) = height {
        crate::body::rig::scale_to_height(&mut space.mean().to_vec(), &mut joints, h)?;
    }
    Ok(joints)
}

/// The rest body of shape `weights` in `space` with the bone-length factors `proportions`
/// applied (model frame, metres), before any scaling to a height: what [`fit_body`] poses, and
/// what `sketchbody-lab calibrate-fit` measures. Errors: the space's and the factors' errors.
pub fn rest_body(
    model: &BodyModel,
    space: ShapeChoice,
    weights: &[f64],
    proportions: Option<&Proportions>,
) -> Result<RestShape> {
    let mut rest = model.shape_space(space)?.synthesize(weights)?;
    if let Some(props) = proportions {
        crate::fit::proportions::apply_in_place(&mut rest.vertices, &mut rest.joints, model.skin_weights(), props)?;
    }
    Ok(rest)
}

/// `weights` (a `gender` fit in `space`) mapped by `calibration`'s shape map and clamped to the
/// prior's [`PRIOR_RANGE_SD`] box; unchanged when the map does not apply (another number of
/// dimensions). Errors: a non-finite weight; the space's.
pub fn calibrated_weights(
    model: &BodyModel,
    space: ShapeChoice,
    calibration: &FitCalibration,
    gender: Gender,
    weights: Vec<f64>,
) -> Result<Vec<f64>> {
    let Some(mut mapped) = calibration.shape.apply(gender, &weights)? else { return Ok(weights) };
    let range = model.shape_space(space)?.gmm().marginal(mapped.len())?.range(PRIOR_RANGE_SD);
    for (w, (lo, hi)) in mapped.iter_mut().zip(range) {
        *w = w.clamp(lo, hi);
    }
    Ok(mapped)
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

/// Which shape space [`fit_body`] fits and how it treats the camera. `Default`: the both-sexes
/// space (gender fitted), camera refitted to the body.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyChoice {
    /// The shape space to fit: a gender's, or with `None` the both-sexes space with gender as a
    /// fitted continuous weight.
    pub gender: Option<Gender>,
    /// Skip the fit and use the gender's mean shape, posed the same way (the benchmark's
    /// baseline). Needs `gender`.
    pub mean_shape: bool,
    /// Keep the pose solver's camera (fitted to a 1.75 m person of the dictionary's
    /// proportions) instead of refitting its scales and translation to each body's skeleton
    /// ([`refit_camera`]; only done when the 2-D joints are given).
    pub keep_pose_scale: bool,
    /// When [`FitOptions::height`] is unknown, map a gendered fit's shape weights by this
    /// calibration's [`crate::fit::ShapeCalibration`] (clamped to the prior's
    /// [`PRIOR_RANGE_SD`] box) and scale the rest body about its pelvis to its
    /// [`crate::fit::HeightCalibration`]'s height (the both-sexes space: the height only);
    /// `None` (the default) keeps the fit's weights and height. Never applied to the mean shape.
    pub calibration: Option<FitCalibration>,
    /// The drawing's measured widths ([`crate::fit::gender_features`]), read by the height
    /// calibration with the fitted bone factors ([`crate::fit::HeightEvidence`]); `None` (the
    /// default) = not measured.
    pub widths: Option<GenderFeatures>,
}

/// What [`fit_body`] produces. Owns its data.
#[derive(Clone, Debug)]
pub struct FittedBody {
    /// The fit (one: the given gender's space, or the blended one).
    pub fits: Vec<GenderFit>,
    /// The space fitted.
    pub space: ShapeChoice,
    /// The nearer gender: the given one, or for the blended space male when
    /// [`FittedBody::gender_value`] > 0.5.
    pub gender: Gender,
    /// Gender value, 0 = female mean … 1 = male mean: 0 or 1 when given, else the fit's
    /// posterior mean ([`FitResult::gender_value`]).
    pub gender_value: f64,
    /// Probability under the fit's posterior that [`FittedBody::gender`] is the right half
    /// (the gender value on its side of 0.5): 1 when the gender was given, 0.5..=1 when fitted.
    pub gender_confidence: f64,
    /// PCA weights of the body in [`FittedBody::space`] (Y* of the SIR, mapped by the shape
    /// calibration when [`FittedBody::calibrated`]; empty for the mean shape), metres; weight 0
    /// of the blended space is its gender axis. The SIR's own Y* is in [`FittedBody::fits`].
    pub weights: Vec<f64>,
    /// Fraction of the fitted silhouette's boundary the sketch's strokes support
    /// ([`FitResult::edge_support`]; NaN for the mean shape).
    pub edge_support: f64,
    /// The fit is low-evidence ([`FitResult::low_evidence`]): the body is mostly the prior's
    /// (e.g. a figure under a cloak to the ground). `false` for the mean shape.
    pub low_evidence: bool,
    /// Per body part, the share of the fitted silhouette's outline the sketch's strokes support
    /// ([`FitResult::part_support`]); `None` for the mean shape.
    pub part_support: Option<PartSupport>,
    /// Best match score of the chosen fit (NaN for the mean shape).
    pub score: f64,
    /// The camera refitted to the chosen body (see [`BodyChoice::keep_pose_scale`] and
    /// [`FitOptions::sample_camera`]), pixels.
    pub camera: WeakPerspective,
    /// Each extra view's camera, refitted the same way ([`fit_body_views`]; empty for one
    /// view), pixels of that view.
    pub view_cameras: Vec<WeakPerspective>,
    /// The rest shape of [`FittedBody::weights`] with its bone-length factors applied and scaled
    /// to [`FitOptions::height`] when given, else to [`BodyChoice::calibration`]'s height when
    /// asked (model frame, metres).
    pub rest: RestShape,
    /// Height of the rest body of [`FittedBody::weights`] before any scaling to a given or
    /// calibrated height, metres ([`crate::body::rig::y_extent`] of its vertices).
    pub fit_height: f64,
    /// `true` when [`BodyChoice::calibration`] was applied (weights mapped for a gendered
    /// 10-dimension fit, height calibrated).
    pub calibrated: bool,
    /// The IK pose taking `rest.joints` to the estimated 3-D joints.
    pub ik_pose: Pose,
    /// The posed vertices (model frame, metres); project with `pose.camera`.
    pub posed_vertices: Vec<[f32; 3]>,
    /// Wall-clock seconds of every fit together.
    pub fit_seconds: f64,
    /// Wall-clock seconds of posing the chosen shape (IK and skinning).
    pub posing_seconds: f64,
}

/// One extra view of a turnaround for [`fit_body_views`]: its camera (its rotation turned from
/// the front's, [`crate::view::ViewLabel::camera_from_front`]), edge map and 2-D joints, image
/// pixels of that view.
#[derive(Clone, Copy)]
pub struct BodyView<'a> {
    /// The view's camera (image pixels).
    pub camera: &'a WeakPerspective,
    /// The view's edge map (255 edge, 0 not).
    pub edges: &'a GrayImage,
    /// The view's 2-D joints.
    pub joints2d: &'a Joints2,
}

/// Fits the body to `edges` (255 edge, 0 not) under the 3-D `pose` (canonical joints, metres)
/// seen through `camera`: the chosen shape space by SIR ([`fit_shape`]; without a gender the
/// both-sexes space, so no hard gender choice), then the calibration's shape map
/// ([`BodyChoice::calibration`]), bone-length factors, height (given, or calibrated), IK and
/// skinning. With `joints2d` the camera is refitted to each body's skeleton (and, with
/// [`FitOptions::sample_camera`], to the chosen body's) and the fit uses the joints term.
/// `progress(fraction)` (0..=1 over the fits, non-decreasing) returning `false` cancels.
///
/// Errors: `mean_shape` without a gender ([`Error::OutOfRange`]); the camera refit's, the fit's,
/// IK's and skinning's errors; [`Error::Cancelled`].
pub fn fit_body(
    model: &BodyModel,
    pose: &Joints3,
    camera: &WeakPerspective,
    edges: &GrayImage,
    joints2d: Option<&Joints2>,
    options: &FitOptions,
    choice: &BodyChoice,
    progress: &mut dyn FnMut(f32) -> bool,
) -> Result<FittedBody> {
    fit_body_views(model, pose, camera, edges, joints2d, &[], options, choice, progress)
}

/// [`fit_body`] of a turnaround: the front view (`camera`, `edges`, `joints2d`) and the extra
/// `views` of the same posed body. Each view's camera is refitted like the front's (to each
/// body's skeleton, and with [`FitOptions::sample_camera`] to the chosen body's); the fit scores
/// every view ([`crate::fit::FitProblem::views`]). The result's [`FittedBody::view_cameras`]
/// hold the views' final cameras, in order. Errors as [`fit_body`]'s.
#[allow(clippy::too_many_arguments)]
pub fn fit_body_views(
    model: &BodyModel,
    pose: &Joints3,
    camera: &WeakPerspective,
    edges: &GrayImage,
    joints2d: Option<&Joints2>,
    views: &[BodyView],
    options: &FitOptions,
    choice: &BodyChoice,
    progress: &mut dyn FnMut(f32) -> bool,
) -> Result<FittedBody> {
    if choice.mean_shape && choice.gender.is_none() {
        return Err(Error::OutOfRange {
            name: "gender",
            detail: "the mean-shape baseline needs a gender (nothing to choose by)".into(),
        });
    }
    let space = choice.gender.map_or(ShapeChoice::Blended, ShapeChoice::Gendered);
    let t = Instant::now();
    let camera = match joints2d {
        Some(j2) if !choice.keep_pose_scale => {
            refit_scale(pose, camera, &mean_skeleton(model, space, options.height)?, j2)?
        }
        _ => *camera,
    };
    let view_cameras: Vec<WeakPerspective> = views
        .iter()
        .map(|v| match choice.keep_pose_scale {
            true => Ok(*v.camera),
            false => refit_scale(pose, v.camera, &mean_skeleton(model, space, options.height)?, v.joints2d),
        })
        .collect::<Result<_>>()?;
    let fit_views: Vec<FitView> = views
        .iter()
        .zip(&view_cameras)
        .map(|(v, camera)| FitView { camera, edges: v.edges, joints2d: Some(v.joints2d) })
        .collect();
    let fit = if choice.mean_shape {
        GenderFit { space, fit: None, score: f64::NAN, seconds: 0.0 }
    } else {
        let problem = FitProblem { model, gender: space, pose, camera: &camera, edges, joints2d, views: &fit_views };
        let fit = fit_shape(&problem, options, &mut |f| progress(f.clamp(0.0, 1.0)))?;
        GenderFit { space, score: fit.best_score, fit: Some(fit), seconds: t.elapsed().as_secs_f64() }
    };
    let fit_seconds = t.elapsed().as_secs_f64();
    let weights = fit.fit.as_ref().map_or_else(Vec::new, |f| f.weights.clone());
    let score = fit.score;
    let (gender, gender_value, gender_confidence) = match (choice.gender, fit.fit.as_ref()) {
        (Some(g), _) => (g, g.index() as f64, 1.0),
        (None, Some(f)) => {
            let value = f.gender_value.unwrap_or(0.5);
            let male = f.male_probability.unwrap_or(0.5);
            (if value > 0.5 { Gender::Male } else { Gender::Female }, value, male.max(1.0 - male))
        }
        (None, None) => {
            return Err(Error::OutOfRange { name: "gender", detail: "the mean-shape baseline needs a gender".into() })
        }
    };
    let (edge_support, low_evidence) =
        fit.fit.as_ref().map_or((f64::NAN, false), |f| (f.edge_support, f.low_evidence()));
    let part_support = fit.fit.as_ref().map(|f| f.part_support);
    let proportions = fit.fit.as_ref().and_then(|f| f.proportions);
    let fits = vec![fit];

    let t = Instant::now();
    let calibration = choice.calibration.filter(|_| options.height.is_none() && !choice.mean_shape);
    let weights = match (calibration, choice.gender) {
        (Some(c), Some(g)) => calibrated_weights(model, space, &c, g, weights)?,
        _ => weights,
    };
    let mut rest = rest_body(model, space, &weights, proportions.as_ref())?;
    let fit_height = crate::body::rig::y_extent(&rest.vertices);
    let height = match (options.height, calibration) {
        (Some(h), _) => Some(h),
        (None, Some(c)) => {
            let evidence = HeightEvidence::new(proportions.as_ref(), choice.widths.as_ref());
            Some(c.height.calibrated(fit_height, gender_value, &evidence)?)
        }
        (None, None) => None,
    };
    if let Some(h) = height {
        crate::body::rig::scale_to_height(&mut rest.vertices, &mut rest.joints, h)?;
    }
    // With per-sample cameras the chosen body's own skeleton sets the image scale.
    let camera = match joints2d {
        Some(j2) if options.sample_camera && !choice.mean_shape => refit_scale(pose, &camera, &rest.joints, j2)?,
        _ => camera,
    };
    let view_cameras = views
        .iter()
        .zip(view_cameras)
        .map(|(v, c)| match options.sample_camera && !choice.mean_shape {
            true => refit_scale(pose, &c, &rest.joints, v.joints2d),
            false => Ok(c),
        })
        .collect::<Result<_>>()?;
    let ik_pose = ik::solve(&rest.joints, pose, &IkOptions { retarget: options.retarget })?;
    let posed_vertices = skin(&rest.vertices, model.skin_weights(), &ik_pose, options.skinning)?;
    Ok(FittedBody {
        fits,
        space,
        gender,
        gender_value,
        gender_confidence,
        weights,
        edge_support,
        low_evidence,
        part_support,
        score,
        camera,
        view_cameras,
        rest,
        fit_height,
        calibrated: calibration.is_some(),
        ik_pose,
        posed_vertices,
        fit_seconds,
        posing_seconds: t.elapsed().as_secs_f64(),
    })
}

//! The shape stage in one place: fit each shape space the caller allows, keep the best, apply its
//! bone-length factors, scale it to the height, pose it by IK and skin it. [`super::run_pipeline`]
//! and the C API's `skb_fit_shape` both call [`fit_body`].

use std::time::Instant;

use crate::body::ik::{self, IkOptions, Pose};
use crate::body::skin::skin;
use crate::body::{BodyModel, Gender, RestShape};
use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::fit::{fit_shape, FitOptions, FitProblem, FitResult};
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

/// The gender's mean rest skeleton, scaled about its pelvis to `height` metres when given
/// ([`FitOptions::height`]).
fn mean_skeleton(model: &BodyModel, gender: Gender, height: Option<f64>) -> Result<Joints3> {
    let space = model.space(gender);
    let mut joints = *space.mean_joints();
    if let Some(h) = height {
        crate::body::rig::scale_to_height(&mut space.mean().to_vec(), &mut joints, h)?;
    }
    Ok(joints)
}

/// One gender's fit.
#[derive(Clone, Debug, PartialEq)]
pub struct GenderFit {
    /// The shape space fitted.
    pub gender: Gender,
    /// The SIR's result (`None` for the mean shape).
    pub fit: Option<FitResult>,
    /// Best sample's match score (higher is better); NaN for the mean shape.
    pub score: f64,
    /// Wall-clock seconds of this fit.
    pub seconds: f64,
}

/// Which shape spaces [`fit_body`] tries and how it treats the camera. `Default`: both genders,
/// fitted, camera refitted to each body.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyChoice {
    /// The shape space to fit; `None` fits both and keeps the better-scoring one.
    pub gender: Option<Gender>,
    /// Skip the fit and use the gender's mean shape, posed the same way (the benchmark's
    /// baseline). Needs `gender`.
    pub mean_shape: bool,
    /// Keep the pose solver's camera (fitted to a 1.75 m person of the dictionary's
    /// proportions) instead of refitting its scales and translation to each body's skeleton
    /// ([`refit_camera`]; only done when the 2-D joints are given).
    pub keep_pose_scale: bool,
}

/// What [`fit_body`] produces. Owns its data.
#[derive(Clone, Debug)]
pub struct FittedBody {
    /// The fits, in order: the given gender, or female then male.
    pub fits: Vec<GenderFit>,
    /// The chosen shape space.
    pub gender: Gender,
    /// PCA weights of the chosen shape (Y* of the SIR; empty for the mean shape), metres.
    pub weights: Vec<f64>,
    /// Best match score of the chosen fit (NaN for the mean shape).
    pub score: f64,
    /// The camera refitted to the chosen body (see [`BodyChoice::keep_pose_scale`] and
    /// [`FitOptions::sample_camera`]), pixels.
    pub camera: WeakPerspective,
    /// The chosen rest shape with its bone-length factors applied and scaled to
    /// [`FitOptions::height`] when given (model frame, metres).
    pub rest: RestShape,
    /// The IK pose taking `rest.joints` to the estimated 3-D joints.
    pub ik_pose: Pose,
    /// The posed vertices (model frame, metres); project with `pose.camera`.
    pub posed_vertices: Vec<[f32; 3]>,
    /// Wall-clock seconds of every fit together.
    pub fit_seconds: f64,
    /// Wall-clock seconds of posing the chosen shape (IK and skinning).
    pub posing_seconds: f64,
}

/// Fits the body to `edges` (255 edge, 0 not) under the 3-D `pose` (canonical joints, metres)
/// seen through `camera`: each allowed shape space by
/// SIR ([`fit_shape`]), the best score wins (ties keep the first), then bone-length factors,
/// height, IK and skinning. With `joints2d` the camera is refitted to each body's skeleton (and,
/// with [`FitOptions::sample_camera`], to the chosen body's) and the fit uses the joints term.
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
    if choice.mean_shape && choice.gender.is_none() {
        return Err(Error::OutOfRange {
            name: "gender",
            detail: "the mean-shape baseline needs a gender (nothing to choose by)".into(),
        });
    }
    let genders: Vec<Gender> = choice.gender.map_or(Gender::ALL.to_vec(), |g| vec![g]);
    let n = genders.len() as f32;
    let t = Instant::now();
    let mut fits = Vec::with_capacity(genders.len());
    let mut cameras = Vec::with_capacity(genders.len());
    for (i, &gender) in genders.iter().enumerate() {
        let tf = Instant::now();
        let camera = match joints2d {
            Some(j2) if !choice.keep_pose_scale => {
                refit_scale(pose, camera, &mean_skeleton(model, gender, options.height)?, j2)?
            }
            _ => *camera,
        };
        if choice.mean_shape {
            fits.push(GenderFit { gender, fit: None, score: f64::NAN, seconds: 0.0 });
            cameras.push(camera);
            continue;
        }
        let problem = FitProblem { model, gender, pose, camera: &camera, edges, joints2d };
        let fit = fit_shape(&problem, options, &mut |f| progress(((i as f32 + f) / n).clamp(0.0, 1.0)))?;
        fits.push(GenderFit { gender, score: fit.best_score, fit: Some(fit), seconds: tf.elapsed().as_secs_f64() });
        cameras.push(camera);
    }
    let fit_seconds = t.elapsed().as_secs_f64();
    // Highest score wins; ties (and NaN mean-shape scores) keep the first.
    let chosen = (1..fits.len()).fold(0, |best, k| if fits[k].score > fits[best].score { k } else { best });
    let gender = fits[chosen].gender;
    let weights = fits[chosen].fit.as_ref().map_or_else(Vec::new, |f| f.weights.clone());
    let score = fits[chosen].score;
    let camera = cameras.swap_remove(chosen);

    let t = Instant::now();
    let mut rest = model.space(gender).synthesize(&weights)?;
    if let Some(props) = fits[chosen].fit.as_ref().and_then(|f| f.proportions.as_ref()) {
        crate::fit::proportions::apply_in_place(&mut rest.vertices, &mut rest.joints, model.skin_weights(), props)?;
    }
    if let Some(h) = options.height {
        crate::body::rig::scale_to_height(&mut rest.vertices, &mut rest.joints, h)?;
    }
    // With per-sample cameras the chosen body's own skeleton sets the image scale.
    let camera = match joints2d {
        Some(j2) if options.sample_camera && !choice.mean_shape => refit_scale(pose, &camera, &rest.joints, j2)?,
        _ => camera,
    };
    let ik_pose = ik::solve(&rest.joints, pose, &IkOptions { retarget: options.retarget })?;
    let posed_vertices = skin(&rest.vertices, model.skin_weights(), &ik_pose, options.skinning)?;
    Ok(FittedBody {
        fits,
        gender,
        weights,
        score,
        camera,
        rest,
        ik_pose,
        posed_vertices,
        fit_seconds,
        posing_seconds: t.elapsed().as_secs_f64(),
    })
}

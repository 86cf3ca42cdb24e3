//! Re-posing a finished result without re-fitting its shape ([`repose`]): pick one of the pose's
//! depth readings ([`crate::pose::alternatives`]), flip one limb's depth, or re-estimate the 3-D
//! pose from moved 2-D joints (issue 50's live correction: a host calls it while the artist
//! drags a joint marker). The fitted rest body (shape weights, bone-length factors, height, rest
//! mesh and skin weights) is kept; only the 3-D pose, the IK pose, the posed vertices and joints
//! and the camera change. Cost: a pick or a flip is IK + skinning (a few ms); moved joints add
//! one [`crate::pose::estimate_pose`] (about 4 ms; docs/benchmarks.md, "Re-pose").

use crate::body::ik::{self, IkOptions};
use crate::body::skin::{skin, SkinMethod};
use crate::error::{Error, Result};
use crate::pose::{estimate_pose, flip_limb, pick_alternative, Dictionary, FlipStatus, Limb, PoseOptions};
use crate::skeleton::{Joints2, JOINT_NAMES, NUM_JOINTS};

use super::PipelineResult;

/// What a result needs to be re-posed: the options its pose and posing steps ran with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Posing {
    /// The pose solver's options ([`super::PipelineOptions::pose`]).
    pub pose: PoseOptions,
    /// IK retargeting ([`crate::fit::FitOptions::retarget`]).
    pub retarget: bool,
    /// Skinning method ([`crate::fit::FitOptions::skinning`]).
    pub skinning: SkinMethod,
}

/// Two visible moved joints closer than this fraction of the visible joints' bounding-box
/// diagonal count as dropped onto each other (1 %: 5 px on a 500-px figure; a drawn figure's
/// distinct joints are farther apart, hands on hips included).
pub const COINCIDE_FRACTION: f64 = 0.01;

/// What [`repose`] should do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ReposeRequest<'a> {
    /// Take the pose's alternative at this index (0 = the current pose).
    Alternative(usize),
    /// Flip this limb's depth.
    Flip(Limb),
    /// Re-estimate the 3-D pose from these 2-D joints (pixels of the result's sketch).
    Joints(&'a Joints2),
}

/// What [`repose`] did. Every outcome but [`ReposeOutcome::Reposed`] leaves the result unchanged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ReposeOutcome {
    /// The result was re-posed.
    Reposed,
    /// The limb lies in the picture plane: no depth to flip ([`crate::pose::FlipStatus::NoDepth`]).
    NoDepth,
    /// A visible moved joint lies outside the sketch (or is not finite).
    JointOutsideImage {
        /// The joint's name.
        joint: &'static str,
    },
    /// Two visible moved joints lie on each other ([`COINCIDE_FRACTION`]).
    JointsCoincide {
        /// The first joint's name.
        a: &'static str,
        /// The second joint's name.
        b: &'static str,
    },
    /// No plausible body explains the moved joints ([`PoseEstimate::plausible`], or the solver
    /// found them degenerate): the body is not contorted to them.
    Implausible,
}

impl ReposeOutcome {
    /// A one-line description for a host's status bar.
    pub fn message(&self) -> String {
        match self {
            ReposeOutcome::Reposed => "re-posed".into(),
            ReposeOutcome::NoDepth => "the limb lies in the picture plane: no depth to flip".into(),
            ReposeOutcome::JointOutsideImage { joint } => format!("joint {joint} is outside the sketch"),
            ReposeOutcome::JointsCoincide { a, b } => format!("joints {a} and {b} lie on each other"),
            ReposeOutcome::Implausible => "no plausible body explains these joints".into(),
        }
    }
}

/// Checks moved joints against a `width` × `height` sketch (module doc of [`ReposeOutcome`]).
fn check_moved(j: &Joints2, width: usize, height: usize) -> Option<ReposeOutcome> {
    let vis: Vec<usize> = (0..NUM_JOINTS).filter(|&k| j.visible[k]).collect();
    for &k in &vis {
        let [x, y] = j.xy[k];
        if !(x.is_finite() && y.is_finite() && (0.0..=width as f64).contains(&x) && (0.0..=height as f64).contains(&y))
        {
            return Some(ReposeOutcome::JointOutsideImage { joint: JOINT_NAMES[k] });
        }
    }
    let span = |a: usize| {
        let (lo, hi) =
            vis.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &k| (l.min(j.xy[k][a]), h.max(j.xy[k][a])));
        hi - lo
    };
    let limit = COINCIDE_FRACTION * span(0).hypot(span(1));
    for (i, &a) in vis.iter().enumerate() {
        for &b in &vis[i + 1..] {
            if (j.xy[a][0] - j.xy[b][0]).hypot(j.xy[a][1] - j.xy[b][1]) <= limit {
                return Some(ReposeOutcome::JointsCoincide { a: JOINT_NAMES[a], b: JOINT_NAMES[b] });
            }
        }
    }
    None
}

/// Re-poses `result` in place as `request` says (module doc), keeping its fitted shape: the new
/// 3-D pose is posed onto the rest skeleton by IK and the rest mesh skinned to it with the
/// result's [`Posing`]. For moved joints, the pose is re-estimated with `dict` (the dictionary
/// the result was made with) and the result's pose options, without an image depth cue, and the
/// camera's scales and translation are refitted to the body's own skeleton
/// ([`super::refit_camera`]); a pick or a flip keeps the camera (the image is unchanged) and the
/// 2-D joints. With the joints the result was made from (given, not detected), the re-estimate
/// is the run's own, so the mesh is the run's.
///
/// Returns the outcome; every outcome but [`ReposeOutcome::Reposed`] leaves `result` as it was.
/// Errors: [`Error::OutOfRange`] for an alternative index past the pose's alternatives; IK's and
/// skinning's (not expected for a plausible pose).
pub fn repose(result: &mut PipelineResult, dict: &Dictionary, request: ReposeRequest) -> Result<ReposeOutcome> {
    let posing = result.posing_options;
    let (pose, joints2d) = match request {
        ReposeRequest::Alternative(i) => {
            let n = result.pose.alternatives.len();
            let p = pick_alternative(&result.pose, i).ok_or_else(|| Error::OutOfRange {
                name: "alternative",
                detail: format!("{i} is not below the pose's {n} alternatives"),
            })?;
            (p, result.joints2d)
        }
        ReposeRequest::Flip(limb) => match flip_limb(&result.pose, limb) {
            (_, FlipStatus::NoDepth) => return Ok(ReposeOutcome::NoDepth),
            (p, FlipStatus::Flipped) => (p, result.joints2d),
        },
        ReposeRequest::Joints(j) => {
            if let Some(o) = check_moved(j, result.edges.width(), result.edges.height()) {
                return Ok(o);
            }
            let est = match estimate_pose(dict, j, &posing.pose) {
                Ok(e) if e.plausible => e,
                Ok(_) | Err(Error::Degenerate(_) | Error::CoincidentJoints { .. } | Error::TooFewJoints { .. }) => {
                    return Ok(ReposeOutcome::Implausible)
                }
                Err(e) => return Err(e),
            };
            let est = super::refit_camera(&est, &result.mesh.joints, j)?;
            (est, *j)
        }
    };
    let ik_pose = ik::solve(&result.mesh.joints, &pose.joints, &IkOptions { retarget: posing.retarget })?;
    let posed_vertices = skin(&result.mesh.vertices, &result.mesh.weights, &ik_pose, posing.skinning)?;
    result.posed_joints = ik_pose.joints;
    result.ik_pose = ik_pose;
    result.posed_vertices = posed_vertices;
    result.pose = pose;
    result.joints2d = joints2d;
    Ok(ReposeOutcome::Reposed)
}

//! Interim bodies of a run: what a host can show before the final body
//! ([`super::run_pipeline_progressive`]): the mean shape in the estimated pose as soon as the pose
//! is known, then the gender decision's fit of the chosen gender before the final fit refines it.

use crate::body::ik::Pose;
use crate::body::{Gender, RestShape};
use crate::camera::WeakPerspective;

use super::shape_keys::ShapeOrigin;

/// Which interim body [`InterimBody`] is, in the order a run reports them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InterimStage {
    /// The mean shape of the expected gender (given, or the gender classifier's guess from the
    /// drawing's proportions), posed to the estimated 3-D pose: right after the pose step.
    MeanShape,
    /// The gender decision's fit of the chosen gender (its deciding dimensions), posed: before
    /// the final fit in all dimensions. Only runs that decide the gender by fitting report it.
    DecidingFit,
}

impl InterimStage {
    /// The stage's number in the C API (`SKB_INTERIM_MEAN_SHAPE` 0, `SKB_INTERIM_DECIDING_FIT` 1).
    pub fn index(self) -> u32 {
        match self {
            InterimStage::MeanShape => 0,
            InterimStage::DecidingFit => 1,
        }
    }
}

/// A body shown before the final one; borrowed for the callback's duration.
#[derive(Clone, Debug)]
pub struct InterimBody<'a> {
    /// Which interim body this is.
    pub stage: InterimStage,
    /// The body's gender.
    pub gender: Gender,
    /// The rest shape (model frame, metres).
    pub rest: &'a RestShape,
    /// How `rest` was made from the shape space (its weights, metres, are empty for the mean
    /// shape), for its shape keys.
    pub shape: ShapeOrigin,
    /// Its pose: the IK solution that poses `rest` to the estimated 3-D pose.
    pub pose: &'a Pose,
    /// The posed vertices (model frame, metres), in `rest`'s order.
    pub posed_vertices: &'a [[f32; 3]],
    /// The camera that projects the posed body onto the sketch.
    pub camera: &'a WeakPerspective,
}

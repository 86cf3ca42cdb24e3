//! The production rig's options shared by `run` and `body`: bone names, rest pose, origin.

use sketchbody::body::rig::{Naming, Placement, RestPose, RigOptions};

use crate::CliError;

/// Rig options of the GLB export.
#[derive(clap::Args)]
pub struct RigArgs {
    /// Bone names: project (r_elbow, …), mixamo (mixamorig:RightForeArm, …) or unreal
    /// (lowerarm_r, …).
    #[arg(long, default_value = "project")]
    naming: String,
    /// Rest pose of the GLB: a (MakeHuman's A-pose) or t (MakeHuman's T-pose).
    #[arg(long, default_value = "a")]
    rest_pose: String,
    /// Origin of the GLB: floor (between the feet, feet at height 0) or pelvis.
    #[arg(long, default_value = "floor")]
    origin: String,
}

impl RigArgs {
    /// The parsed options (errors name the bad value).
    pub fn options(&self) -> Result<RigOptions, CliError> {
        Ok(RigOptions {
            naming: Naming::parse(&self.naming)?,
            rest_pose: RestPose::parse(&self.rest_pose)?,
            placement: Placement::parse(&self.origin)?,
        })
    }
}

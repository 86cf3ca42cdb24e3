//! The production rig's options shared by `run` and `body`: bone names, rest pose, origin,
//! twist bones, how the pose is carried, IK targets.

use sketchbody::body::rig::{Naming, Placement, PoseAs, RestPose, RigOptions};

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
    /// Twist bones in the upper arms, forearms and thighs (upperarm_twist_01_l, … under
    /// --naming unreal), sharing the limbs' skin so a twist spreads along the limb
    /// (`--twist-bones false`: MakeHuman's 53 bones only).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    twist_bones: bool,
    /// How the rigged files carry the sketch's pose: action (the rest is the A- or T-pose, the
    /// bones stand in the pose, also a one-frame clip "pose"), rest (the pose is the rest pose,
    /// no clip: bones posed by hand stay), both (the pose is the rest pose, plus a one-frame clip
    /// "a_pose" or "t_pose" holding --rest-pose's pose, for retargeting).
    #[arg(long, default_value = "action")]
    pose_as: String,
    /// Non-deforming IK target bones at the hands and feet (ik_hand_r, ik_foot_l, … under
    /// ik_hand_root / ik_foot_root, Unreal's names under --naming unreal).
    #[arg(long)]
    ik_targets: bool,
    /// The body's shape dimensions as shape keys (glTF morph targets, FBX blend shapes, USD
    /// BlendShapes): one per shape weight (the fit's for `run`, --weights' for `body`; the
    /// space's default count for the mean shape), each one standard deviation of its
    /// component, at 0 (`--shape-keys false`: none).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    shape_keys: bool,
}

impl RigArgs {
    /// Whether the rigged files carry shape keys.
    pub fn shape_keys(&self) -> bool {
        self.shape_keys
    }

    /// The parsed options (errors name the bad value).
    pub fn options(&self) -> Result<RigOptions, CliError> {
        Ok(RigOptions {
            naming: Naming::parse(&self.naming)?,
            rest_pose: RestPose::parse(&self.rest_pose)?,
            placement: Placement::parse(&self.origin)?,
            twist_bones: self.twist_bones,
            pose_as: PoseAs::parse(&self.pose_as)?,
            ik_targets: self.ik_targets,
        })
    }
}

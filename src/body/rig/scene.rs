//! What an export writes for the production rig, for the chosen options: the rest mesh (A- or
//! T-pose) and armature placed with the origin at the floor or at the pelvis, and the body's pose
//! as bone rotations with the root's translation only.

use nalgebra::Vector3;

use crate::body::ik::Pose;
use crate::body::rig::RiggedMesh;
use crate::body::VertexWeights;
use crate::error::{Error, Result};
use crate::skeleton::{joint, Joints3};

use super::armature::{Armature, RigPose};
use super::bones::{NUM_RIG_BONES, RIG_BONES};
use super::data::RigData;
use super::ik_targets::{with_ik_targets, IK_BONES};
use super::shape_keys::ShapeKey;
use super::twist::{split_weights, with_twist_bones, TWIST_BONES};

/// Bone naming convention of an export.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Naming {
    /// The project's names: each bone named after the joint it starts at (`pelvis`, `spine`,
    /// `r_shoulder`, `r_elbow`, …; the canonical joint names where they coincide). Default.
    #[default]
    Project,
    /// Mixamo's (`mixamorig:Hips`, `mixamorig:Spine`, `mixamorig:RightForeArm`, …; the root at
    /// the floor is `mixamorig:Root`).
    Mixamo,
    /// Unreal-style, MakeHuman's `game_engine` names (`root`, `pelvis`, `spine_01`,
    /// `lowerarm_r`, …).
    Unreal,
}

impl Naming {
    /// All conventions, in the C API's order (0 project, 1 Mixamo, 2 Unreal).
    pub const ALL: [Naming; 3] = [Naming::Project, Naming::Mixamo, Naming::Unreal];

    /// Parses `project`, `mixamo` or `unreal`. Errors: anything else ([`Error::OutOfRange`]).
    pub fn parse(s: &str) -> Result<Naming> {
        match s {
            "project" => Ok(Naming::Project),
            "mixamo" => Ok(Naming::Mixamo),
            "unreal" => Ok(Naming::Unreal),
            _ => Err(Error::OutOfRange {
                name: "bone naming",
                detail: format!("{s:?}: expected project, mixamo or unreal"),
            }),
        }
    }

    /// The name of bone `b` (an index into [`RIG_BONES`], then [`TWIST_BONES`] from 53 on);
    /// `None` when out of range.
    pub fn bone_name(self, b: usize) -> Option<String> {
        let (project, mixamo, unreal) = match RIG_BONES.get(b) {
            Some(bone) => (bone.project, bone.mixamo, if b == 0 { "root" } else { bone.makehuman }),
            None => {
                let t = TWIST_BONES.get(b - NUM_RIG_BONES)?;
                (t.project, t.mixamo, t.unreal)
            }
        };
        Some(self.pick(project, mixamo, unreal))
    }

    /// The name of IK target bone `k` (an index into [`IK_BONES`]); `None` when out of range.
    pub fn ik_bone_name(self, k: usize) -> Option<String> {
        IK_BONES.get(k).map(|b| self.pick(b.project, b.mixamo, b.unreal))
    }

    fn pick(self, project: &str, mixamo: &str, unreal: &str) -> String {
        match self {
            Naming::Project => project.to_string(),
            Naming::Mixamo => format!("mixamorig:{mixamo}"),
            Naming::Unreal => unreal.to_string(),
        }
    }
}

/// The rest pose of an export.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RestPose {
    /// MakeHuman's A-pose, the shape model's own rest. Default (the OBJ files' rest).
    #[default]
    APose,
    /// MakeHuman's T-pose (MPFB2's `poses/game_engine_fk/t-pose.json`: clavicles, arms, thighs
    /// and feet turned so the arms are horizontal), the rest mesh skinned into it.
    TPose,
}

impl RestPose {
    /// Parses `a` or `t`. Errors: anything else ([`Error::OutOfRange`]).
    pub fn parse(s: &str) -> Result<RestPose> {
        match s {
            "a" => Ok(RestPose::APose),
            "t" => Ok(RestPose::TPose),
            _ => Err(Error::OutOfRange { name: "rest pose", detail: format!("{s:?}: expected a or t") }),
        }
    }
}

/// Where the export's origin is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Placement {
    /// On the floor between the feet: the rest body's lowest point at y = 0, x and z of the
    /// midpoint of the ankles at 0; the posed body is lifted or lowered (root translation) so
    /// that its lowest point is on the floor too. Default.
    #[default]
    Floor,
    /// At the rest pelvis joint (the skeleton's own origin); no root translation.
    Pelvis,
}

impl Placement {
    /// Parses `floor` or `pelvis`. Errors: anything else ([`Error::OutOfRange`]).
    pub fn parse(s: &str) -> Result<Placement> {
        match s {
            "floor" => Ok(Placement::Floor),
            "pelvis" => Ok(Placement::Pelvis),
            _ => Err(Error::OutOfRange { name: "origin", detail: format!("{s:?}: expected floor or pelvis") }),
        }
    }
}

/// How an export carries the body's pose.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PoseAs {
    /// The rest (bind) pose is the A- or T-pose ([`RestPose`]); the bones stand in the body's
    /// pose, which is also a one-frame clip `pose` (glTF's animation; USD's `SkelAnimation`, the
    /// skeleton's animation source). Default.
    #[default]
    Action,
    /// The body's pose is the rest (bind) pose: the rest mesh is the posed body, the bones stand
    /// at rest, no clip, so a bone an artist poses by hand stays where it is put.
    Rest,
    /// As [`PoseAs::Rest`], plus a one-frame clip `a_pose` or `t_pose` holding the model's A- or
    /// T-pose ([`RestPose`]) relative to that rest (for retargeting; glTF's animation, USD's
    /// `SkelAnimation` not bound to the skeleton, FBX's animation stack).
    Both,
}

impl PoseAs {
    /// Parses `rest`, `action` or `both`. Errors: anything else ([`Error::OutOfRange`]).
    pub fn parse(s: &str) -> Result<PoseAs> {
        match s {
            "action" => Ok(PoseAs::Action),
            "rest" => Ok(PoseAs::Rest),
            "both" => Ok(PoseAs::Both),
            _ => Err(Error::OutOfRange { name: "pose as", detail: format!("{s:?}: expected rest, action or both") }),
        }
    }
}

/// A one-frame clip an export writes: a name and a pose of the scene's armature.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// The clip's name (`pose`, `a_pose` or `t_pose`).
    pub name: &'static str,
    /// Its pose, relative to the scene's rest.
    pub pose: RigPose,
}

/// Options of the rigged export. `Default`: project names, A-pose, origin at the floor,
/// MakeHuman's 53 bones only (no twist bones, no IK targets), the pose as an action.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RigOptions {
    /// Bone names.
    pub naming: Naming,
    /// Rest pose.
    pub rest_pose: RestPose,
    /// Origin.
    pub placement: Placement,
    /// Add the twist bones of [`super::twist`] (bones 53..59) and share the limbs' skin with
    /// them.
    pub twist_bones: bool,
    /// How the body's pose is carried.
    pub pose_as: PoseAs,
    /// Add the IK target bones of [`super::ik_targets`] after the others (non-deforming).
    pub ik_targets: bool,
}

/// The rigged body an export writes. Owns its data.
#[derive(Clone, Debug)]
pub struct RigScene {
    /// Rest vertices (placed; skinned into the T-pose when asked), metres.
    pub rest_vertices: Vec<[f32; 3]>,
    /// Canonical joints of that rest, metres.
    pub rest_joints: Joints3,
    /// The rest armature: MakeHuman's 53 bones, then the twist bones and the IK targets when
    /// asked (its `parents` give the tree every export writes).
    pub armature: Armature,
    /// The body's pose relative to that rest (root translation only below the root).
    pub pose: RigPose,
    /// The posed vertices (the rig's own skinning, as a glTF viewer shows them), metres.
    pub posed_vertices: Vec<[f32; 3]>,
    /// Skin weights to the armature's bones, per vertex.
    pub skin: Vec<VertexWeights>,
    /// Bone names in the chosen convention.
    pub names: Vec<String>,
    /// The translation applied to the model frame (placement), metres.
    pub offset: Vector3<f64>,
    /// How the pose is carried ([`RigOptions::pose_as`]).
    pub pose_as: PoseAs,
    /// Shape keys in this rest's frame (each key's displacement of [`RigScene::rest_vertices`]);
    /// empty unless built by [`RigScene::build_with_shape_keys`].
    pub shape_keys: Vec<ShapeKey>,
    /// The one-frame clip to write, if any: the pose itself (`pose`, [`PoseAs::Action`]) or the
    /// A- or T-pose relative to the body's pose as rest ([`PoseAs::Both`]).
    pub clip: Option<Clip>,
}

impl RigScene {
    /// The rigged scene of `mesh` (rest, with its canonical joints) posed by `pose` (IK from
    /// `mesh.joints`), using the body model's rig `rig`. Errors: the pose's rest joints are not
    /// the mesh's ([`Error::OutOfRange`]); an invalid mesh or rig; degenerate bones.
    pub fn build(rig: &RigData, mesh: &RiggedMesh, pose: &Pose, options: &RigOptions) -> Result<RigScene> {
        RigScene::build_with_shape_keys(rig, mesh, pose, options, &[])
    }

    /// As [`RigScene::build`], with shape keys: `keys` displace `mesh`'s rest vertices (model
    /// frame, metres); the scene carries them into its own rest (the T-pose's, the pose's as rest)
    /// through the same skinning ([`ShapeKey::skinned`]). Errors: [`RigScene::build`]'s; a key
    /// without one finite displacement per vertex ([`ShapeKey::check`]).
    pub fn build_with_shape_keys(
        rig: &RigData,
        mesh: &RiggedMesh,
        pose: &Pose,
        options: &RigOptions,
        keys: &[ShapeKey],
    ) -> Result<RigScene> {
        mesh.validate()?;
        for k in keys {
            k.check(mesh.vertices.len())?;
        }
        let same = mesh.joints.iter().flatten().zip(pose.rest.iter().flatten()).all(|(a, b)| (a - b).abs() < 1e-9);
        if !same {
            return Err(Error::OutOfRange { name: "pose", detail: "its rest joints are not the mesh's".into() });
        }
        let a_pose = Armature::rest(rig, &mesh.joints, &mesh.vertices)?;
        let posed = RigPose::from_canonical(pose);
        let (vertices, joints, armature, posed, keys) = match options.rest_pose {
            RestPose::APose => (mesh.vertices.clone(), mesh.joints, a_pose, posed, keys.to_vec()),
            RestPose::TPose => {
                let t = RigPose::from_local_eulers(&a_pose, &rig.tpose);
                let v = t.skin(&a_pose, &mesh.vertices, &rig.skin)?;
                let keys = keys.iter().map(|k| k.skinned(&rig.skin, &t.rotations)).collect();
                let joints = t.canonical_joints(&a_pose, &mesh.joints);
                (v, joints, t.posed_armature(&a_pose), posed.relative_to(&t), keys)
            }
        };
        let offset = match options.placement {
            Placement::Floor => -armature.heads[0],
            Placement::Pelvis => -Vector3::from(joints[joint::PELVIS]),
        };
        let rest_vertices: Vec<[f32; 3]> =
            vertices.iter().map(|v| [0, 1, 2].map(|c| (v[c] as f64 + offset[c]) as f32)).collect();
        let rest_joints = joints.map(|j| [0, 1, 2].map(|c| j[c] + offset[c]));
        let mut armature = armature.translated(&offset);
        let mut pose = posed;
        let mut skin = rig.skin.clone();
        if options.twist_bones {
            skin = split_weights(&armature, &rest_vertices, &skin);
            armature = with_twist_bones(&armature);
            let twists: Vec<_> = TWIST_BONES.iter().map(|t| pose.rotations[t.limb]).collect();
            pose.rotations.extend(twists);
        }
        let mut names: Vec<String> = (0..armature.len()).filter_map(|b| options.naming.bone_name(b)).collect();
        if options.ik_targets {
            armature = with_ik_targets(&armature);
            let targets: Vec<_> = IK_BONES.iter().map(|t| pose.rotations[t.follows]).collect();
            pose.rotations.extend(targets);
            names.extend((0..IK_BONES.len()).filter_map(|k| options.naming.ik_bone_name(k)));
        }
        let mut posed_vertices = pose.skin(&armature, &rest_vertices, &skin)?;
        if options.placement == Placement::Floor {
            let low = posed_vertices.iter().map(|v| v[1]).fold(f32::INFINITY, f32::min);
            pose.root_translation = Vector3::new(0.0, -low as f64, 0.0);
            posed_vertices.iter_mut().for_each(|v| v[1] -= low);
        }
        let (rest_vertices, rest_joints, armature, pose, clip, shape_keys) = match options.pose_as {
            PoseAs::Action => {
                let clip = Clip { name: "pose", pose: pose.clone() };
                (rest_vertices, rest_joints, armature, pose, Some(clip), keys)
            }
            PoseAs::Rest | PoseAs::Both => {
                let joints = pose.canonical_joints(&armature, &rest_joints);
                let still = RigPose::rest(armature.len());
                let clip = (options.pose_as == PoseAs::Both).then(|| Clip {
                    name: match options.rest_pose {
                        RestPose::APose => "a_pose",
                        RestPose::TPose => "t_pose",
                    },
                    pose: still.relative_to(&pose),
                });
                let keys = keys.iter().map(|k| k.skinned(&skin, &pose.rotations)).collect();
                (posed_vertices.clone(), joints, pose.posed_armature(&armature), still, clip, keys)
            }
        };
        Ok(RigScene {
            rest_vertices,
            rest_joints,
            armature,
            pose,
            posed_vertices,
            skin,
            names,
            offset,
            pose_as: options.pose_as,
            shape_keys,
            clip,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_options_parse_and_reject_the_rest() {
        assert_eq!(Naming::Project.bone_name(9).unwrap(), "r_elbow");
        assert_eq!(Naming::Mixamo.bone_name(1).unwrap(), "mixamorig:Hips");
        assert_eq!(Naming::Unreal.bone_name(0).unwrap(), "root");
        assert_eq!(Naming::Unreal.bone_name(2).unwrap(), "spine_01");
        assert_eq!(Naming::Unreal.bone_name(54).unwrap(), "lowerarm_twist_01_r");
        assert_eq!(Naming::Mixamo.bone_name(55).unwrap(), "mixamorig:LeftArmTwist");
        assert!(Naming::Project.bone_name(59).is_none());
        assert_eq!(Naming::Unreal.ik_bone_name(5).unwrap(), "ik_hand_r");
        assert!(Naming::Unreal.ik_bone_name(7).is_none());
        assert_eq!(Naming::parse("mixamo").unwrap(), Naming::Mixamo);
        assert!(matches!(Naming::parse("rigify"), Err(Error::OutOfRange { name: "bone naming", .. })));
        assert_eq!(RestPose::parse("t").unwrap(), RestPose::TPose);
        assert!(RestPose::parse("x").is_err());
        assert_eq!(Placement::parse("pelvis").unwrap(), Placement::Pelvis);
        assert_eq!(PoseAs::parse("both").unwrap(), PoseAs::Both);
        assert!(matches!(PoseAs::parse("keyed"), Err(Error::OutOfRange { name: "pose as", .. })));
        assert!(Placement::parse("").is_err());
    }
}

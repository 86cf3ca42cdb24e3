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
use super::bones::RIG_BONES;
use super::data::RigData;

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

    /// The name of bone `b` (an index into [`RIG_BONES`]); `None` when out of range.
    pub fn bone_name(self, b: usize) -> Option<String> {
        let bone = RIG_BONES.get(b)?;
        Some(match self {
            Naming::Project => bone.project.to_string(),
            Naming::Mixamo => format!("mixamorig:{}", bone.mixamo),
            Naming::Unreal if b == 0 => "root".to_string(),
            Naming::Unreal => bone.makehuman.to_string(),
        })
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

/// Options of the rigged export. `Default`: project names, A-pose, origin at the floor.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RigOptions {
    /// Bone names.
    pub naming: Naming,
    /// Rest pose.
    pub rest_pose: RestPose,
    /// Origin.
    pub placement: Placement,
}

/// The rigged body an export writes. Owns its data.
#[derive(Clone, Debug)]
pub struct RigScene {
    /// Rest vertices (placed; skinned into the T-pose when asked), metres.
    pub rest_vertices: Vec<[f32; 3]>,
    /// Canonical joints of that rest, metres.
    pub rest_joints: Joints3,
    /// The rest armature.
    pub armature: Armature,
    /// The body's pose relative to that rest (root translation only below the root).
    pub pose: RigPose,
    /// The posed vertices (the rig's own skinning, as a glTF viewer shows them), metres.
    pub posed_vertices: Vec<[f32; 3]>,
    /// Skin weights to the 53 bones, per vertex.
    pub skin: Vec<VertexWeights>,
    /// Bone names in the chosen convention.
    pub names: Vec<String>,
    /// The translation applied to the model frame (placement), metres.
    pub offset: Vector3<f64>,
}

impl RigScene {
    /// The rigged scene of `mesh` (rest, with its canonical joints) posed by `pose` (IK from
    /// `mesh.joints`), using the body model's rig `rig`. Errors: the pose's rest joints are not
    /// the mesh's ([`Error::OutOfRange`]); an invalid mesh or rig; degenerate bones.
    pub fn build(rig: &RigData, mesh: &RiggedMesh, pose: &Pose, options: &RigOptions) -> Result<RigScene> {
        mesh.validate()?;
        let same = mesh.joints.iter().flatten().zip(pose.rest.iter().flatten()).all(|(a, b)| (a - b).abs() < 1e-9);
        if !same {
            return Err(Error::OutOfRange { name: "pose", detail: "its rest joints are not the mesh's".into() });
        }
        let a_pose = Armature::rest(rig, &mesh.joints, &mesh.vertices)?;
        let posed = RigPose::from_canonical(pose);
        let (vertices, joints, armature, posed) = match options.rest_pose {
            RestPose::APose => (mesh.vertices.clone(), mesh.joints, a_pose, posed),
            RestPose::TPose => {
                let t = RigPose::from_local_eulers(&a_pose, &rig.tpose);
                let v = t.skin(&a_pose, &mesh.vertices, &rig.skin)?;
                (v, t.canonical_joints(&a_pose, &mesh.joints), t.posed_armature(&a_pose), posed.relative_to(&t))
            }
        };
        let offset = match options.placement {
            Placement::Floor => -armature.heads[0],
            Placement::Pelvis => -Vector3::from(joints[joint::PELVIS]),
        };
        let rest_vertices: Vec<[f32; 3]> =
            vertices.iter().map(|v| [0, 1, 2].map(|c| (v[c] as f64 + offset[c]) as f32)).collect();
        let rest_joints = joints.map(|j| [0, 1, 2].map(|c| j[c] + offset[c]));
        let armature = armature.translated(&offset);
        let mut pose = posed;
        let mut posed_vertices = pose.skin(&armature, &rest_vertices, &rig.skin)?;
        if options.placement == Placement::Floor {
            let low = posed_vertices.iter().map(|v| v[1]).fold(f32::INFINITY, f32::min);
            pose.root_translation = Vector3::new(0.0, -low as f64, 0.0);
            posed_vertices.iter_mut().for_each(|v| v[1] -= low);
        }
        let names = (0..RIG_BONES.len()).filter_map(|b| options.naming.bone_name(b)).collect();
        Ok(RigScene {
            rest_vertices,
            rest_joints,
            armature,
            pose,
            posed_vertices,
            skin: rig.skin.clone(),
            names,
            offset,
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
        assert!(Naming::Project.bone_name(53).is_none());
        assert_eq!(Naming::parse("mixamo").unwrap(), Naming::Mixamo);
        assert!(matches!(Naming::parse("rigify"), Err(Error::OutOfRange { name: "bone naming", .. })));
        assert_eq!(RestPose::parse("t").unwrap(), RestPose::TPose);
        assert!(RestPose::parse("x").is_err());
        assert_eq!(Placement::parse("pelvis").unwrap(), Placement::Pelvis);
        assert!(Placement::parse("").is_err());
    }
}

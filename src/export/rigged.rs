//! What every rigged exporter (glTF, FBX, USD) needs from a [`RigScene`]: the input checks and
//! each bone's rest (bind) and posed local transforms.
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::body::rig::RiggedMesh;
use crate::body::rig::{RigPose, RigScene};
use crate::error::{Error, Result};

/// Checks that `scene` was built for `mesh`: a valid mesh, one rest vertex and one skin entry per
/// mesh vertex, finite coordinates. Errors: [`Error::OutOfRange`] (`"rig scene"`) for a count
/// mismatch, [`Error::NonFinite`] for a non-finite rest coordinate, the mesh's own errors.
pub fn check_scene(mesh: &RiggedMesh, scene: &RigScene) -> Result<()> {
    mesh.validate()?;
    if scene.rest_vertices.len() != mesh.vertices.len() || scene.skin.len() != mesh.vertices.len() {
        return Err(Error::OutOfRange {
            name: "rig scene",
            detail: format!("{} vertices for a mesh of {}", scene.rest_vertices.len(), mesh.vertices.len()),
        });
    }
    if let Some(c) = scene.rest_vertices.iter().flatten().find(|c| !c.is_finite()) {
        return Err(Error::NonFinite { name: "vertex coordinate", value: *c as f64 });
    }
    Ok(())
}

/// Bone `b`'s rest (bind) transform in the model frame: rotation its rest frame (local +Y
/// along the bone), translation its head, metres.
pub fn bind_transform(scene: &RigScene, b: usize) -> Isometry3<f64> {
    let arm = &scene.armature;
    Isometry3::from_parts(Translation3::from(arm.heads[b]), arm.frames[b])
}

/// Each bone's posed transform relative to its parent (the root's relative to the model
/// frame), in the armature's order: the rotation the pose gives it and its head's offset from the
/// parent's head in the parent's rest frame (the root: its head plus the pose's translation; an
/// IK target: its posed head in its parent's posed frame), metres.
pub fn posed_locals(scene: &RigScene) -> Vec<(Vector3<f64>, UnitQuaternion<f64>)> {
    pose_locals(scene, &scene.pose)
}

/// As [`posed_locals`] for another pose of the scene's armature (a clip's).
pub fn pose_locals(scene: &RigScene, pose: &RigPose) -> Vec<(Vector3<f64>, UnitQuaternion<f64>)> {
    let arm = &scene.armature;
    let local = pose.local_rotations(arm);
    let heads = pose.heads(arm);
    (0..arm.len())
        .map(|b| {
            let t = match (arm.parents[b], arm.follows[b]) {
                (None, _) => arm.heads[b] + pose.root_translation,
                // A helper that follows another bone: its posed head in its parent's posed frame.
                (Some(p), Some(_)) => (pose.rotations[p] * arm.frames[p]).inverse() * (heads[b] - heads[p]),
                (Some(p), None) => arm.frames[p].inverse() * (arm.heads[b] - arm.heads[p]),
            };
            (t, local[b])
        })
        .collect()
}

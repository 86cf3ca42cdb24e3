//! Posing a body onto another skeleton's motion: target joints that keep a source pose's bone
//! directions with the body's own bone lengths ([`retarget_directions`]), and a rest mesh posed
//! onto such targets by IK and linear blend skinning ([`pose_mesh`]). Used by the pose
//! dictionary's learning (mocap of other skeletons) and by the synthetic-sketch renderer.

use nalgebra::{Matrix3, Vector3};

use crate::body::ik::{self, IkOptions, Pose, BONE_ORDER};
use crate::body::skin::{skin, SkinMethod};
use crate::body::VertexWeights;
use crate::error::Result;
use crate::skeleton::{joint, Joints3, BONES, NUM_JOINTS};

/// An orthonormal frame (columns x, y, z) with y along `up` and x toward `side` (orthogonalised).
fn frame(side: &Vector3<f64>, up: &Vector3<f64>) -> Option<Matrix3<f64>> {
    let y = up.try_normalize(1e-9)?;
    let x = (side - y * side.dot(&y)).try_normalize(1e-9)?;
    Some(Matrix3::from_columns(&[x, y, x.cross(&y)]))
}

/// Target joints with the bone directions of `source` and the bone lengths of `rest`, pelvis at
/// the origin. The girdle bones (neck→shoulders, pelvis→hips) do not take the source's
/// directions, which belong to another skeleton's proportions: they keep their rest directions
/// turned with the source's chest frame (spine, shoulder line) and hip frame (spine, hip line),
/// so shoulders neither shrug nor droop. Errors on non-finite joints or zero-length bones.
pub fn retarget_directions(rest: &Joints3, source: &Joints3) -> Result<Joints3> {
    ik::check_joints("rest joint", rest)?;
    ik::check_joints("pose joint", source)?;
    let v = |j: &Joints3, k: usize| Vector3::from(j[k]);
    let spine = |j: &Joints3| v(j, joint::NECK) - v(j, joint::PELVIS);
    let girdle = |a: usize, b: usize| -> Option<Matrix3<f64>> {
        let f0 = frame(&(v(rest, b) - v(rest, a)), &spine(rest))?;
        let f1 = frame(&(v(source, b) - v(source, a)), &spine(source))?;
        Some(f1 * f0.transpose())
    };
    let chest = girdle(joint::R_SHOULDER, joint::L_SHOULDER);
    let hips = girdle(joint::R_HIP, joint::L_HIP);
    let mut t = [[0.0; 3]; NUM_JOINTS];
    for &b in &BONE_ORDER {
        let (s, c) = BONES[b];
        let rest_d = v(rest, c) - v(rest, s);
        let len = rest_d.norm();
        let turned = match b {
            1 | 4 => chest.map(|r| r * rest_d),
            8 | 11 => hips.map(|r| r * rest_d),
            _ => None,
        };
        let d = turned.unwrap_or_else(|| v(source, c) - v(source, s)).normalize();
        t[c] = (Vector3::from(t[s]) + d * len).into();
    }
    Ok(t)
}

/// Poses a rest mesh onto `target` joints (IK without retargeting, then LBS).
pub fn pose_mesh(
    rest_vertices: &[[f32; 3]],
    rest_joints: &Joints3,
    weights: &[VertexWeights],
    target: &Joints3,
) -> Result<(Vec<[f32; 3]>, Pose)> {
    let pose = ik::solve(rest_joints, target, &IkOptions { retarget: false })?;
    let posed = skin(rest_vertices, weights, &pose, SkinMethod::Linear)?;
    Ok((posed, pose))
}

//! Non-standard body proportions: per-group bone-length factors and their application to a rest
//! mesh ("scale the mesh per bone").
//!
//! Every bone `b` is stretched along its rest direction by a factor `k_b` (legs, arms, torso, the
//! neck→shoulder bones for shoulder width) with the posing machinery (a [`Pose`] with identity
//! rotations and `stretch = k`, skinned with LBS), so children follow their parents and the
//! joints land at the scaled positions. The head is scaled *uniformly* about the neck joint
//! instead (a vertex with weight `w` on the neck→head bone is scaled by `1 + (k−1)w`), because a
//! stretch along the bone alone would squash it. With `k ≠ 1` the result lies outside the PCA
//! space. Used by the shape fit (bone-length factors of a drawn character) and by the
//! synthetic-sketch renderer (ground-truth bodies).

use nalgebra::Vector3;

use crate::body::ik::{self, Pose, BONE_ORDER};
use crate::body::skin::{skin, SkinMethod};
use crate::body::VertexWeights;
use crate::error::{ensure_finite, Error, Result};
use crate::skeleton::{joint, Joints3, BONES, NUM_BONES};

/// Bone-length factors for non-standard proportions. Each is a multiplier of the body's own
/// length (1 = unchanged); accepted range 0.5..=2.0. The synthetic-sketch renderer draws random ones
/// (`render::sketch::scene::random_proportions`, ranges given on each field).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Proportions {
    /// Thigh and shin length (hip→knee→ankle); random 0.9..1.3 ("long legs").
    pub legs: f64,
    /// Upper arm and forearm length; random 0.9..1.15.
    pub arms: f64,
    /// Neck→shoulder bones, i.e. shoulder width; random 0.9..1.4 ("broad shoulders").
    pub shoulders: f64,
    /// Uniform head size about the neck joint; random 0.75..1.1 ("small heads").
    pub head: f64,
    /// Pelvis→neck length; random 0.9..1.1.
    pub torso: f64,
}

impl Default for Proportions {
    fn default() -> Self {
        Proportions { legs: 1.0, arms: 1.0, shoulders: 1.0, head: 1.0, torso: 1.0 }
    }
}

impl Proportions {
    /// Checks that every factor is finite and in 0.5..=2.0.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("proportions.legs", self.legs),
            ("proportions.arms", self.arms),
            ("proportions.shoulders", self.shoulders),
            ("proportions.head", self.head),
            ("proportions.torso", self.torso),
        ] {
            ensure_finite(name, v)?;
            if !(0.5..=2.0).contains(&v) {
                return Err(Error::OutOfRange { name, detail: format!("{v} is outside 0.5..=2.0") });
            }
        }
        Ok(())
    }

    /// Stretch factor of each canonical bone (the head bone is 1: the head scales uniformly).
    pub fn bone_factors(&self) -> [f64; NUM_BONES] {
        let (l, a, s, t) = (self.legs, self.arms, self.shoulders, self.torso);
        [1.0, s, a, a, s, a, a, t, 1.0, l, l, 1.0, l, l]
    }
}

/// Applies `props` to a rest mesh and its joints (see the module doc). Returns the new rest
/// vertices and joints.
pub fn apply_proportions(
    vertices: &[[f32; 3]],
    joints: &Joints3,
    weights: &[VertexWeights],
    props: &Proportions,
) -> Result<(Vec<[f32; 3]>, Joints3)> {
    props.validate()?;
    ik::check_joints("rest joint", joints)?;
    let k = props.bone_factors();
    let mut nj = *joints;
    for &b in &BONE_ORDER {
        let (s, c) = BONES[b];
        let d = Vector3::from(joints[c]) - Vector3::from(joints[s]);
        nj[c] = (Vector3::from(nj[s]) + d * k[b]).into();
    }
    let mut pose = Pose::rest(joints);
    pose.joints = nj;
    pose.stretch = k;
    let mut out = skin(vertices, weights, &pose, SkinMethod::Linear)?;
    // Uniform head scale about the (moved) neck joint.
    let neck = Vector3::from(nj[joint::NECK]);
    let h = (props.head - 1.0) as f32;
    if h != 0.0 {
        for (v, w) in out.iter_mut().zip(weights) {
            let wh: f32 = w.influences().filter(|&(b, _)| b == 0).map(|(_, x)| x).sum();
            if wh > 0.0 {
                let f = 1.0 + h * wh;
                for a in 0..3 {
                    v[a] = neck[a] as f32 + (v[a] - neck[a] as f32) * f;
                }
            }
        }
        let d = Vector3::from(joints[joint::HEAD]) - Vector3::from(joints[joint::NECK]);
        nj[joint::HEAD] = (neck + d * props.head).into();
    }
    Ok((out, nj))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::procedural::{capsule_humanoid, rest_joints};
    use crate::body::retarget::{pose_mesh, retarget_directions};
    use crate::skeleton::NUM_JOINTS;

    #[test]
    fn proportions_scale_bones_and_head_and_pose_lands_on_targets() {
        let j = rest_joints();
        let m = capsule_humanoid(&j, 8, 6);
        let props = Proportions { legs: 1.3, head: 0.8, ..Default::default() };
        let (v, nj) = apply_proportions(&m.vertices, &m.joints, &m.weights, &props).unwrap();
        let len = |j: &Joints3, a: usize, b: usize| (Vector3::from(j[a]) - Vector3::from(j[b])).norm();
        assert!((len(&nj, joint::R_KNEE, joint::R_ANKLE) / len(&j, joint::R_KNEE, joint::R_ANKLE) - 1.3).abs() < 1e-9);
        assert!((len(&nj, joint::HEAD, joint::NECK) / len(&j, joint::HEAD, joint::NECK) - 0.8).abs() < 1e-9);
        assert!((len(&nj, joint::NECK, joint::PELVIS) - len(&j, joint::NECK, joint::PELVIS)).abs() < 1e-9);
        let lowest = |v: &[[f32; 3]]| v.iter().map(|p| p[1]).fold(f32::INFINITY, f32::min);
        assert!(lowest(&v) < lowest(&m.vertices) - 0.1, "longer legs reach lower");
        let bad = Proportions { legs: f64::NAN, ..Default::default() };
        assert!(apply_proportions(&m.vertices, &m.joints, &m.weights, &bad).is_err());

        let target = retarget_directions(&nj, &j).unwrap();
        let (posed, pose) = pose_mesh(&v, &nj, &m.weights, &target).unwrap();
        assert_eq!(posed.len(), v.len());
        for k in 0..NUM_JOINTS {
            assert!((Vector3::from(pose.joints[k]) - Vector3::from(target[k])).norm() < 1e-6, "joint {k}");
        }
    }
}

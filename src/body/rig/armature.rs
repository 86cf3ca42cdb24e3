//! The production armature of one body: bone heads, tails and rest frames (Y along the bone,
//! MakeHuman's roll about it), and its poses (one global rotation per bone, rest → posed).
//!
//! Frames: a bone's rest frame is the rotation whose columns are the bone's X, Y, Z axes in the
//! model frame. It is Blender's `vec_roll_to_mat3` (the shortest rotation taking +Y to the bone
//! direction, then the roll about the bone) evaluated in Blender's axes (MakeHuman's rig files:
//! `(x, −z, y)` of the model frame) and expressed back in the model frame, so the axes are
//! physically those of MakeHuman's own Blender rig.

use nalgebra::{Matrix3, Rotation3, Unit, UnitQuaternion, Vector3};

use crate::body::ik::Pose;
use crate::body::VertexWeights;
use crate::error::{Error, Result};
use crate::skeleton::{Joints3, NUM_JOINTS};

use super::bones::{Driver, CANONICAL_CARRIER, NUM_RIG_BONES, RIG_BONES};
use super::data::RigData;

/// Length of the root bone (at the floor, pointing forward), metres.
pub const ROOT_LENGTH: f64 = 0.1;
/// Bones shorter than this (metres) are rejected as degenerate.
pub const MIN_RIG_BONE_LENGTH: f64 = 1e-5;

/// The rest armature of one body. Owns its data; indices follow [`RIG_BONES`], then any bones
/// an export adds ([`super::extra`]: twist bones, IK targets), every parent before its children.
#[derive(Clone, Debug, PartialEq)]
pub struct Armature {
    /// Each bone's parent index (`None` for the root).
    pub parents: Vec<Option<usize>>,
    /// For a helper bone that follows another in every pose (an IK target,
    /// [`super::ik_targets`]), that bone's index: its posed head is that bone's, not forward
    /// kinematics'. `None` for every other bone.
    pub follows: Vec<Option<usize>>,
    /// Bone heads (where each bone rotates), metres, model frame.
    pub heads: Vec<Vector3<f64>>,
    /// Bone tails, metres, model frame.
    pub tails: Vec<Vector3<f64>>,
    /// Rest frames (columns: the bone's X, Y, Z axes in the model frame; Y along the bone).
    pub frames: Vec<UnitQuaternion<f64>>,
}

/// Model frame → Blender's axes (MakeHuman's rig files): `(x, y, z) ↦ (x, −z, y)`.
fn to_blender() -> Matrix3<f64> {
    Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0)
}

/// Blender's bone frame for unit direction `dir` and `roll` (both in Blender's axes).
fn vec_roll_to_mat3(dir: &Vector3<f64>, roll: f64) -> Matrix3<f64> {
    let y = Vector3::y();
    let swing = Rotation3::rotation_between(&y, dir)
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI));
    let twist = Rotation3::from_axis_angle(&Unit::new_normalize(*dir), roll);
    (twist * swing).into_inner()
}

/// The rest frame of a bone from its head, tail (model frame) and MakeHuman roll.
pub fn bone_frame(head: &Vector3<f64>, tail: &Vector3<f64>, roll: f64) -> Result<UnitQuaternion<f64>> {
    let d = tail - head;
    let len = d.norm();
    if !(len >= MIN_RIG_BONE_LENGTH) {
        return Err(Error::Degenerate(format!("a rig bone has length {len:e} m")));
    }
    let p = to_blender();
    // The bone's axes in Blender's coordinates, then each axis expressed in the model frame.
    let frame = p.transpose() * vec_roll_to_mat3(&(p * d / len), roll);
    Ok(UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(frame)))
}

impl Armature {
    /// The armature of a body from the stored rig (`rig`, see [`RigData`]): heads and tails
    /// evaluated on the body's canonical `joints` and rest `vertices` (metres, model frame);
    /// the root's head is dropped to the body's lowest vertex (the floor between the ankles) and
    /// its tail put [`ROOT_LENGTH`] in front of it. Errors: a degenerate bone
    /// ([`Error::Degenerate`]), an invalid rig ([`RigData::validate`]).
    pub fn rest(rig: &RigData, joints: &Joints3, vertices: &[[f32; 3]]) -> Result<Armature> {
        rig.validate(vertices.len())?;
        let mut heads: Vec<Vector3<f64>> = rig.heads.iter().map(|r| Vector3::from(r.eval(joints, vertices))).collect();
        let mut tails: Vec<Vector3<f64>> = rig.tails.iter().map(|r| Vector3::from(r.eval(joints, vertices))).collect();
        let floor = vertices.iter().map(|v| v[1] as f64).fold(f64::INFINITY, f64::min);
        heads[0].y = floor;
        tails[0] = heads[0] + Vector3::new(0.0, 0.0, ROOT_LENGTH);
        let frames = (0..NUM_RIG_BONES)
            .map(|b| bone_frame(&heads[b], &tails[b], rig.rolls[b] as f64))
            .collect::<Result<Vec<_>>>()?;
        let parents = RIG_BONES.iter().map(|b| b.parent).collect();
        Ok(Armature { parents, follows: vec![None; NUM_RIG_BONES], heads, tails, frames })
    }

    /// Number of bones.
    pub fn len(&self) -> usize {
        self.parents.len()
    }

    /// True for an armature without bones.
    pub fn is_empty(&self) -> bool {
        self.parents.is_empty()
    }

    /// Every point moved by `offset` (metres).
    pub fn translated(&self, offset: &Vector3<f64>) -> Armature {
        Armature {
            parents: self.parents.clone(),
            follows: self.follows.clone(),
            heads: self.heads.iter().map(|h| h + offset).collect(),
            tails: self.tails.iter().map(|t| t + offset).collect(),
            frames: self.frames.clone(),
        }
    }
}

/// A pose of the production armature: per bone the global rotation rest → posed (model frame)
/// and the root's translation. Posed heads follow by forward kinematics (rotations only below
/// the root, so bone lengths are the rest's).
#[derive(Clone, Debug, PartialEq)]
pub struct RigPose {
    /// Global rotation of each bone, rest → posed.
    pub rotations: Vec<UnitQuaternion<f64>>,
    /// Translation of the root (posed root head − rest root head), metres.
    pub root_translation: Vector3<f64>,
}

impl RigPose {
    /// The rest pose of an armature of `bones` bones.
    pub fn rest(bones: usize) -> RigPose {
        RigPose { rotations: vec![UnitQuaternion::identity(); bones], root_translation: Vector3::zeros() }
    }

    /// The production pose driven by a canonical IK pose (made from the same body's rest
    /// joints): each bone takes its [`Driver`]'s rotation; the spine slerps from the pelvis frame
    /// to the torso bone's rotation. The root does not move (see [`RigPose::grounded`]).
    pub fn from_canonical(pose: &Pose) -> RigPose {
        let rotations = RIG_BONES
            .iter()
            .map(|b| match b.driver {
                Driver::Fixed => UnitQuaternion::identity(),
                Driver::Pelvis => pose.root,
                Driver::Spine(f) => pose.root.slerp(&pose.rotations[7], f),
                Driver::Bone(k) => pose.rotations[k],
            })
            .collect();
        RigPose { rotations, root_translation: Vector3::zeros() }
    }

    /// MakeHuman's local pose (`angles`: per bone Euler XYZ radians in its own rest frame, as in
    /// MPFB's pose files) as global rotations: `G_b = G_parent F_parentᵀ F_b R_b`, `Q_b = G_b F_bᵀ`.
    pub fn from_local_eulers(armature: &Armature, angles: &[[f32; 3]]) -> RigPose {
        let mut global: Vec<UnitQuaternion<f64>> = Vec::with_capacity(NUM_RIG_BONES);
        let mut rotations = Vec::with_capacity(NUM_RIG_BONES);
        for (b, bone) in RIG_BONES.iter().enumerate() {
            let e = angles.get(b).copied().unwrap_or([0.0; 3]).map(|a| a as f64);
            let local = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), e[2])
                * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), e[1])
                * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), e[0]);
            let f = armature.frames[b];
            let g = match bone.parent {
                None => f * local,
                Some(p) => global[p] * armature.frames[p].inverse() * f * local,
            };
            rotations.push(g * f.inverse());
            global.push(g);
        }
        RigPose { rotations, root_translation: Vector3::zeros() }
    }

    /// Posed bone heads by forward kinematics from `armature`'s rest heads.
    pub fn heads(&self, armature: &Armature) -> Vec<Vector3<f64>> {
        let mut out: Vec<Vector3<f64>> = Vec::with_capacity(armature.len());
        for (b, parent) in armature.parents.iter().enumerate() {
            let h = match (armature.follows[b], *parent) {
                (Some(f), _) => out[f],
                (None, None) => armature.heads[b] + self.root_translation,
                (None, Some(p)) => out[p] + self.rotations[p] * (armature.heads[b] - armature.heads[p]),
            };
            out.push(h);
        }
        out
    }

    /// The armature in this pose, as a new rest armature (heads and tails moved, frames turned).
    pub fn posed_armature(&self, armature: &Armature) -> Armature {
        let heads = self.heads(armature);
        let n = armature.len();
        let tails = (0..n).map(|b| heads[b] + self.rotations[b] * (armature.tails[b] - armature.heads[b]));
        Armature {
            parents: armature.parents.clone(),
            follows: armature.follows.clone(),
            tails: tails.collect(),
            frames: (0..n).map(|b| self.rotations[b] * armature.frames[b]).collect(),
            heads,
        }
    }

    /// Linear blend skinning of rest `vertices` with the rig's `skin` weights: each bone moves a
    /// point `x` to `h'_b + Q_b (x − h_b)`. Errors: a weight list of the wrong length or a bone
    /// index beyond the armature's ([`Error::OutOfRange`]).
    pub fn skin(&self, armature: &Armature, vertices: &[[f32; 3]], skin: &[VertexWeights]) -> Result<Vec<[f32; 3]>> {
        if skin.len() != vertices.len() {
            return Err(Error::OutOfRange {
                name: "rig skin weights",
                detail: format!("{} entries for {} vertices", skin.len(), vertices.len()),
            });
        }
        let heads = self.heads(armature);
        let mats: Vec<Matrix3<f64>> = self.rotations.iter().map(|q| q.to_rotation_matrix().into_inner()).collect();
        vertices
            .iter()
            .zip(skin)
            .map(|(v, w)| {
                let x = Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                let mut p = Vector3::zeros();
                for (&b, &wt) in w.bones.iter().zip(&w.weights) {
                    let b = b as usize;
                    if wt == 0.0 {
                        continue;
                    }
                    if b >= mats.len() {
                        return Err(Error::OutOfRange { name: "rig bone", detail: format!("{b} >= {}", mats.len()) });
                    }
                    p += (heads[b] + mats[b] * (x - armature.heads[b])) * wt as f64;
                }
                Ok([p.x as f32, p.y as f32, p.z as f32])
            })
            .collect()
    }

    /// The canonical joints carried by this pose: each joint moves rigidly with the bone whose
    /// head sits on it ([`CANONICAL_CARRIER`]; the head joint rides on the head bone).
    pub fn canonical_joints(&self, armature: &Armature, joints: &Joints3) -> Joints3 {
        let heads = self.heads(armature);
        let mut out = *joints;
        for j in 0..NUM_JOINTS {
            let b = CANONICAL_CARRIER[j];
            let p = heads[b] + self.rotations[b] * (Vector3::from(joints[j]) - armature.heads[b]);
            out[j] = p.into();
        }
        out
    }

    /// This pose relative to another rest: when the body's rest is `base` posed by `rest`, the
    /// rotations taking that new rest to this pose (`Q_b · Q_rest,bᵀ`).
    pub fn relative_to(&self, rest: &RigPose) -> RigPose {
        RigPose {
            rotations: self.rotations.iter().zip(&rest.rotations).map(|(q, r)| q * r.inverse()).collect(),
            root_translation: self.root_translation - rest.root_translation,
        }
    }

    /// Each bone's rotation relative to its parent in the local frames of `armature`
    /// (`(G_parent)⁻¹ G_b` with `G = Q F`; the root's relative to the model frame): the values a
    /// DCC shows as the pose bones' rotations.
    pub fn local_rotations(&self, armature: &Armature) -> Vec<UnitQuaternion<f64>> {
        let g: Vec<UnitQuaternion<f64>> = (0..armature.len()).map(|b| self.rotations[b] * armature.frames[b]).collect();
        armature
            .parents
            .iter()
            .enumerate()
            .map(|(b, parent)| match *parent {
                None => g[b],
                Some(p) => g[p].inverse() * g[b],
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::rig::RiggedMesh;
    use crate::body::{BodyModel, Gender};
    use crate::skeleton::JOINT_NAMES;

    fn mean_body() -> (BodyModel, RiggedMesh) {
        let model = BodyModel::embedded().unwrap();
        let mesh = RiggedMesh::from_model(&model, Gender::Female, &[]).unwrap();
        (model, mesh)
    }

    /// Frames have Y along the bone; canonical-joint heads are the joints themselves; the
    /// root is on the floor.
    #[test]
    fn rest_armature_follows_the_body() {
        let (model, mesh) = mean_body();
        let arm = Armature::rest(model.rig(), &mesh.joints, &mesh.vertices).unwrap();
        for b in 0..NUM_RIG_BONES {
            let d = (arm.tails[b] - arm.heads[b]).normalize();
            assert!((arm.frames[b] * Vector3::y() - d).norm() < 1e-9, "{}", RIG_BONES[b].makehuman);
        }
        for (j, &c) in CANONICAL_CARRIER.iter().enumerate() {
            if j != crate::skeleton::joint::HEAD {
                assert!((arm.heads[c] - Vector3::from(mesh.joints[j])).norm() < 1e-6, "{}", JOINT_NAMES[j]);
            }
        }
        let low = mesh.vertices.iter().map(|v| v[1] as f64).fold(f64::INFINITY, f64::min);
        assert_eq!(arm.heads[0].y, low);
        // Elbow hinge: MakeHuman's roll puts the forearm's bend axis (X) across the arm, roughly
        // horizontal-forward in the A-pose rather than along the body's up axis.
        let spine = arm.heads[4] - arm.heads[1];
        assert!(spine.y > 0.2 && spine.x.abs() < 0.02, "{spine:?}");
    }

    /// MakeHuman's T-pose brings the upper arms and forearms close to horizontal.
    #[test]
    fn tpose_makes_the_arms_horizontal() {
        let (model, mesh) = mean_body();
        let arm = Armature::rest(model.rig(), &mesh.joints, &mesh.vertices).unwrap();
        let t = RigPose::from_local_eulers(&arm, &model.rig().tpose);
        let posed = t.posed_armature(&arm);
        for b in [8, 9, 27, 28] {
            let d = (posed.tails[b] - posed.heads[b]).normalize();
            let a0 = (arm.tails[b] - arm.heads[b]).normalize();
            assert!(d.y.abs() < 0.12, "{} {d:?} (rest {a0:?})", RIG_BONES[b].makehuman);
        }
        let v = t.skin(&arm, &mesh.vertices, &model.rig().skin).unwrap();
        assert_eq!(v.len(), mesh.vertices.len());
    }
}

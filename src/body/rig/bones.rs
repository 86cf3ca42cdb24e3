//! The production skeleton's bone table: MakeHuman's `game_engine` rig (53 bones, MPFB2, CC0),
//! in an order where every parent comes before its children, with the project's, Mixamo's and
//! the Unreal-style name of each bone and the canonical rotation that drives it.

use crate::skeleton::{joint, NUM_JOINTS};

/// Number of production bones (MakeHuman's `game_engine` rig).
pub const NUM_RIG_BONES: usize = 53;

/// Where a production bone's posed rotation comes from (the 15 canonical joints drive the rig).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Driver {
    /// The root at the floor: never rotates, carries the body's translation.
    Fixed,
    /// The pelvis frame of the canonical pose ([`crate::body::ik::Pose::root`]).
    Pelvis,
    /// The spine chain: the pelvis frame slerped toward the canonical torso bone's rotation
    /// (bone 7, pelvis → neck) by this fraction.
    Spine(f64),
    /// The global rotation of canonical bone `b` ([`crate::skeleton::BONES`]); hands and
    /// fingers ride on the forearms, feet and toes on the shins.
    Bone(usize),
}

/// One production bone.
#[derive(Clone, Copy, Debug)]
pub struct RigBone {
    /// MakeHuman's `game_engine` name (the Unreal-style name; `Root` is Unreal's `root`).
    pub makehuman: &'static str,
    /// The project's name: the joint the bone starts at (canonical names where they coincide).
    pub project: &'static str,
    /// Mixamo's name (`mixamorig:` prefix added by [`super::Naming`]).
    pub mixamo: &'static str,
    /// Index of the parent bone in [`RIG_BONES`] (`None` for the root).
    pub parent: Option<usize>,
    /// What rotates it.
    pub driver: Driver,
}

const fn b(
    makehuman: &'static str,
    project: &'static str,
    mixamo: &'static str,
    parent: usize,
    driver: Driver,
) -> RigBone {
    RigBone { makehuman, project, mixamo, parent: Some(parent), driver }
}

use Driver::{Bone, Pelvis, Spine};

/// The 53 bones, parents first. Indices 7–25 are the right arm, 26–44 the left arm, 45–48 the
/// right leg, 49–52 the left leg.
pub const RIG_BONES: [RigBone; NUM_RIG_BONES] = [
    RigBone { makehuman: "Root", project: "root", mixamo: "Root", parent: None, driver: Driver::Fixed },
    b("pelvis", "pelvis", "Hips", 0, Pelvis),
    b("spine_01", "spine", "Spine", 1, Spine(1.0 / 3.0)),
    b("spine_02", "chest", "Spine1", 2, Spine(2.0 / 3.0)),
    b("spine_03", "upper_chest", "Spine2", 3, Spine(1.0)),
    b("neck_01", "neck", "Neck", 4, Bone(0)),
    b("head", "head", "Head", 5, Bone(0)),
    // Right arm (7..=25).
    b("clavicle_r", "r_clavicle", "RightShoulder", 4, Bone(1)),
    b("upperarm_r", "r_shoulder", "RightArm", 7, Bone(2)),
    b("lowerarm_r", "r_elbow", "RightForeArm", 8, Bone(3)),
    b("hand_r", "r_wrist", "RightHand", 9, Bone(3)),
    b("thumb_01_r", "r_thumb_1", "RightHandThumb1", 10, Bone(3)),
    b("thumb_02_r", "r_thumb_2", "RightHandThumb2", 11, Bone(3)),
    b("thumb_03_r", "r_thumb_3", "RightHandThumb3", 12, Bone(3)),
    b("index_01_r", "r_index_1", "RightHandIndex1", 10, Bone(3)),
    b("index_02_r", "r_index_2", "RightHandIndex2", 14, Bone(3)),
    b("index_03_r", "r_index_3", "RightHandIndex3", 15, Bone(3)),
    b("middle_01_r", "r_middle_1", "RightHandMiddle1", 10, Bone(3)),
    b("middle_02_r", "r_middle_2", "RightHandMiddle2", 17, Bone(3)),
    b("middle_03_r", "r_middle_3", "RightHandMiddle3", 18, Bone(3)),
    b("ring_01_r", "r_ring_1", "RightHandRing1", 10, Bone(3)),
    b("ring_02_r", "r_ring_2", "RightHandRing2", 20, Bone(3)),
    b("ring_03_r", "r_ring_3", "RightHandRing3", 21, Bone(3)),
    b("pinky_01_r", "r_pinky_1", "RightHandPinky1", 10, Bone(3)),
    b("pinky_02_r", "r_pinky_2", "RightHandPinky2", 23, Bone(3)),
    b("pinky_03_r", "r_pinky_3", "RightHandPinky3", 24, Bone(3)),
    // Left arm (26..=44).
    b("clavicle_l", "l_clavicle", "LeftShoulder", 4, Bone(4)),
    b("upperarm_l", "l_shoulder", "LeftArm", 26, Bone(5)),
    b("lowerarm_l", "l_elbow", "LeftForeArm", 27, Bone(6)),
    b("hand_l", "l_wrist", "LeftHand", 28, Bone(6)),
    b("thumb_01_l", "l_thumb_1", "LeftHandThumb1", 29, Bone(6)),
    b("thumb_02_l", "l_thumb_2", "LeftHandThumb2", 30, Bone(6)),
    b("thumb_03_l", "l_thumb_3", "LeftHandThumb3", 31, Bone(6)),
    b("index_01_l", "l_index_1", "LeftHandIndex1", 29, Bone(6)),
    b("index_02_l", "l_index_2", "LeftHandIndex2", 33, Bone(6)),
    b("index_03_l", "l_index_3", "LeftHandIndex3", 34, Bone(6)),
    b("middle_01_l", "l_middle_1", "LeftHandMiddle1", 29, Bone(6)),
    b("middle_02_l", "l_middle_2", "LeftHandMiddle2", 36, Bone(6)),
    b("middle_03_l", "l_middle_3", "LeftHandMiddle3", 37, Bone(6)),
    b("ring_01_l", "l_ring_1", "LeftHandRing1", 29, Bone(6)),
    b("ring_02_l", "l_ring_2", "LeftHandRing2", 39, Bone(6)),
    b("ring_03_l", "l_ring_3", "LeftHandRing3", 40, Bone(6)),
    b("pinky_01_l", "l_pinky_1", "LeftHandPinky1", 29, Bone(6)),
    b("pinky_02_l", "l_pinky_2", "LeftHandPinky2", 42, Bone(6)),
    b("pinky_03_l", "l_pinky_3", "LeftHandPinky3", 43, Bone(6)),
    // Legs (45..=52).
    b("thigh_r", "r_hip", "RightUpLeg", 1, Bone(9)),
    b("calf_r", "r_knee", "RightLeg", 45, Bone(10)),
    b("foot_r", "r_ankle", "RightFoot", 46, Bone(10)),
    b("ball_r", "r_ball", "RightToeBase", 47, Bone(10)),
    b("thigh_l", "l_hip", "LeftUpLeg", 1, Bone(12)),
    b("calf_l", "l_knee", "LeftLeg", 49, Bone(13)),
    b("foot_l", "l_ankle", "LeftFoot", 50, Bone(13)),
    b("ball_l", "l_ball", "LeftToeBase", 51, Bone(13)),
];

/// Bone index by MakeHuman (`game_engine`) name.
pub fn bone_by_makehuman_name(name: &str) -> Option<usize> {
    RIG_BONES.iter().position(|b| b.makehuman == name)
}

/// MakeHuman joint cubes that are canonical joints: a bone end on one of these uses the
/// canonical joint itself, so the 15 canonical joints place the rig exactly where they are.
pub const CANONICAL_CUBES: [(&str, usize); 13] = [
    ("joint-pelvis", joint::PELVIS),
    ("joint-neck", joint::NECK),
    ("joint-r-shoulder", joint::R_SHOULDER),
    ("joint-r-elbow", joint::R_ELBOW),
    ("joint-r-hand", joint::R_WRIST),
    ("joint-l-shoulder", joint::L_SHOULDER),
    ("joint-l-elbow", joint::L_ELBOW),
    ("joint-l-hand", joint::L_WRIST),
    ("joint-r-upper-leg", joint::R_HIP),
    ("joint-r-knee", joint::R_KNEE),
    ("joint-r-ankle", joint::R_ANKLE),
    ("joint-l-upper-leg", joint::L_HIP),
    ("joint-l-knee", joint::L_KNEE),
];

/// The canonical joint a cube stands for ([`CANONICAL_CUBES`] plus the left ankle).
pub fn canonical_joint_of_cube(cube: &str) -> Option<usize> {
    if cube == "joint-l-ankle" {
        return Some(joint::L_ANKLE);
    }
    CANONICAL_CUBES.iter().find(|c| c.0 == cube).map(|c| c.1)
}

/// For each canonical joint, the production bone whose head sits on it and that carries it
/// when the rig is posed (the head joint, between the skull base and the crown, rides on the
/// head bone).
pub const CANONICAL_CARRIER: [usize; NUM_JOINTS] = [6, 5, 8, 9, 10, 27, 28, 29, 1, 45, 46, 47, 49, 50, 51];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::JOINT_NAMES;

    #[test]
    fn parents_come_first_and_names_are_unique() {
        for (i, b) in RIG_BONES.iter().enumerate() {
            assert!(b.parent.map_or(i == 0, |p| p < i), "{}", b.makehuman);
            for other in &RIG_BONES[..i] {
                assert!(other.makehuman != b.makehuman && other.project != b.project && other.mixamo != b.mixamo);
            }
        }
        // The bones carrying canonical joints bear the canonical names.
        for (j, &c) in CANONICAL_CARRIER.iter().enumerate() {
            assert_eq!(RIG_BONES[c].project, JOINT_NAMES[j]);
        }
    }
}

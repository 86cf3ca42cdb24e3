//! The canonical 15-joint skeleton shared by every stage (docs/design.md, "Canonical joints").
//! "r" is the character's own right. 3-D joints are metres in the model frame (+Y up, +Z toward
//! the viewer); 2-D joints are image pixels (origin top-left, y down).

/// Number of canonical joints (the paper's P).
pub const NUM_JOINTS: usize = 15;
/// Number of bones.
pub const NUM_BONES: usize = 14;

/// Canonical joint indices.
pub mod joint {
    /// Index of the top of the head.
    pub const HEAD: usize = 0;
    /// Index of the base of the neck.
    pub const NECK: usize = 1;
    /// Index of the character's right shoulder.
    pub const R_SHOULDER: usize = 2;
    /// Index of the right elbow.
    pub const R_ELBOW: usize = 3;
    /// Index of the right wrist.
    pub const R_WRIST: usize = 4;
    /// Index of the character's left shoulder.
    pub const L_SHOULDER: usize = 5;
    /// Index of the left elbow.
    pub const L_ELBOW: usize = 6;
    /// Index of the left wrist.
    pub const L_WRIST: usize = 7;
    /// Index of the pelvis (root).
    pub const PELVIS: usize = 8;
    /// Index of the right hip.
    pub const R_HIP: usize = 9;
    /// Index of the right knee.
    pub const R_KNEE: usize = 10;
    /// Index of the right ankle.
    pub const R_ANKLE: usize = 11;
    /// Index of the left hip.
    pub const L_HIP: usize = 12;
    /// Index of the left knee.
    pub const L_KNEE: usize = 13;
    /// Index of the left ankle.
    pub const L_ANKLE: usize = 14;
}

/// Joint names in canonical order (also the JSON keys of the joint files).
pub const JOINT_NAMES: [&str; NUM_JOINTS] = [
    "head",
    "neck",
    "r_shoulder",
    "r_elbow",
    "r_wrist",
    "l_shoulder",
    "l_elbow",
    "l_wrist",
    "pelvis",
    "r_hip",
    "r_knee",
    "r_ankle",
    "l_hip",
    "l_knee",
    "l_ankle",
];

/// The 14 bones as (parent joint, child joint), in docs/design.md's order. Bone `b` ends at joint
/// `BONES[b].1`; the hierarchy is rooted at the pelvis.
pub const BONES: [(usize, usize); NUM_BONES] = [
    (1, 0),   // neck -> head
    (1, 2),   // neck -> r_shoulder
    (2, 3),   // r_shoulder -> r_elbow
    (3, 4),   // r_elbow -> r_wrist
    (1, 5),   // neck -> l_shoulder
    (5, 6),   // l_shoulder -> l_elbow
    (6, 7),   // l_elbow -> l_wrist
    (8, 1),   // pelvis -> neck
    (8, 9),   // pelvis -> r_hip
    (9, 10),  // r_hip -> r_knee
    (10, 11), // r_knee -> r_ankle
    (8, 12),  // pelvis -> l_hip
    (12, 13), // l_hip -> l_knee
    (13, 14), // l_knee -> l_ankle
];

/// The limb bones: right and left upper arm, forearm, thigh and shin (indices into [`BONES`]).
pub const LIMB_BONES: [usize; 8] = [2, 3, 5, 6, 9, 10, 12, 13];

/// Parent of each joint in the hierarchy (`None` for the pelvis, the root).
pub const PARENT: [Option<usize>; NUM_JOINTS] = [
    Some(1),
    Some(8),
    Some(1),
    Some(2),
    Some(3),
    Some(1),
    Some(5),
    Some(6),
    None,
    Some(8),
    Some(9),
    Some(10),
    Some(8),
    Some(12),
    Some(13),
];

/// Left/right mirror of each joint (centre joints map to themselves).
pub const MIRROR: [usize; NUM_JOINTS] = [0, 1, 5, 6, 7, 2, 3, 4, 8, 12, 13, 14, 9, 10, 11];

/// Index of a joint by its canonical name.
pub fn joint_index(name: &str) -> Option<usize> {
    JOINT_NAMES.iter().position(|&n| n == name)
}

/// 15 joints in 3-D, metres, model frame.
pub type Joints3 = [[f64; 3]; NUM_JOINTS];

/// 15 joints in an image: pixel positions and whether each is visible/known. Invisible joints
/// keep a position (a guess) but stages may drop their residuals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joints2 {
    /// (x, y) in pixels, image frame.
    pub xy: [[f64; 2]; NUM_JOINTS],
    /// `true` where the joint is known.
    pub visible: [bool; NUM_JOINTS],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_are_consistent() {
        for (b, &(p, c)) in BONES.iter().enumerate() {
            assert_eq!(PARENT[c], Some(p), "bone {b}");
        }
        assert_eq!(PARENT.iter().filter(|p| p.is_none()).count(), 1);
        for j in 0..NUM_JOINTS {
            assert_eq!(MIRROR[MIRROR[j]], j);
            let (a, b) = (JOINT_NAMES[j], JOINT_NAMES[MIRROR[j]]);
            assert_eq!(a.replace("r_", "l_").replace("l_", "x_"), b.replace("r_", "l_").replace("l_", "x_"));
        }
        assert_eq!(joint_index("l_knee"), Some(joint::L_KNEE));
    }
}

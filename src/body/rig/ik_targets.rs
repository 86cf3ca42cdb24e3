//! IK target bones (issue 49, optional): non-deforming helper bones at the hands and feet under
//! two roots at the floor, Unreal's mannequin hierarchy (`root` → `ik_foot_root` → `ik_foot_r`,
//! `ik_foot_l`; `root` → `ik_hand_root` → `ik_hand_gun` → `ik_hand_r`, `ik_hand_l`), so an
//! engine's or a DCC's IK can aim at them. Each target has the rest frame of the bone it sits on
//! (`hand_r`, `foot_l`, …; `ik_hand_gun` on the right hand) and follows it in every pose: its
//! head is that bone's head, its rotation that bone's; the two roots stay with the root. No
//! vertex is bound to them.

use super::armature::Armature;
use super::bones::NUM_RIG_BONES;

/// One IK target bone.
#[derive(Clone, Copy, Debug)]
pub struct IkBone {
    /// Unreal's name (the UE4 mannequin's).
    pub unreal: &'static str,
    /// The project's name.
    pub project: &'static str,
    /// Mixamo-style name (`mixamorig:` prefix added by [`super::Naming`]).
    pub mixamo: &'static str,
    /// Its parent: `None` for the root bone (index 0), else an index into [`IK_BONES`].
    pub parent: Option<usize>,
    /// The bone it sits on and follows (an index into [`super::RIG_BONES`]).
    pub follows: usize,
}

/// Number of IK target bones.
pub const NUM_IK_BONES: usize = 7;

const fn ik(
    unreal: &'static str,
    project: &'static str,
    mixamo: &'static str,
    parent: Option<usize>,
    follows: usize,
) -> IkBone {
    IkBone { unreal, project, mixamo, parent, follows }
}

/// The IK target bones, parents first, in the order an export appends them after the other
/// bones.
pub const IK_BONES: [IkBone; NUM_IK_BONES] = [
    ik("ik_foot_root", "ik_foot_root", "IKFootRoot", None, 0),
    ik("ik_foot_r", "r_ik_foot", "RightFootIK", Some(0), 47),
    ik("ik_foot_l", "l_ik_foot", "LeftFootIK", Some(0), 51),
    ik("ik_hand_root", "ik_hand_root", "IKHandRoot", None, 0),
    ik("ik_hand_gun", "ik_hand_gun", "IKHandGun", Some(3), 10),
    ik("ik_hand_r", "r_ik_hand", "RightHandIK", Some(4), 10),
    ik("ik_hand_l", "l_ik_hand", "LeftHandIK", Some(4), 29),
];

/// `armature` with the IK target bones appended (after whatever it holds), each a copy of the
/// bone it follows (head, tail, frame) that follows it in every pose
/// ([`Armature::follows`]).
pub fn with_ik_targets(armature: &Armature) -> Armature {
    let mut out = armature.clone();
    let base = armature.len();
    for bone in &IK_BONES {
        let f = bone.follows;
        debug_assert!(f < NUM_RIG_BONES);
        out.parents.push(Some(bone.parent.map_or(0, |p| base + p)));
        out.follows.push(Some(f));
        out.heads.push(armature.heads[f]);
        out.tails.push(armature.tails[f]);
        out.frames.push(armature.frames[f]);
    }
    out
}

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

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Translation3};
    use rand::SeedableRng;

    use super::*;
    use crate::body::ik::{solve, IkOptions};
    use crate::body::procedural::random_pose;
    use crate::body::rig::{Naming, RigOptions, RigScene, RiggedMesh};
    use crate::body::{BodyModel, Gender};
    use crate::export::rigged::posed_locals;

    /// The local transforms every writer takes ([`posed_locals`]), composed down the tree, stand
    /// each IK target exactly where the bone it follows is (head and frame), in a random pose,
    /// with twist bones before them; the targets are named and parented as documented.
    #[test]
    fn targets_stand_on_their_bones_in_the_pose() {
        let model = BodyModel::embedded().unwrap();
        let mesh = RiggedMesh::from_model(&model, Gender::Male, &[]).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
        let pose = solve(&mesh.joints, &random_pose(&mesh.joints, &mut rng, 0.0), &IkOptions::default()).unwrap();
        let options =
            RigOptions { naming: Naming::Unreal, twist_bones: true, ik_targets: true, ..RigOptions::default() };
        let scene = RigScene::build(model.rig(), &mesh, &pose, &options).unwrap();
        let arm = &scene.armature;
        let base = arm.len() - NUM_IK_BONES;
        assert_eq!(
            scene.names[base..],
            ["ik_foot_root", "ik_foot_r", "ik_foot_l", "ik_hand_root", "ik_hand_gun", "ik_hand_r", "ik_hand_l"]
        );
        assert_eq!(arm.parents[base + 6], Some(base + 4));
        assert_eq!(arm.parents[base], Some(0));
        let mut global: Vec<Isometry3<f64>> = Vec::with_capacity(arm.len());
        for (b, (t, q)) in posed_locals(&scene).into_iter().enumerate() {
            let local = Isometry3::from_parts(Translation3::from(t), q);
            global.push(arm.parents[b].map_or(local, |p| global[p] * local));
        }
        for (k, bone) in IK_BONES.iter().enumerate() {
            let (g, f) = (global[base + k], global[bone.follows]);
            let gap = (g.translation.vector - f.translation.vector).norm();
            assert!(gap < 1e-9 && g.rotation.angle_to(&f.rotation) < 1e-9, "{}: {gap} m", scene.names[base + k]);
        }
        // The hand moved: the targets are not left at the rest.
        let hand = global[IK_BONES[5].follows].translation.vector;
        assert!((hand - arm.heads[IK_BONES[5].follows]).norm() > 0.05);
    }
}

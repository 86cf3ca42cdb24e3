//! Twist bones (issue 49): one bone at the middle of each upper arm, forearm and thigh, a child
//! of its limb bone with the limb's rest frame (its +Y along the limb), taking over the part of
//! the limb's skin nearest the end that twists, so that a twist spreads along the segment
//! instead of collapsing the skin where two bones blend (linear blend skinning's "candy
//! wrapper").
//!
//! The convention an animator (or a constraint) follows: an upper-arm or thigh twist bone turns
//! back half of its limb bone's twist about the limb (local rotation −θ/2 about +Y when the
//! limb turns θ about its own axis), so the skin goes from the parent's twist at the shoulder or
//! hip through θ/2 at mid-segment to θ at the elbow or knee; a forearm twist bone takes half of
//! the hand's twist about the forearm (+θ/2 when the hand turns θ). In the pose an export
//! writes, a twist bone follows its limb (local rotation the identity), so the posed body is
//! exactly the one without twist bones.

use nalgebra::Vector3;

use crate::body::VertexWeights;

use super::armature::Armature;
use super::bones::NUM_RIG_BONES;

/// Which end of its segment a twist bone shares the twist of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TwistEnd {
    /// The proximal end (shoulder, hip): the limb twists against its parent; the twist bone
    /// carries the proximal half of the limb's skin.
    Proximal,
    /// The distal end (wrist): the hand twists against the forearm; the twist bone carries the
    /// distal half.
    Distal,
}

/// One twist bone.
#[derive(Clone, Copy, Debug)]
pub struct TwistBone {
    /// Unreal's name (the UE4 mannequin's).
    pub unreal: &'static str,
    /// The project's name.
    pub project: &'static str,
    /// Mixamo-style name (`mixamorig:` prefix added by [`super::Naming`]; Mixamo's own rig has
    /// no twist bones).
    pub mixamo: &'static str,
    /// Its limb bone (parent), an index into [`super::RIG_BONES`].
    pub limb: usize,
    /// The end whose twist it shares.
    pub end: TwistEnd,
}

const fn t(unreal: &'static str, project: &'static str, mixamo: &'static str, limb: usize, end: TwistEnd) -> TwistBone {
    TwistBone { unreal, project, mixamo, limb, end }
}

/// Number of twist bones.
pub const NUM_TWIST_BONES: usize = 6;

/// The twist bones, in the order an export appends them after the 53 bones.
pub const TWIST_BONES: [TwistBone; NUM_TWIST_BONES] = [
    t("upperarm_twist_01_r", "r_upper_arm_twist", "RightArmTwist", 8, TwistEnd::Proximal),
    t("lowerarm_twist_01_r", "r_forearm_twist", "RightForeArmTwist", 9, TwistEnd::Distal),
    t("upperarm_twist_01_l", "l_upper_arm_twist", "LeftArmTwist", 27, TwistEnd::Proximal),
    t("lowerarm_twist_01_l", "l_forearm_twist", "LeftForeArmTwist", 28, TwistEnd::Distal),
    t("thigh_twist_01_r", "r_thigh_twist", "RightUpLegTwist", 45, TwistEnd::Proximal),
    t("thigh_twist_01_l", "l_thigh_twist", "LeftUpLegTwist", 49, TwistEnd::Proximal),
];

impl TwistBone {
    /// The share (0..=1) of the limb's weight this twist bone takes at parameter `t` along the
    /// limb (0 at its head, 1 at its tail): all of it over the half at its end, falling
    /// linearly to none at the other end.
    pub fn share(&self, t: f64) -> f64 {
        match self.end {
            TwistEnd::Proximal => (2.0 * (1.0 - t)).clamp(0.0, 1.0),
            TwistEnd::Distal => (2.0 * t).clamp(0.0, 1.0),
        }
    }
}

/// Parameter of `x` along the segment `head` → `tail` (0 at the head, 1 at the tail; not clamped).
pub fn along(head: &Vector3<f64>, tail: &Vector3<f64>, x: &Vector3<f64>) -> f64 {
    let d = tail - head;
    (x - head).dot(&d) / d.norm_squared()
}

/// `armature` (MakeHuman's 53 bones) with the twist bones appended: each at the middle of its
/// limb (head at the limb's midpoint, tail at the limb's tail) with the limb's rest frame.
pub fn with_twist_bones(armature: &Armature) -> Armature {
    let mut out = armature.clone();
    for tb in &TWIST_BONES {
        let (h, t) = (armature.heads[tb.limb], armature.tails[tb.limb]);
        out.parents.push(Some(tb.limb));
        out.follows.push(None);
        out.heads.push(h + 0.5 * (t - h));
        out.tails.push(t);
        out.frames.push(armature.frames[tb.limb]);
    }
    out
}

/// The skin weights with each limb's weight shared with its twist bone (twist bone `k` is bone
/// `53 + k`) by [`TwistBone::share`] of the vertex's rest position `vertices` along the limb of
/// `armature`. A vertex whose four influences are all in use gives its smallest other
/// influence's slot to the twist bone and is renormalised.
pub fn split_weights(armature: &Armature, vertices: &[[f32; 3]], skin: &[VertexWeights]) -> Vec<VertexWeights> {
    skin.iter()
        .zip(vertices)
        .map(|(w, v)| {
            let x = Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64);
            let mut w = *w;
            let mut dropped = false;
            for (k, tb) in TWIST_BONES.iter().enumerate() {
                let Some(slot) = (0..w.bones.len()).find(|&s| w.bones[s] as usize == tb.limb && w.weights[s] > 0.0)
                else {
                    continue;
                };
                let share = tb.share(along(&armature.heads[tb.limb], &armature.tails[tb.limb], &x)) as f32;
                let moved = w.weights[slot] * share;
                let twist = (NUM_RIG_BONES + k) as u8;
                if moved <= 0.0 {
                    continue;
                }
                if share >= 1.0 {
                    w.bones[slot] = twist;
                    continue;
                }
                let free = (0..w.bones.len()).find(|&s| w.weights[s] == 0.0).unwrap_or_else(|| {
                    dropped = true;
                    let others = (0..w.bones.len()).filter(|&s| s != slot);
                    others.min_by(|&a, &b| w.weights[a].total_cmp(&w.weights[b])).unwrap_or(slot)
                });
                w.weights[slot] -= moved;
                w.bones[free] = twist;
                w.weights[free] = moved;
            }
            if dropped {
                let sum: f32 = w.weights.iter().sum();
                w.weights.iter_mut().for_each(|x| *x /= sum);
            }
            sort_influences(&mut w);
            w
        })
        .collect()
}

/// Orders the influences by decreasing weight (unused slots, weight 0, last as bone 0).
fn sort_influences(w: &mut VertexWeights) {
    let mut pairs: Vec<(u8, f32)> = w.bones.iter().copied().zip(w.weights).collect();
    pairs.sort_by(|a, b| b.1.total_cmp(&a.1));
    for (k, (b, x)) in pairs.into_iter().enumerate() {
        w.bones[k] = if x > 0.0 { b } else { 0 };
        w.weights[k] = x;
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::UnitQuaternion;

    use super::*;
    use crate::body::ik::Pose;
    use crate::body::rig::{RigOptions, RigPose, RigScene, RiggedMesh};
    use crate::body::{BodyModel, Gender};

    /// Area of the convex hull of `points` (Andrew's monotone chain).
    fn hull_area(points: &mut [[f64; 2]]) -> f64 {
        points.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
        let cross =
            |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
        let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * points.len());
        for pass in 0..2 {
            let start = hull.len();
            let iter: Box<dyn Iterator<Item = &[f64; 2]>> =
                if pass == 0 { Box::new(points.iter()) } else { Box::new(points.iter().rev()) };
            for &p in iter {
                while hull.len() >= start + 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
                    hull.pop();
                }
                hull.push(p);
            }
            hull.pop();
        }
        let n = hull.len();
        (0..n).map(|i| cross([0.0, 0.0], hull[i], hull[(i + 1) % n])).sum::<f64>() / 2.0
    }

    /// The scene's rest with `twist` of `theta` radians applied the documented way: a
    /// proximal twist turns the limb and everything below it about the limb's axis, a distal
    /// one turns the limb's descendants only; the limb's twist bone (when the scene has one)
    /// turns by `theta / 2`.
    fn twisted(scene: &RigScene, twist: &TwistBone, theta: f64) -> Vec<[f32; 3]> {
        let arm = &scene.armature;
        let axis = nalgebra::Unit::new_normalize(arm.frames[twist.limb] * Vector3::y());
        let full = UnitQuaternion::from_axis_angle(&axis, theta);
        let mut pose = RigPose::rest(arm.len());
        let below = |b: usize| {
            let mut p = Some(b);
            while let Some(q) = p {
                if q == twist.limb {
                    return true;
                }
                p = arm.parents[q];
            }
            false
        };
        for b in 0..NUM_RIG_BONES {
            let moves = below(b) && (b != twist.limb || twist.end == TwistEnd::Proximal);
            if moves {
                pose.rotations[b] = full;
            }
        }
        for (k, tb) in TWIST_BONES.iter().enumerate() {
            if tb.limb == twist.limb && arm.len() > NUM_RIG_BONES + k {
                pose.rotations[NUM_RIG_BONES + k] = UnitQuaternion::from_axis_angle(&axis, theta / 2.0);
            }
        }
        pose.skin(arm, &scene.rest_vertices, &scene.skin).unwrap()
    }

    /// Cross-section area kept (posed hull area / rest hull area) at each station `t` along the
    /// limb (0, 0.1, … 1: its head to its tail), over the vertices bound to the limb with weight ≥ 0.2 in
    /// MakeHuman's skin and within ±0.05 of the station (the body's rings of vertices are about
    /// 0.1 apart along a limb).
    fn kept(scene: &RigScene, skin: &[VertexWeights], twist: &TwistBone, posed: &[[f32; 3]]) -> Vec<(f64, f64)> {
        let arm = &scene.armature;
        let (h, tl, f) = (arm.heads[twist.limb], arm.tails[twist.limb], arm.frames[twist.limb]);
        let (u, w) = (f * Vector3::x(), f * Vector3::z());
        let v3 = |p: &[f32; 3]| Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        let flat = |p: &[f32; 3]| {
            let d = v3(p) - h;
            [d.dot(&u), d.dot(&w)]
        };
        (0..=10)
            .map(|i| {
                let t0 = i as f64 / 10.0;
                let (mut rest, mut moved) = (Vec::new(), Vec::new());
                for (v, x) in scene.rest_vertices.iter().enumerate() {
                    let bound: f32 = skin[v].influences().filter(|&(b, _)| b == twist.limb).map(|(_, x)| x).sum();
                    if bound >= 0.2 && (along(&h, &tl, &v3(x)) - t0).abs() <= 0.05 {
                        rest.push(flat(x));
                        moved.push(flat(&posed[v]));
                    }
                }
                assert!(rest.len() >= 5, "station {t0}: {} vertices", rest.len());
                (t0, hull_area(&mut moved) / hull_area(&mut rest))
            })
            .collect()
    }

    /// The measurement of issue 49: each limb of the mean female body twisted by 90° about its
    /// axis, the cross-section area kept at stations along it, with plain linear blend skinning
    /// (MakeHuman's 53 bones) and with the twist bones; the goal is ≥ 85 % everywhere along the
    /// limb. Prints the figures (docs/benchmarks.md, "Twist bones").
    #[test]
    fn a_90_degree_twist_keeps_the_cross_section() {
        let model = BodyModel::embedded().unwrap();
        let mesh = RiggedMesh::from_model(&model, Gender::Female, &[]).unwrap();
        let pose = Pose::rest(&mesh.joints);
        let plain = RigScene::build(model.rig(), &mesh, &pose, &RigOptions::default()).unwrap();
        let options = RigOptions { twist_bones: true, ..RigOptions::default() };
        let twist = RigScene::build(model.rig(), &mesh, &pose, &options).unwrap();
        assert_eq!(twist.armature.len(), NUM_RIG_BONES + NUM_TWIST_BONES);
        // In the body's own pose the twist bones follow their limbs: the same posed body.
        let gap = twist
            .posed_vertices
            .iter()
            .zip(&plain.posed_vertices)
            .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0f32, f32::max))
            .fold(0.0f32, f32::max);
        assert!(gap < 1e-5, "{gap}");
        for w in &twist.skin {
            assert!((w.weights.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{w:?}");
        }
        let theta = std::f64::consts::FRAC_PI_2;
        let mut worst = 1.0f64;
        for tb in &TWIST_BONES {
            let before = kept(&plain, &plain.skin, tb, &twisted(&plain, tb, theta));
            let after = kept(&twist, &plain.skin, tb, &twisted(&twist, tb, theta));
            let min = |k: &[(f64, f64)]| k.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
            println!(
                "{}: 90° twist keeps {:.1} % (mid-segment {:.1} %) with twist bones, {:.1} % (mid {:.1} %) without; stations {:?}",
                tb.unreal,
                100.0 * min(&after),
                100.0 * after[5].1,
                100.0 * min(&before),
                100.0 * before[5].1,
                after.iter().map(|x| (1000.0 * x.1).round() / 10.0).collect::<Vec<_>>()
            );
            println!("  without: {:?}", before.iter().map(|x| (1000.0 * x.1).round() / 10.0).collect::<Vec<_>>());
            worst = worst.min(min(&after));
            assert!(min(&after) > min(&before), "{}: twist bones help", tb.unreal);
        }
        assert!(worst >= 0.85, "worst cross-section kept {worst}");
    }
}

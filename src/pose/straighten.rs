//! Straight limbs where the drawing shows them straight ([`super::PoseOptions::straight_limbs`]).
//!
//! Under weak perspective a limb (upper bone, lower bone) that is straight in 3-D is straight in
//! the image, and a drawn limb that is straight in the image is either straight in 3-D or bent
//! in a plane holding the viewing direction. The solver keeps the dictionary's bone lengths (per
//! group, [`super::figure`]), so a drawing whose thigh and shin (or upper arm and forearm) are
//! in other proportions than the dictionary's can only be explained by foreshortening: a knee
//! bent toward or away from the viewer. This step takes the other reading when the bend is at
//! most [`MAX_BEND_DEG`]: for each limb whose three joints are visible, whose middle joint lies within
//! [`MAX_OFFSET`] of the line through its ends in the image, and whose 3-D bend is at most the
//! option's angle, the middle joint moves onto the 3-D segment between the two end joints (their
//! positions kept), at the point whose image is the foot of the drawn middle joint on the image
//! line. The image of the end joints is unchanged and the middle joint's moves by at most
//! [`MAX_OFFSET`]; the limb's two bones get shorter by the bend's foreshortening (a drawn
//! proportion, not a depth).
//!
//! It is an option, off by default: on held-out action categories it removes the extra bend of
//! limbs straight in the truth but straightens limbs truly bent in depth too (a frontal walker's
//! knees), which costs more limb-direction error than it saves (docs/benchmarks.md, "3-D pose").
//! It suits what an artist draws standing or posing with straight limbs.

use nalgebra::Vector3;

use crate::camera::WeakPerspective;
use crate::skeleton::{joint, Joints2, Joints3, NUM_JOINTS};

/// The four limbs as (end at the body, middle, far end) joints: right and left arm, right and
/// left leg.
pub const LIMBS: [(usize, usize, usize); 4] = [
    (joint::R_SHOULDER, joint::R_ELBOW, joint::R_WRIST),
    (joint::L_SHOULDER, joint::L_ELBOW, joint::L_WRIST),
    (joint::R_HIP, joint::R_KNEE, joint::R_ANKLE),
    (joint::L_HIP, joint::L_KNEE, joint::L_ANKLE),
];

/// Largest distance of the drawn middle joint from the image line through the limb's ends, as a
/// fraction of the limb's length at the camera's scale (3 % of a 0.9 m leg on a 500-px figure
/// is 8 px), for the limb to count as drawn straight.
pub const MAX_OFFSET: f64 = 0.03;

/// Largest 3-D bend, degrees, of a limb this step may straighten.
pub const MAX_BEND_DEG: f64 = 60.0;

/// A limb this step straightens: drawn straight, bent more than 0 and at most [`MAX_BEND_DEG`]
/// in 3-D.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LimbCandidate {
    /// Index into [`LIMBS`].
    limb: usize,
    /// Where the middle joint goes: `end + t (far end − end)`, in [0, 1].
    t: f64,
}

/// Bend of the limb `a → b → c`, degrees (0 = straight); 0 for a zero-length bone.
pub fn bend_deg(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> f64 {
    let (u, v) = (b - a, c - b);
    let n = u.norm() * v.norm();
    if n > 0.0 {
        (u.dot(&v) / n).clamp(-1.0, 1.0).acos().to_degrees()
    } else {
        0.0
    }
}

/// The limbs of `joints` (model frame, seen by `camera`) that the drawn 2-D joints `drawn` show
/// straight (all three visible, the middle one within [`MAX_OFFSET`] of the ends' line and its
/// foot between them) and that are bent more than 0 and at most [`MAX_BEND_DEG`] in 3-D.
fn candidates(joints: &Joints3, camera: &WeakPerspective, drawn: &Joints2) -> Vec<LimbCandidate> {
    let x: [Vector3<f64>; NUM_JOINTS] = std::array::from_fn(|j| Vector3::from(joints[j]));
    let scale = 0.5 * (camera.sx + camera.sy);
    let mut out = Vec::new();
    for (limb, &(a, b, c)) in LIMBS.iter().enumerate() {
        if !(drawn.visible[a] && drawn.visible[b] && drawn.visible[c]) {
            continue;
        }
        let bend = bend_deg(&x[a], &x[b], &x[c]);
        if !(bend > 0.0 && bend <= MAX_BEND_DEG) {
            continue;
        }
        let (l1, l2) = ((x[b] - x[a]).norm(), (x[c] - x[b]).norm());
        let Some(t) = foot_on_line(&camera.project(&x[a]), &camera.project(&x[c]), &drawn.xy[b]) else { continue };
        let offset = line_offset(&drawn.xy[a], &drawn.xy[c], &drawn.xy[b]) / (MAX_OFFSET * (l1 + l2) * scale);
        if !(offset <= 1.0) || !(0.0..=1.0).contains(&t) {
            continue;
        }
        out.push(LimbCandidate { limb, t });
    }
    out
}

/// The straightened joints of `joints` (model frame, seen by `camera`) for the drawn 2-D joints
/// `drawn` (module doc): every limb drawn straight and bent at most [`MAX_BEND_DEG`] in depth;
/// returns the joints and how many limbs were straightened.
pub fn straighten_limbs(joints: &Joints3, camera: &WeakPerspective, drawn: &Joints2) -> (Joints3, usize) {
    let mut out = *joints;
    let mut n = 0;
    for c in candidates(joints, camera, drawn) {
        let (a, b, e) = LIMBS[c.limb];
        let (pa, pe) = (Vector3::from(joints[a]), Vector3::from(joints[e]));
        out[b] = (pa + c.t * (pe - pa)).into();
        n += 1;
    }
    (out, n)
}

/// Parameter `t` of the foot of `p` on the image line `a → b` (`a + t (b − a)`); `None` when the
/// ends coincide.
fn foot_on_line(a: &[f64; 2], b: &[f64; 2], p: &[f64; 2]) -> Option<f64> {
    let d = [b[0] - a[0], b[1] - a[1]];
    let dd = d[0] * d[0] + d[1] * d[1];
    (dd > 0.0).then(|| ((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / dd)
}

/// Distance of `p` from the image line through `a` and `b`, pixels (from `a` when they coincide).
fn line_offset(a: &[f64; 2], b: &[f64; 2], p: &[f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let e = [p[0] - a[0], p[1] - a[1]];
    let len = d[0].hypot(d[1]);
    if len > 0.0 {
        (d[0] * e[1] - d[1] * e[0]).abs() / len
    } else {
        e[0].hypot(e[1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Rotation3};

    fn camera(yaw_deg: f64) -> WeakPerspective {
        let r: Matrix3<f64> = *Rotation3::from_axis_angle(&Vector3::y_axis(), yaw_deg.to_radians()).matrix();
        WeakPerspective { sx: 280.0, sy: 280.0, r, t: [250.0, 260.0] }
    }

    /// A figure whose right leg is hip (0, 0, 0), knee bent toward the viewer by `knee_z`, ankle
    /// 0.9 m below the hip; the other limbs hang straight down.
    fn figure(knee_z: f64) -> Joints3 {
        let mut x = [[0.0; 3]; NUM_JOINTS];
        for (a, b, c) in LIMBS {
            let side = if a == joint::R_SHOULDER || a == joint::R_HIP { -0.15 } else { 0.15 };
            let top = if a == joint::R_HIP || a == joint::L_HIP { 0.0 } else { 0.5 };
            x[a] = [side, top, 0.0];
            x[b] = [side, top - 0.45, 0.0];
            x[c] = [side, top - 0.9, 0.0];
        }
        x[joint::R_KNEE][2] = knee_z;
        x
    }

    fn drawn(x: &Joints3, cam: &WeakPerspective) -> Joints2 {
        Joints2 { xy: std::array::from_fn(|j| cam.project(&Vector3::from(x[j]))), visible: [true; NUM_JOINTS] }
    }

    #[test]
    fn a_knee_bent_in_depth_behind_a_straight_drawn_leg_is_straightened() {
        let cam = camera(0.0);
        // The drawing: a straight leg whose knee sits at 45 % of its length (a longer shin
        // than the estimate's bones). The estimate: the knee bent 0.1 m toward the viewer.
        let mut truth = figure(0.0);
        truth[joint::R_KNEE][1] = -0.405;
        let est = figure(0.1);
        let before = bend_deg(&Vector3::from(est[9]), &Vector3::from(est[10]), &Vector3::from(est[11]));
        assert!(before > 20.0, "{before}");
        let (out, n) = straighten_limbs(&est, &cam, &drawn(&truth, &cam));
        assert_eq!(n, 1);
        let k = Vector3::from(out[joint::R_KNEE]);
        assert!(bend_deg(&Vector3::from(out[9]), &k, &Vector3::from(out[11])) < 1e-9);
        // The knee's image is the drawn one; the ends and the other limbs are untouched.
        let p = cam.project(&k);
        let q = drawn(&truth, &cam).xy[joint::R_KNEE];
        assert!((p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9, "{p:?} vs {q:?}");
        for j in (0..NUM_JOINTS).filter(|&j| j != joint::R_KNEE) {
            assert_eq!(out[j], est[j], "joint {j}");
        }
    }

    #[test]
    fn limbs_bent_beyond_the_limit_or_bent_in_the_image_are_kept() {
        let cam = camera(0.0);
        let est = figure(0.1);
        // Beyond the largest bend (70°): the bend stays.
        let deep = figure(0.315);
        let (out, n) = straighten_limbs(&deep, &cam, &drawn(&figure(0.0), &cam));
        assert_eq!((n, out), (0, deep));
        // Drawn bent: the knee 0.05 m to the side of the hip–ankle line (5.6 % of the leg).
        let mut bent = figure(0.0);
        bent[joint::R_KNEE][0] += 0.05;
        let (out, n) = straighten_limbs(&est, &cam, &drawn(&bent, &cam));
        assert_eq!((n, out), (0, est));
        // A hidden knee: nothing to judge by.
        let mut hidden = drawn(&figure(0.0), &cam);
        hidden.visible[joint::R_KNEE] = false;
        assert_eq!(straighten_limbs(&est, &cam, &hidden).1, 0);
    }

    #[test]
    fn a_turned_camera_straightens_along_its_own_viewing_direction() {
        // Seen from 60° of yaw the bend toward +z shows partly in the image: drawn straight
        // means straight along this camera's line of sight, and the image is kept.
        let cam = camera(60.0);
        let view_dir = cam.r.transpose() * Vector3::z();
        let mut est = figure(0.0);
        let k = Vector3::from(est[joint::R_KNEE]) + 0.1 * view_dir;
        est[joint::R_KNEE] = k.into();
        let (out, n) = straighten_limbs(&est, &cam, &drawn(&figure(0.0), &cam));
        assert_eq!(n, 1);
        let k2 = Vector3::from(out[joint::R_KNEE]);
        assert!((k2 - Vector3::from(figure(0.0)[joint::R_KNEE])).norm() < 1e-9, "{k2:?}");
    }

    #[test]
    fn bend_is_the_angle_between_the_bones() {
        let (a, b) = (Vector3::new(0.0, 0.0, 0.0), Vector3::new(0.0, -1.0, 0.0));
        assert!(bend_deg(&a, &b, &Vector3::new(0.0, -2.0, 0.0)).abs() < 1e-9);
        assert!((bend_deg(&a, &b, &Vector3::new(1.0, -1.0, 0.0)) - 90.0).abs() < 1e-9);
        assert_eq!(bend_deg(&a, &a, &b), 0.0);
    }
}

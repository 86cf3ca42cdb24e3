//! A procedural rigged humanoid (capsules along the bones, skin weights by distance) and random
//! plausible poses made by rotating its rig. For tests, examples and benchmarks that need a
//! body without the MakeHuman shape model; not a substitute for it.

use nalgebra::{Unit, UnitQuaternion, Vector3};
use rand::Rng;

use super::ik::{parent_bone, BONE_ORDER};
use super::rig::{RiggedMesh, VertexWeights};
use super::MAX_INFLUENCES;
use crate::skeleton::{Joints3, BONES, NUM_BONES, NUM_JOINTS};

/// Rest joints of a 1.7 m adult in an A-pose (arms 50° below horizontal, legs straight),
/// metres, model frame (+Y up, +Z front, the character's right at −X), feet at y = 0.
pub fn rest_joints() -> Joints3 {
    let (c, s) = (50f64.to_radians().cos(), 50f64.to_radians().sin());
    let (ua, fa) = (0.29, 0.26);
    let (sh, sy) = (0.19, 1.42);
    [
        [0.0, 1.60, 0.01],                                // head
        [0.0, 1.45, -0.02],                               // neck
        [-sh, sy, -0.03],                                 // r_shoulder
        [-sh - ua * c, sy - ua * s, -0.03],               // r_elbow
        [-sh - (ua + fa) * c, sy - (ua + fa) * s, -0.03], // r_wrist
        [sh, sy, -0.03],                                  // l_shoulder
        [sh + ua * c, sy - ua * s, -0.03],                // l_elbow
        [sh + (ua + fa) * c, sy - (ua + fa) * s, -0.03],  // l_wrist
        [0.0, 0.98, 0.0],                                 // pelvis
        [-0.09, 0.92, 0.0],                               // r_hip
        [-0.10, 0.50, 0.01],                              // r_knee
        [-0.11, 0.08, -0.02],                             // r_ankle
        [0.09, 0.92, 0.0],                                // l_hip
        [0.10, 0.50, 0.01],                               // l_knee
        [0.11, 0.08, -0.02],                              // l_ankle
    ]
}

/// Largest local rotation (radians) of each bone in [`random_pose`].
const MAX_SWING: [f64; NUM_BONES] = [0.5, 0.25, 1.4, 0.0, 0.25, 1.4, 0.0, 0.5, 0.15, 1.2, 0.0, 0.15, 1.2, 0.0];

/// A random plausible pose of `rest`: the root turned about +Y (any angle) and tilted a little,
/// each bone rotated about a random axis by up to a per-bone limit, elbows and knees flexed as
/// hinges (0–140°), and with `length_jitter` > 0 every bone scaled by a factor in
/// [1 − jitter, 1 + jitter]. Returns the posed joints (forward kinematics).
pub fn random_pose<R: Rng>(rest: &Joints3, rng: &mut R, length_jitter: f64) -> Joints3 {
    let mut rot = [UnitQuaternion::identity(); NUM_BONES];
    let root = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), rng.random_range(-3.1..3.1))
        * UnitQuaternion::from_axis_angle(&random_axis(rng), rng.random_range(0.0..0.3));
    let mut joints = [[0.0; 3]; NUM_JOINTS];
    joints[crate::skeleton::joint::PELVIS] = rest[crate::skeleton::joint::PELVIS];
    for &b in &BONE_ORDER {
        let (s, c) = BONES[b];
        let parent = parent_bone(b).map_or(root, |p| rot[p]);
        let local = if MAX_SWING[b] == 0.0 {
            // Hinge: flex about the axis perpendicular to the limb and the body's front.
            let d = Vector3::from(rest[c]) - Vector3::from(rest[s]);
            let is_leg = b >= 9;
            let forward = if is_leg { -Vector3::z() } else { Vector3::z() };
            let axis = Unit::new_normalize(d.cross(&forward));
            UnitQuaternion::from_axis_angle(&axis, rng.random_range(0.0..2.4))
        } else {
            UnitQuaternion::from_axis_angle(&random_axis(rng), rng.random_range(0.0..MAX_SWING[b]))
        };
        rot[b] = parent * local;
        let scale = if length_jitter > 0.0 { rng.random_range(1.0 - length_jitter..1.0 + length_jitter) } else { 1.0 };
        let d = rot[b] * (Vector3::from(rest[c]) - Vector3::from(rest[s])) * scale;
        let p = Vector3::from(joints[s]) + d;
        joints[c] = [p.x, p.y, p.z];
    }
    joints
}

fn random_axis<R: Rng>(rng: &mut R) -> Unit<Vector3<f64>> {
    loop {
        let a = Vector3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        if a.norm() > 0.1 && a.norm() <= 1.0 {
            return Unit::new_normalize(a);
        }
    }
}

/// Capsule radius of each bone, metres.
const RADIUS: [f64; NUM_BONES] =
    [0.10, 0.06, 0.05, 0.04, 0.06, 0.05, 0.04, 0.13, 0.08, 0.075, 0.055, 0.08, 0.075, 0.055];

/// A capsule humanoid on `joints`: one capsule per bone with `rings` quads along it and `segs`
/// around (caps included), skin weights falling to 0 at 4 cm beyond the nearest bone's surface
/// (at most four bones).
/// `rings = 40, segs = 24` gives about 27k triangles. Faces are quads (cap tips repeat a corner).
pub fn capsule_humanoid(joints: &Joints3, rings: usize, segs: usize) -> RiggedMesh {
    let (rings, segs) = (rings.max(4), segs.max(3));
    let mut vertices = Vec::new();
    let mut quads = Vec::new();
    for (b, &(s, c)) in BONES.iter().enumerate() {
        let a = Vector3::from(joints[s]);
        let e = Vector3::from(joints[c]);
        let axis = (e - a).normalize();
        let helper = if axis.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        let u = axis.cross(&helper).normalize();
        let w = axis.cross(&u);
        let (r, len) = (RADIUS[b], (e - a).norm());
        let base = vertices.len() as u32;
        // Profile: a hemisphere at each end joined by a cylinder, `rings + 1` points spaced
        // evenly along its arc length.
        let quarter = r * std::f64::consts::FRAC_PI_2;
        for i in 0..=rings {
            let arc = i as f64 / rings as f64 * (len + 2.0 * quarter);
            let (z, radial) = if arc < quarter {
                (-r * (arc / r).cos(), r * (arc / r).sin())
            } else if arc <= quarter + len {
                (arc - quarter, r)
            } else {
                let theta = (arc - quarter - len) / r + std::f64::consts::FRAC_PI_2;
                (len - r * theta.cos(), r * theta.sin())
            };
            for k in 0..segs {
                let phi = k as f64 / segs as f64 * std::f64::consts::TAU;
                let p = a + axis * z + (u * phi.cos() + w * phi.sin()) * radial;
                vertices.push([p.x as f32, p.y as f32, p.z as f32]);
            }
        }
        for i in 0..rings as u32 {
            for k in 0..segs as u32 {
                let k1 = (k + 1) % segs as u32;
                let row = |i: u32, k: u32| base + i * segs as u32 + k;
                // Counter-clockwise seen from outside.
                quads.push([row(i, k), row(i, k1), row(i + 1, k1), row(i + 1, k)]);
            }
        }
    }
    let weights = vertices.iter().map(|p| distance_weights(joints, p)).collect();
    RiggedMesh { vertices, quads, uvs: None, joints: *joints, weights }
}

fn distance_weights(joints: &Joints3, p: &[f32; 3]) -> VertexWeights {
    let p = Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64);
    let mut d: Vec<(f64, usize)> = BONES
        .iter()
        .enumerate()
        .map(|(b, &(s, c))| {
            let a = Vector3::from(joints[s]);
            let e = Vector3::from(joints[c]) - a;
            let t = ((p - a).dot(&e) / e.norm_squared()).clamp(0.0, 1.0);
            (((p - a - e * t).norm() - RADIUS[b]).max(0.0), b)
        })
        .collect();
    d.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let mut w = VertexWeights { bones: [0; MAX_INFLUENCES], weights: [0.0; MAX_INFLUENCES] };
    let mut sum = 0.0;
    for (slot, &(dist, b)) in d.iter().take(MAX_INFLUENCES).enumerate() {
        let x = (1.0 - (dist - d[0].0) / 0.04).max(0.0).powi(2) as f32;
        if x > 0.0 {
            w.bones[slot] = b as u8;
            w.weights[slot] = x;
            sum += x;
        }
    }
    for x in &mut w.weights {
        *x /= sum;
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capsule_humanoid_is_valid_and_about_27k_triangles() {
        let m = capsule_humanoid(&rest_joints(), 40, 24);
        m.validate().unwrap();
        let n = m.triangles().len();
        assert!((25_000..30_000).contains(&n), "{n} triangles");
    }
}

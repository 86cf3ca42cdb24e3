//! Inverse kinematics on the canonical 14-bone skeleton: from 15 target joints, one global
//! rotation per bone that points every bone exactly along its target direction, with twists
//! chosen from the body's own lines (paper §II-C, where HAVOK did this job).
//!
//! Rotations are *global* (rest → posed, model frame) and are composed down the hierarchy: each
//! bone starts from its parent bone's rotation and adds the smallest swing that takes its rest
//! direction to the target direction; twist about the bone is then set where the body defines
//! it: the pelvis from the hip line, the torso from the shoulder line, the upper arms and legs
//! from the plane of the limb (so elbows and knees bend as hinges). Bone `b` moves a rest point
//! `x` to `P[s] + R_b A_b (x − J[s])`, where `s = BONES[b].0`, `J` are the rest joints, `P` the
//! posed joints and `A_b` the bone's stretch (identity without retargeting).
//!
//! With retargeting, each bone is also scaled along its rest direction by `k_b = |target bone| /
//! |rest bone|` (measured from its start joint; no scaling across the bone), so the posed joints
//! land exactly on the targets. Vertices bound to bone `b` stretch with it, including geometry
//! beyond its end joint (the top of the head for neck–head, hands for the forearms, feet for the
//! shins), which stretches by the same factor.

use nalgebra::{Matrix3, Rotation3, Unit, UnitQuaternion, Vector3};

use crate::error::{Error, Result};
use crate::skeleton::{joint, Joints3, BONES, JOINT_NAMES, NUM_BONES, NUM_JOINTS};

/// Bones shorter than this (metres) count as coincident joints.
pub const MIN_BONE_LENGTH: f64 = 1e-5;

/// Bones in an order where every bone comes after its parent bone.
pub const BONE_ORDER: [usize; NUM_BONES] = [7, 8, 11, 0, 1, 4, 2, 3, 5, 6, 9, 10, 12, 13];

/// The parent bone of each bone (the bone ending where it starts); `None` for bones that start
/// at the pelvis.
pub fn parent_bone(b: usize) -> Option<usize> {
    let start = BONES[b].0;
    BONES.iter().position(|&(_, c)| c == start)
}

/// IK options.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IkOptions {
    /// Scale each bone along its length so that the posed joints land on the targets (for
    /// sketches with non-standard proportions). Off: bones keep their rest lengths and only
    /// the directions match.
    pub retarget: bool,
}

/// A posed skeleton: per-bone rigid rotation and stretch, and the resulting joint positions.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// Rest joints (bind pose), metres, model frame.
    pub rest: Joints3,
    /// Posed joints, metres, model frame.
    pub joints: Joints3,
    /// Global rotation of each bone, rest → posed.
    pub rotations: [UnitQuaternion<f64>; NUM_BONES],
    /// Stretch of each bone along its rest direction (1 without retargeting).
    pub stretch: [f64; NUM_BONES],
    /// Rotation of the pelvis frame (hip line and spine), rest → posed.
    pub root: UnitQuaternion<f64>,
}

impl Pose {
    /// The rest pose itself (identity rotations, unit stretch).
    pub fn rest(rest: &Joints3) -> Pose {
        Pose {
            rest: *rest,
            joints: *rest,
            rotations: [UnitQuaternion::identity(); NUM_BONES],
            stretch: [1.0; NUM_BONES],
            root: UnitQuaternion::identity(),
        }
    }

    /// The affine map of bone `b`: posed = `m * rest + t` (rotation times stretch, and offset).
    pub fn bone_affine(&self, b: usize) -> (Matrix3<f64>, Vector3<f64>) {
        let s = BONES[b].0;
        let a = self.stretch_matrix(b);
        let m = self.rotations[b].to_rotation_matrix().into_inner() * a;
        let t = Vector3::from(self.joints[s]) - m * Vector3::from(self.rest[s]);
        (m, t)
    }

    /// `A_b = I + (k_b − 1) d d^T`, d the rest direction of bone `b`.
    pub fn stretch_matrix(&self, b: usize) -> Matrix3<f64> {
        let (s, c) = BONES[b];
        let d = (Vector3::from(self.rest[c]) - Vector3::from(self.rest[s])).normalize();
        Matrix3::identity() + (self.stretch[b] - 1.0) * d * d.transpose()
    }

    /// Rotation of bone `b` relative to its parent bone (`R_parent^T R_b`; relative to the
    /// pelvis frame [`Pose::root`] for bones that start at the pelvis).
    pub fn local_rotation(&self, b: usize) -> UnitQuaternion<f64> {
        match parent_bone(b) {
            Some(p) => self.rotations[p].inverse() * self.rotations[b],
            None => self.root.inverse() * self.rotations[b],
        }
    }
}

/// Checks 15 joints: finite coordinates and no zero-length bone.
pub fn check_joints(name: &'static str, j: &Joints3) -> Result<()> {
    for p in j {
        for &c in p {
            if !c.is_finite() {
                return Err(Error::NonFinite { name, value: c });
            }
        }
    }
    for &(s, c) in &BONES {
        let length = (Vector3::from(j[c]) - Vector3::from(j[s])).norm();
        if length < MIN_BONE_LENGTH {
            return Err(Error::DegenerateBone { from: JOINT_NAMES[s], to: JOINT_NAMES[c], length });
        }
    }
    Ok(())
}

fn v(j: &Joints3, i: usize) -> Vector3<f64> {
    Vector3::from(j[i])
}

fn dir(j: &Joints3, b: usize) -> Vector3<f64> {
    let (s, c) = BONES[b];
    (v(j, c) - v(j, s)).normalize()
}

/// Orthonormal frame (columns) with first axis along `primary` and second in the plane of
/// `primary` and `secondary`; `None` when the two are (nearly) parallel.
fn frame(primary: &Vector3<f64>, secondary: &Vector3<f64>) -> Option<Matrix3<f64>> {
    let e1 = primary.normalize();
    let s = secondary - e1 * e1.dot(secondary);
    if s.norm() < 1e-6 * secondary.norm().max(1e-300) {
        return None;
    }
    let e2 = s.normalize();
    Some(Matrix3::from_columns(&[e1, e2, e1.cross(&e2)]))
}

/// Rotation taking the rest frame to the target frame.
fn frame_rotation(rest: &Matrix3<f64>, target: &Matrix3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(target * rest.transpose()))
}

/// Smallest rotation taking unit `a` to unit `b` (a half turn about a fixed perpendicular axis
/// when they are opposite).
fn swing(a: &Vector3<f64>, b: &Vector3<f64>) -> UnitQuaternion<f64> {
    if let Some(q) = UnitQuaternion::rotation_between(a, b) {
        if q.into_inner().coords.iter().all(|c| c.is_finite()) {
            return q;
        }
    }
    let helper = if a.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    UnitQuaternion::from_axis_angle(&Unit::new_normalize(a.cross(&helper)), std::f64::consts::PI)
}

/// Rotation `r` followed by the swing that points `r * d0` along `dt`.
fn swing_from(r: &UnitQuaternion<f64>, d0: &Vector3<f64>, dt: &Vector3<f64>) -> UnitQuaternion<f64> {
    swing(&(r * d0), dt) * r
}

fn smoothstep(lo: f64, hi: f64, x: f64) -> f64 {
    let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The rest hinge axis of a limb (upper bone `up`, lower bone `low`): the limb plane's normal
/// when the rest limb is bent, otherwise the anatomical axis (elbows bend forward, knees back).
fn rest_hinge(rest: &Joints3, up: usize, low: usize, is_leg: bool) -> Vector3<f64> {
    let (u, l) = (dir(rest, up), dir(rest, low));
    let n = u.cross(&l);
    let bent = smoothstep(0.10, 0.17, n.norm());
    let forward = if is_leg { -Vector3::z() } else { Vector3::z() };
    let mut anatomical = u.cross(&forward);
    if anatomical.norm() < 1e-6 {
        anatomical = u.cross(&Vector3::x());
    }
    let h =
        if n.norm() > 1e-9 { n.normalize() * bent } else { Vector3::zeros() } + anatomical.normalize() * (1.0 - bent);
    let h = h - u * u.dot(&h);
    if h.norm() > 1e-9 {
        h.normalize()
    } else {
        anatomical.normalize()
    }
}

/// Solves the IK: rotations (and, with `opts.retarget`, stretches) that take the `rest` joints
/// to the `target` joints. The pelvis is moved onto its target. Errors: non-finite joints
/// ([`Error::NonFinite`]) and zero-length bones ([`Error::DegenerateBone`]) in either input.
pub fn solve(rest: &Joints3, target: &Joints3, opts: &IkOptions) -> Result<Pose> {
    check_joints("rest joint", rest)?;
    check_joints("target joint", target)?;
    let id = UnitQuaternion::identity();
    let mut rot = [id; NUM_BONES];
    let d0: Vec<Vector3<f64>> = (0..NUM_BONES).map(|b| dir(rest, b)).collect();
    let dt: Vec<Vector3<f64>> = (0..NUM_BONES).map(|b| dir(target, b)).collect();
    use joint::*;
    let hip_line = |j: &Joints3| v(j, L_HIP) - v(j, R_HIP);
    let shoulder_line = |j: &Joints3| v(j, L_SHOULDER) - v(j, R_SHOULDER);
    let spine = |j: &Joints3| v(j, NECK) - v(j, PELVIS);

    // Pelvis: the hip line fixes the twist about the spine.
    let root = match (frame(&hip_line(rest), &spine(rest)), frame(&hip_line(target), &spine(target))) {
        (Some(f0), Some(ft)) => frame_rotation(&f0, &ft),
        _ => swing(&d0[7], &dt[7]),
    };
    for &b in &BONE_ORDER {
        let inherited = parent_bone(b).map_or(root, |p| rot[p]);
        rot[b] = match b {
            // Torso: the shoulder line fixes the twist.
            7 => match (frame(&spine(rest), &shoulder_line(rest)), frame(&spine(target), &shoulder_line(target))) {
                (Some(f0), Some(ft)) => frame_rotation(&f0, &ft),
                _ => swing_from(&root, &d0[b], &dt[b]),
            },
            // Upper arms and thighs: swing, then twist so the limb bends as a hinge.
            2 | 5 | 9 | 12 => {
                let low = b + 1;
                let r = swing_from(&inherited, &d0[b], &dt[b]);
                let h_now = r * rest_hinge(rest, b, low, b >= 9);
                let n = dt[b].cross(&dt[low]);
                let w = smoothstep(0.035, 0.17, n.norm());
                if w > 0.0 {
                    let ht = n.normalize();
                    let angle = h_now.cross(&ht).dot(&dt[b]).atan2(h_now.dot(&ht));
                    UnitQuaternion::from_axis_angle(&Unit::new_normalize(dt[b]), w * angle) * r
                } else {
                    r
                }
            }
            _ => swing_from(&inherited, &d0[b], &dt[b]),
        };
    }

    let mut stretch = [1.0; NUM_BONES];
    let mut joints = [[0.0; 3]; NUM_JOINTS];
    joints[PELVIS] = target[PELVIS];
    for &b in &BONE_ORDER {
        let (s, c) = BONES[b];
        let rest_len = (v(rest, c) - v(rest, s)).norm();
        let len = if opts.retarget {
            let t = (v(target, c) - v(target, s)).norm();
            stretch[b] = t / rest_len;
            t
        } else {
            rest_len
        };
        let p = v(&joints, s) + rot[b] * d0[b] * len;
        joints[c] = [p.x, p.y, p.z];
    }
    Ok(Pose { rest: *rest, joints, rotations: rot, stretch, root })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::procedural::{random_pose, rest_joints};
    use rand::SeedableRng;

    fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
        a.normalize().cross(&b.normalize()).norm().atan2(a.normalize().dot(&b.normalize())).to_degrees()
    }

    #[test]
    fn reproduces_bone_directions_and_retargeted_positions() {
        let rest = rest_joints();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..200 {
            let target = random_pose(&rest, &mut rng, 0.2);
            let pose = solve(&rest, &target, &IkOptions::default()).unwrap();
            for b in 0..NUM_BONES {
                let posed = pose.rotations[b] * dir(&rest, b);
                assert!(angle_deg(&posed, &dir(&target, b)) < 1e-6, "bone {b}");
                let pj = dir(&pose.joints, b);
                assert!(angle_deg(&pj, &dir(&target, b)) < 1e-6, "bone {b}");
            }
            let pose = solve(&rest, &target, &IkOptions { retarget: true }).unwrap();
            for j in 0..NUM_JOINTS {
                let e = (v(&pose.joints, j) - v(&target, j)).norm();
                assert!(e < 1e-9, "joint {j} off by {e} m");
            }
            // Bone affine maps take rest joints to posed joints at both ends.
            for (b, &(s, c)) in BONES.iter().enumerate() {
                let (m, t) = pose.bone_affine(b);
                assert!((m * v(&rest, s) + t - v(&pose.joints, s)).norm() < 1e-9);
                assert!((m * v(&rest, c) + t - v(&pose.joints, c)).norm() < 1e-9);
            }
        }
    }

    #[test]
    fn rest_target_gives_identity_and_twist_follows_the_hip_line() {
        let rest = rest_joints();
        let pose = solve(&rest, &rest, &IkOptions::default()).unwrap();
        for q in &pose.rotations {
            assert!(q.angle() < 1e-9);
        }
        // Turn the whole body 90 degrees about +Y: every bone turns the same, twist included.
        let turn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 1.2);
        let mut target = rest;
        for p in target.iter_mut() {
            let q = turn * Vector3::from(*p);
            *p = [q.x, q.y, q.z];
        }
        let pose = solve(&rest, &target, &IkOptions::default()).unwrap();
        for (b, q) in pose.rotations.iter().enumerate() {
            assert!(q.angle_to(&turn) < 1e-9, "bone {b}: {}", q.angle_to(&turn));
        }
    }

    #[test]
    fn bad_joints_are_rejected() {
        let rest = rest_joints();
        let mut t = rest;
        t[joint::R_ELBOW][1] = f64::NAN;
        assert!(matches!(solve(&rest, &t, &IkOptions::default()), Err(Error::NonFinite { .. })));
        let mut t = rest;
        t[joint::R_ELBOW] = t[joint::R_WRIST];
        match solve(&rest, &t, &IkOptions::default()) {
            Err(Error::DegenerateBone { from, to, .. }) => assert_eq!((from, to), ("r_elbow", "r_wrist")),
            other => panic!("expected DegenerateBone, got {other:?}"),
        }
    }
}

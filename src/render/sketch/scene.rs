//! The 3-D scene of a sketch: a body shape, non-standard proportions, a pose applied by IK and
//! skinning, and a near-frontal weak-perspective camera that fits the figure into the image.
//!
//! **Proportions** are applied to the rest mesh before posing ("scale the mesh per bone"): every
//! bone `b` is stretched along its rest direction by a factor `k_b` (legs, arms, torso, the
//! neck→shoulder bones for shoulder width) with the posing engineer's stretch machinery (a
//! [`Pose`] with identity rotations and `stretch = k`, skinned with LBS), so children follow their
//! parents and the joints land at the scaled positions. The head is scaled *uniformly* about the
//! neck joint instead (a vertex with weight `w` on the neck→head bone is scaled by `1 + (k−1)w`),
//! because a stretch along the bone alone would squash it. The result is the ground-truth *rest*
//! mesh: it lies outside the PCA space when `k ≠ 1`.
//!
//! **Pose**: the target joints keep the directions of every bone of the source pose (a mocap
//! frame, a procedural pose or the caller's joints) and take the bone lengths of the proportioned
//! rest skeleton, starting from the pelvis at the origin; IK then turns the bones exactly onto
//! them (no retargeting needed) and LBS skins the mesh. The posed joints are the ground truth.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use rand::Rng;

use crate::body::ik::{self, IkOptions, Pose, BONE_ORDER};
use crate::body::skin::{skin, SkinMethod};
use crate::body::VertexWeights;
use crate::camera::WeakPerspective;
use crate::error::{ensure_finite, Error, Result};
use crate::skeleton::{joint, Joints3, BONES, NUM_BONES, NUM_JOINTS};

/// Bone-length factors for non-standard proportions. Each is a multiplier of the body's own
/// length (1 = unchanged); accepted range 0.5..=2.0, random styles use the ranges on each field.
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

    /// Random proportions: each factor uniform in its documented range, or all 1 with
    /// probability `1 − p_custom`.
    pub fn random<R: Rng + ?Sized>(rng: &mut R, p_custom: f64) -> Proportions {
        if !rng.random_bool(p_custom.clamp(0.0, 1.0)) {
            return Proportions::default();
        }
        Proportions {
            legs: rng.random_range(0.9..1.3),
            arms: rng.random_range(0.9..1.15),
            shoulders: rng.random_range(0.9..1.4),
            head: rng.random_range(0.75..1.1),
            torso: rng.random_range(0.9..1.1),
        }
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

/// An orthonormal frame (columns x, y, z) with y along `up` and x toward `side` (orthogonalised).
fn frame(side: &Vector3<f64>, up: &Vector3<f64>) -> Option<Matrix3<f64>> {
    let y = up.try_normalize(1e-9)?;
    let x = (side - y * side.dot(&y)).try_normalize(1e-9)?;
    Some(Matrix3::from_columns(&[x, y, x.cross(&y)]))
}

/// Target joints with the bone directions of `source` and the bone lengths of `rest`, pelvis at
/// the origin. The girdle bones (neck→shoulders, pelvis→hips) do not take the source's
/// directions, which belong to another skeleton's proportions: they keep their rest directions
/// turned with the source's chest frame (spine, shoulder line) and hip frame (spine, hip line),
/// so shoulders neither shrug nor droop. Errors on non-finite joints or zero-length bones.
pub fn retarget_directions(rest: &Joints3, source: &Joints3) -> Result<Joints3> {
    ik::check_joints("rest joint", rest)?;
    ik::check_joints("pose joint", source)?;
    let v = |j: &Joints3, k: usize| Vector3::from(j[k]);
    let spine = |j: &Joints3| v(j, joint::NECK) - v(j, joint::PELVIS);
    let girdle = |a: usize, b: usize| -> Option<Matrix3<f64>> {
        let f0 = frame(&(v(rest, b) - v(rest, a)), &spine(rest))?;
        let f1 = frame(&(v(source, b) - v(source, a)), &spine(source))?;
        Some(f1 * f0.transpose())
    };
    let chest = girdle(joint::R_SHOULDER, joint::L_SHOULDER);
    let hips = girdle(joint::R_HIP, joint::L_HIP);
    let mut t = [[0.0; 3]; NUM_JOINTS];
    for &b in &BONE_ORDER {
        let (s, c) = BONES[b];
        let rest_d = v(rest, c) - v(rest, s);
        let len = rest_d.norm();
        let turned = match b {
            1 | 4 => chest.map(|r| r * rest_d),
            8 | 11 => hips.map(|r| r * rest_d),
            _ => None,
        };
        let d = turned.unwrap_or_else(|| v(source, c) - v(source, s)).normalize();
        t[c] = (Vector3::from(t[s]) + d * len).into();
    }
    Ok(t)
}

/// Poses a rest mesh onto `target` joints (IK without retargeting, then LBS).
pub fn pose_mesh(
    rest_vertices: &[[f32; 3]],
    rest_joints: &Joints3,
    weights: &[VertexWeights],
    target: &Joints3,
) -> Result<(Vec<[f32; 3]>, Pose)> {
    let pose = ik::solve(rest_joints, target, &IkOptions { retarget: false })?;
    let posed = skin(rest_vertices, weights, &pose, SkinMethod::Linear)?;
    Ok((posed, pose))
}

/// Camera angles in degrees: the rotation is `Rz(roll) · Rx(pitch) · Ry(yaw)` (yaw turns the
/// figure about the vertical, pitch tips it toward the viewer, roll tilts the image).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CameraAngles {
    /// Turn about +Y; random range ±30°.
    pub yaw_deg: f64,
    /// Turn about +X; random range ±10°.
    pub pitch_deg: f64,
    /// Turn about +Z (in the image plane); random range ±5°.
    pub roll_deg: f64,
}

impl CameraAngles {
    /// Uniform random angles in the near-frontal ranges (yaw ±30°, pitch ±10°, roll ±5°).
    pub fn random<R: Rng + ?Sized>(rng: &mut R) -> CameraAngles {
        CameraAngles {
            yaw_deg: rng.random_range(-30.0..=30.0),
            pitch_deg: rng.random_range(-10.0..=10.0),
            roll_deg: rng.random_range(-5.0..=5.0),
        }
    }

    /// The rotation matrix. Errors on non-finite angles or any angle beyond ±90°.
    pub fn rotation(&self) -> Result<Matrix3<f64>> {
        for (name, v) in
            [("camera yaw", self.yaw_deg), ("camera pitch", self.pitch_deg), ("camera roll", self.roll_deg)]
        {
            ensure_finite(name, v)?;
            if v.abs() > 90.0 {
                return Err(Error::OutOfRange { name, detail: format!("{v}° is beyond ±90°") });
            }
        }
        let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.roll_deg.to_radians())
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), self.pitch_deg.to_radians())
            * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), self.yaw_deg.to_radians());
        Ok(Rotation3::from(q).into_inner())
    }
}

/// A camera with rotation `r` that fits `points` into a `width`×`height` image with `margin`
/// (fraction of the smaller side left free on every side), centred, equal scales.
pub fn fit_camera(
    r: Matrix3<f64>,
    points: &[[f32; 3]],
    width: usize,
    height: usize,
    margin: f64,
) -> Result<WeakPerspective> {
    if points.is_empty() {
        return Err(Error::OutOfRange { name: "mesh", detail: "no vertices to frame".into() });
    }
    let mut bb = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    for p in points {
        let c = r * Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        bb = [bb[0].min(c.x), bb[1].min(c.y), bb[2].max(c.x), bb[3].max(c.y)];
    }
    let (w, h) = ((bb[2] - bb[0]).max(1e-6), (bb[3] - bb[1]).max(1e-6));
    let free = margin * width.min(height) as f64;
    let s = ((width as f64 - 2.0 * free) / w).min((height as f64 - 2.0 * free) / h);
    if !(s.is_finite() && s > 0.0) {
        return Err(Error::OutOfRange {
            name: "sketch margin",
            detail: format!("margin {margin} leaves no room in {width}x{height}"),
        });
    }
    let (cx, cy) = ((bb[0] + bb[2]) / 2.0, (bb[1] + bb[3]) / 2.0);
    let cam = WeakPerspective { sx: s, sy: s, r, t: [width as f64 / 2.0 - s * cx, height as f64 / 2.0 + s * cy] };
    cam.validate()?;
    Ok(cam)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::procedural::{capsule_humanoid, rest_joints};

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

    #[test]
    fn camera_fits_points_with_margin() {
        let pts = [[-0.5f32, -1.0, 0.0], [0.5, 1.0, 0.0]];
        let cam = fit_camera(Matrix3::identity(), &pts, 200, 100, 0.1).unwrap();
        // Height 2 m into 100 - 2*10 px: 40 px/m; centred.
        assert!((cam.sx - 40.0).abs() < 1e-9);
        assert_eq!(cam.project(&Vector3::new(0.0, 1.0, 0.0)), [100.0, 10.0]);
        assert!(fit_camera(Matrix3::identity(), &pts, 100, 100, 0.6).is_err());
        assert!(CameraAngles { yaw_deg: f64::NAN, ..Default::default() }.rotation().is_err());
        let r = CameraAngles { yaw_deg: 30.0, pitch_deg: -10.0, roll_deg: 5.0 }.rotation().unwrap();
        assert!((r.determinant() - 1.0).abs() < 1e-12);
    }
}

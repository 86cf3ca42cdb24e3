//! 3-D pose errors: MPJPE (root-aligned), PA-MPJPE (after a similarity Procrustes alignment),
//! limb direction errors, the torso lean and the bends of the knees and elbows.

use nalgebra::{Matrix3, Vector3};

use sketchbody::skeleton::{joint, Joints3, BONES, NUM_JOINTS};

fn v(x: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(x[0], x[1], x[2])
}

/// Mean per-joint position error after translating both poses so their pelvises coincide (no
/// rotation or scale), in the poses' units.
pub fn mpjpe(est: &Joints3, gt: &Joints3) -> f64 {
    let (pe, pg) = (v(&est[joint::PELVIS]), v(&gt[joint::PELVIS]));
    (0..NUM_JOINTS).map(|j| ((v(&est[j]) - pe) - (v(&gt[j]) - pg)).norm()).sum::<f64>() / NUM_JOINTS as f64
}

/// The best similarity (rotation without reflection, uniform scale, translation) mapping `est`
/// onto `gt` (Umeyama), applied to `est`; `None` when the covariance has no SVD.
pub fn similarity_aligned(est: &Joints3, gt: &Joints3) -> Option<Joints3> {
    let n = NUM_JOINTS as f64;
    let ce = est.iter().map(v).sum::<Vector3<f64>>() / n;
    let cg = gt.iter().map(v).sum::<Vector3<f64>>() / n;
    let mut cov = Matrix3::zeros();
    let mut var_e = 0.0;
    for j in 0..NUM_JOINTS {
        let (a, b) = (v(&est[j]) - ce, v(&gt[j]) - cg);
        cov += b * a.transpose();
        var_e += a.norm_squared();
    }
    let svd = cov.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else { return None };
    let d = (u * vt).determinant().signum();
    let s_mat = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d));
    let r = u * s_mat * vt;
    let scale =
        if var_e > 0.0 { (svd.singular_values.component_mul(&Vector3::new(1.0, 1.0, d))).sum() / var_e } else { 1.0 };
    Some(std::array::from_fn(|j| (scale * r * (v(&est[j]) - ce) + cg).into()))
}

/// Mean per-joint position error after the best similarity (rotation without reflection,
/// uniform scale, translation) maps `est` onto `gt` (Umeyama); NaN when it cannot be computed.
pub fn pa_mpjpe(est: &Joints3, gt: &Joints3) -> f64 {
    let Some(a) = similarity_aligned(est, gt) else { return f64::NAN };
    (0..NUM_JOINTS).map(|j| (v(&a[j]) - v(&gt[j])).norm()).sum::<f64>() / NUM_JOINTS as f64
}

/// The limb bones scored by [`limb_direction_errors`]: right and left upper arm, forearm,
/// thigh and shin (indices into [`sketchbody::skeleton::BONES`]).
pub const LIMB_BONES: [usize; 8] = [2, 3, 5, 6, 9, 10, 12, 13];

/// Angle between two vectors, degrees (0 when either is zero).
pub fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let n = a.norm() * b.norm();
    if !(n > 0.0) {
        return 0.0;
    }
    (a.dot(b) / n).clamp(-1.0, 1.0).acos().to_degrees()
}

/// Limb direction errors, degrees: for each bone of [`LIMB_BONES`], the angle between the bone
/// vector of `est` after the similarity alignment onto `gt` ([`similarity_aligned`]) and that of
/// `gt`. Bone lengths do not matter, so poses of different proportions compare fairly. `None`
/// when the alignment cannot be computed.
pub fn limb_direction_errors(est: &Joints3, gt: &Joints3) -> Option<[f64; 8]> {
    let a = similarity_aligned(est, gt)?;
    Some(LIMB_BONES.map(|b| {
        let (p, c) = BONES[b];
        angle_deg(&(v(&a[c]) - v(&a[p])), &(v(&gt[c]) - v(&gt[p])))
    }))
}

/// The hinge joints scored by [`hinge_bends_deg`], as (parent, hinge, child) joints: right
/// knee, left knee, right elbow, left elbow.
pub const HINGES: [(usize, usize, usize); 4] = [
    (joint::R_HIP, joint::R_KNEE, joint::R_ANKLE),
    (joint::L_HIP, joint::L_KNEE, joint::L_ANKLE),
    (joint::R_SHOULDER, joint::R_ELBOW, joint::R_WRIST),
    (joint::L_SHOULDER, joint::L_ELBOW, joint::L_WRIST),
];

/// Largest bend, degrees, of a hinge counted as straight by [`HingeScores`].
pub const STRAIGHT_BEND_DEG: f64 = 15.0;

/// Bend of each of [`HINGES`], degrees: the angle between the upper and the lower bone (0 =
/// straight, whatever the direction of the bend). Needs no alignment: bends do not change under
/// a similarity.
pub fn hinge_bends_deg(x: &Joints3) -> [f64; 4] {
    HINGES.map(|(p, h, c)| angle_deg(&(v(&x[h]) - v(&x[p])), &(v(&x[c]) - v(&x[h]))))
}

/// For each of [`HINGES`], the angle of its chord (first joint to last) out of the image plane
/// of the camera with model-to-camera rotation `r`, degrees (0 = in the plane, 90 = pointing
/// along the viewing direction, signed: > 0 toward +z of the camera frame).
pub fn hinge_depth_angles_deg(x: &Joints3, r: &Matrix3<f64>) -> [f64; 4] {
    HINGES.map(|(p, _, c)| {
        let d = r * (v(&x[c]) - v(&x[p]));
        let n = d.norm();
        if n > 0.0 {
            (d.z / n).clamp(-1.0, 1.0).asin().to_degrees()
        } else {
            0.0
        }
    })
}

/// Sums of hinge-bend errors over many poses ([`HingeScores::add`]); the means are the
/// benchmark's figures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HingeScores {
    /// Sum of |estimated − true| knee bends, degrees.
    pub knee_sum: f64,
    /// Knees counted.
    pub knees: usize,
    /// Sum of |estimated − true| elbow bends, degrees.
    pub elbow_sum: f64,
    /// Elbows counted.
    pub elbows: usize,
    /// Sum of estimated − true bend (signed: > 0 bent more than the truth), degrees, over the
    /// hinges whose true bend is below [`STRAIGHT_BEND_DEG`].
    pub straight_extra_sum: f64,
    /// Hinges straight in the truth.
    pub straight: usize,
}

impl HingeScores {
    /// Adds the hinges of one estimate `est` against its truth `gt`.
    pub fn add(&mut self, est: &Joints3, gt: &Joints3) {
        let (e, g) = (hinge_bends_deg(est), hinge_bends_deg(gt));
        for i in 0..4 {
            let d = e[i] - g[i];
            if i < 2 {
                self.knee_sum += d.abs();
                self.knees += 1;
            } else {
                self.elbow_sum += d.abs();
                self.elbows += 1;
            }
            if g[i] < STRAIGHT_BEND_DEG {
                self.straight_extra_sum += d;
                self.straight += 1;
            }
        }
    }

    /// Adds another set of sums.
    pub fn merge(&mut self, o: &HingeScores) {
        self.knee_sum += o.knee_sum;
        self.knees += o.knees;
        self.elbow_sum += o.elbow_sum;
        self.elbows += o.elbows;
        self.straight_extra_sum += o.straight_extra_sum;
        self.straight += o.straight;
    }

    /// Mean knee-bend error, degrees (NaN without knees).
    pub fn knee_deg(&self) -> f64 {
        self.knee_sum / self.knees as f64
    }

    /// Mean elbow-bend error, degrees (NaN without elbows).
    pub fn elbow_deg(&self) -> f64 {
        self.elbow_sum / self.elbows as f64
    }

    /// Mean extra bend of the hinges straight in the truth, degrees (NaN without any).
    pub fn straight_extra_deg(&self) -> f64 {
        self.straight_extra_sum / self.straight as f64
    }
}

/// Torso lean of a pose, degrees: the angle between its pelvis→neck vector and the model's up
/// axis (+Y).
pub fn torso_lean_deg(x: &Joints3) -> f64 {
    angle_deg(&(v(&x[joint::NECK]) - v(&x[joint::PELVIS])), &Vector3::y())
}

/// Torso direction error, degrees: the angle between the pelvis→neck vectors of `est` and `gt`,
/// each seen in its own camera frame (`r_est`, `r_gt`: model-to-camera rotations) — how far the
/// estimated torso leans (toward the viewer, away or sideways) from the true one as seen.
pub fn torso_lean_error_deg(est: &Joints3, r_est: &Matrix3<f64>, gt: &Joints3, r_gt: &Matrix3<f64>) -> f64 {
    let t = |x: &Joints3, r: &Matrix3<f64>| r * (v(&x[joint::NECK]) - v(&x[joint::PELVIS]));
    angle_deg(&t(est, r_est), &t(gt, r_gt))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    #[test]
    fn procrustes_removes_similarity_but_not_reflection() {
        let gt: Joints3 = std::array::from_fn(|j| [(j as f64).sin(), j as f64 * 0.1, (j as f64 * 0.7).cos()]);
        let r = Rotation3::from_euler_angles(0.3, -0.2, 1.0);
        let est: Joints3 = std::array::from_fn(|j| {
            let p = r * v(&gt[j]) * 1.7 + Vector3::new(1.0, 2.0, 3.0);
            [p.x, p.y, p.z]
        });
        assert!(pa_mpjpe(&est, &gt) < 1e-9);
        assert!(mpjpe(&est, &gt) > 0.1);
        assert!(mpjpe(&gt, &gt) == 0.0);
        let mirrored: Joints3 = std::array::from_fn(|j| [-gt[j][0], gt[j][1], gt[j][2]]);
        assert!(pa_mpjpe(&mirrored, &gt) > 1e-3);
        assert!(limb_direction_errors(&est, &gt).unwrap().iter().all(|e| *e < 1e-4));
        // A longer forearm in the same direction moves only the alignment (a small direction
        // error, a position error); a turned one gives its angle.
        let mut long = gt;
        long[4] = (v(&gt[3]) + 1.5 * (v(&gt[4]) - v(&gt[3]))).into();
        let mut bent = gt;
        bent[4] = (v(&gt[3]) + Rotation3::from_euler_angles(0.0, 0.0, 0.8) * (v(&gt[4]) - v(&gt[3]))).into();
        let (el, eb) = (limb_direction_errors(&long, &gt).unwrap()[1], limb_direction_errors(&bent, &gt).unwrap()[1]);
        assert!(eb > 20.0 && el < 0.25 * eb, "long {el}, bent {eb}");
        assert!(pa_mpjpe(&long, &gt) > 1e-3);
        let id = Matrix3::identity();
        assert!(torso_lean_error_deg(&gt, &id, &gt, &id) < 1e-9);
        let up: Joints3 = std::array::from_fn(|j| if j == joint::NECK { [0.0, 0.5, 0.0] } else { [0.0; 3] });
        assert!(torso_lean_deg(&up) < 1e-9);
        let r = *Rotation3::from_euler_angles(0.2, 0.0, 0.0).matrix();
        assert!((torso_lean_error_deg(&up, &r, &up, &id) - 0.2f64.to_degrees()).abs() < 1e-9);
    }

    #[test]
    fn hinge_bends_score_knees_elbows_and_straight_limbs() {
        use joint::*;
        let mut gt = [[0.0; 3]; NUM_JOINTS];
        for (h, k, a, x) in [(R_HIP, R_KNEE, R_ANKLE, -0.1), (L_HIP, L_KNEE, L_ANKLE, 0.1)] {
            gt[h] = [x, 0.0, 0.0];
            gt[k] = [x, -0.4, 0.0];
            gt[a] = [x, -0.8, 0.0];
        }
        for (s, e, w, x) in [(R_SHOULDER, R_ELBOW, R_WRIST, -0.2), (L_SHOULDER, L_ELBOW, L_WRIST, 0.2)] {
            gt[s] = [x, 0.5, 0.0];
            gt[e] = [x, 0.2, 0.0];
            gt[w] = [x, 0.2, 0.3];
        }
        let b = hinge_bends_deg(&gt);
        assert!(b[0] < 1e-9 && b[1] < 1e-9 && (b[2] - 90.0).abs() < 1e-9 && (b[3] - 90.0).abs() < 1e-9);
        // The right knee bent 30° forward, and the same pose turned and scaled.
        let mut est = gt;
        est[R_ANKLE] = [-0.1, -0.4 - 0.4 * 30f64.to_radians().cos(), 0.4 * 30f64.to_radians().sin()];
        let r = Rotation3::from_euler_angles(0.3, -0.2, 1.0);
        let est: Joints3 = std::array::from_fn(|j| (r * v(&est[j]) * 2.0).into());
        let mut s = HingeScores::default();
        s.add(&est, &gt);
        assert!((s.knee_deg() - 15.0).abs() < 1e-6, "{s:?}");
        assert!(s.elbow_deg() < 1e-6);
        assert_eq!(s.straight, 2);
        assert!((s.straight_extra_deg() - 15.0).abs() < 1e-6);
        let mut t = HingeScores::default();
        t.merge(&s);
        t.merge(&s);
        assert_eq!((t.knees, t.straight), (4, 4));
        assert!((t.straight_extra_deg() - 15.0).abs() < 1e-6);
        assert!(HingeScores::default().knee_deg().is_nan());
    }
}

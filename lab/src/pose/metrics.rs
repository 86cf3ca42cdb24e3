//! 3-D pose errors: MPJPE (root-aligned), PA-MPJPE (after a similarity Procrustes alignment),
//! limb direction errors and the torso lean.

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
}

//! 3-D pose errors: MPJPE (root-aligned) and PA-MPJPE (after a similarity Procrustes alignment).

use nalgebra::{Matrix3, Vector3};

use crate::skeleton::{joint, Joints3, NUM_JOINTS};

fn v(x: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(x[0], x[1], x[2])
}

/// Mean per-joint position error after translating both poses so their pelvises coincide (no
/// rotation or scale), in the poses' units.
pub fn mpjpe(est: &Joints3, gt: &Joints3) -> f64 {
    let (pe, pg) = (v(&est[joint::PELVIS]), v(&gt[joint::PELVIS]));
    (0..NUM_JOINTS).map(|j| ((v(&est[j]) - pe) - (v(&gt[j]) - pg)).norm()).sum::<f64>() / NUM_JOINTS as f64
}

/// Mean per-joint position error after the best similarity (rotation without reflection,
/// uniform scale, translation) maps `est` onto `gt` (Umeyama).
pub fn pa_mpjpe(est: &Joints3, gt: &Joints3) -> f64 {
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
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else { return f64::NAN };
    let d = (u * vt).determinant().signum();
    let s_mat = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d));
    let r = u * s_mat * vt;
    let scale =
        if var_e > 0.0 { (svd.singular_values.component_mul(&Vector3::new(1.0, 1.0, d))).sum() / var_e } else { 1.0 };
    (0..NUM_JOINTS).map(|j| (scale * r * (v(&est[j]) - ce) - (v(&gt[j]) - cg)).norm()).sum::<f64>() / n
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
    }
}

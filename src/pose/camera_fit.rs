//! The camera step of the matching pursuit (paper §II-B): given 3-D joints, the weak-perspective
//! camera of eq. (1) from the SVD of M = x̂ 𝒳ᵀ(𝒳𝒳ᵀ)⁻¹ = U D Vᵀ, the rotation pulled toward the
//! identity by eq. (4) (R̂ = αI + (1−α)R_svd) and projected back onto SO(3) through the SVD of R̂.
//!
//! Details: image v is flipped (v → −v) to match the paper's y-up form; R_svd's first two rows
//! are U Vᵀ (the nearest orthonormal rows to M) and the third is their cross product. Because
//! sx ≠ sy is allowed, the scales are then the per-axis least-squares scales for that rotation
//! (for sx = sy and α = 0 they equal the mean of the singular values of D up to noise); the
//! translation maps the 3-D centroid of the visible joints onto their 2-D centroid.

use nalgebra::{Matrix2x3, Matrix3, Vector3};

use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::skeleton::NUM_JOINTS;

/// Fits the camera to visible joints `vis` of `x3` (metres) and `uv` (pixels) with pull `alpha`.
pub fn fit_camera(x3: &[Vector3<f64>; NUM_JOINTS], uv: &[[f64; 2]; NUM_JOINTS], vis: &[usize], alpha: f64) -> Result<WeakPerspective> {
    let n = vis.len() as f64;
    let c3 = vis.iter().fold(Vector3::zeros(), |a, &p| a + x3[p]) / n;
    let cu = vis.iter().map(|&p| uv[p][0]).sum::<f64>() / n;
    let cv = vis.iter().map(|&p| uv[p][1]).sum::<f64>() / n;
    let mut s = Matrix3::zeros();
    let mut wx = Matrix2x3::zeros();
    for &p in vis {
        let d = x3[p] - c3;
        let w = nalgebra::Vector2::new(uv[p][0] - cu, -(uv[p][1] - cv));
        s += d * d.transpose();
        wx += w * d.transpose();
    }
    let sinv = s.pseudo_inverse(1e-12 * s.norm().max(f64::MIN_POSITIVE)).map_err(|e| Error::Degenerate(e.to_string()))?;
    let m = wx * sinv;
    let svd = m.svd(true, true);
    let (u, vt) = match (svd.u, svd.v_t) {
        (Some(u), Some(vt)) => (u, vt),
        _ => return Err(Error::Degenerate("camera SVD failed".into())),
    };
    if !(svd.singular_values[0] > 0.0) || !svd.singular_values[0].is_finite() {
        return Err(Error::Degenerate("the 3-D joints do not explain the 2-D spread (M = 0)".into()));
    }
    let r12 = u * vt;
    let (r1, r2): (Vector3<f64>, Vector3<f64>) = (r12.row(0).transpose(), r12.row(1).transpose());
    let r_svd = Matrix3::from_rows(&[r1.transpose(), r2.transpose(), r1.cross(&r2).transpose()]);
    let r = project_so3(&(Matrix3::identity() * alpha + r_svd * (1.0 - alpha)))?;
    let (mut num, mut den) = ([0.0; 2], [0.0; 2]);
    for &p in vis {
        let y = r * (x3[p] - c3);
        num[0] += (uv[p][0] - cu) * y.x;
        den[0] += y.x * y.x;
        num[1] += -(uv[p][1] - cv) * y.y;
        den[1] += y.y * y.y;
    }
    let fallback = 0.5 * (svd.singular_values[0] + svd.singular_values[1]);
    let scale = |a: usize| if den[a] > 0.0 && num[a] / den[a] > 1e-6 * fallback { num[a] / den[a] } else { fallback };
    let (sx, sy) = (scale(0), scale(1));
    let rc = r * c3;
    let cam = WeakPerspective { sx, sy, r, t: [cu - sx * rc.x, cv + sy * rc.y] };
    cam.validate().map_err(|e| Error::Degenerate(format!("camera fit: {e}")))?;
    Ok(cam)
}

/// The rotation nearest to `m` (SVD, determinant forced to +1).
pub fn project_so3(m: &Matrix3<f64>) -> Result<Matrix3<f64>> {
    let svd = m.svd(true, true);
    let (u, vt) = match (svd.u, svd.v_t) {
        (Some(u), Some(vt)) => (u, vt),
        _ => return Err(Error::Degenerate("rotation SVD failed".into())),
    };
    let d = (u * vt).determinant().signum();
    Ok(u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * vt)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn figure() -> [Vector3<f64>; NUM_JOINTS] {
        std::array::from_fn(|j| Vector3::new((j as f64 * 0.37).sin() * 0.4, j as f64 * 0.1 - 0.7, (j as f64 * 1.3).cos() * 0.2))
    }

    #[test]
    fn recovers_an_exact_camera_without_pull_and_stays_nearer_identity_with_pull() {
        let x = figure();
        let r = *Rotation3::from_euler_angles(0.1, 0.4, -0.05).matrix();
        let truth = WeakPerspective { sx: 300.0, sy: 280.0, r, t: [250.0, 260.0] };
        let uv: [[f64; 2]; NUM_JOINTS] = std::array::from_fn(|j| truth.project(&x[j]));
        let vis: Vec<usize> = (0..NUM_JOINTS).collect();
        let cam = fit_camera(&x, &uv, &vis, 0.0).unwrap();
        assert!((cam.r - r).norm() < 1e-9, "{}", cam.r);
        assert!((cam.sx - 300.0).abs() < 1e-7 && (cam.sy - 280.0).abs() < 1e-7);
        assert!((cam.t[0] - 250.0).abs() < 1e-7 && (cam.t[1] - 260.0).abs() < 1e-7);
        let pulled = fit_camera(&x, &uv, &vis, 0.8).unwrap();
        assert!((pulled.r - Matrix3::identity()).norm() < (r - Matrix3::identity()).norm());
        assert!((pulled.r.determinant() - 1.0).abs() < 1e-12);
    }
}

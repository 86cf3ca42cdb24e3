//! The camera step of the matching pursuit (paper §II-B): given 3-D joints, the weak-perspective
//! camera of eq. (1) from the SVD of M = x̂ 𝒳ᵀ(𝒳𝒳ᵀ)⁻¹ = U D Vᵀ, the rotation pulled toward a
//! target by eq. (4) (R̂ = αT + (1−α)R_svd; T = I in the paper, or R_svd with its pitch removed,
//! [`RotationTarget::Level`]) and projected back onto SO(3) through the SVD of R̂.
//!
//! Details: image v is flipped (v → −v) to match the paper's y-up form; R_svd's first two rows
//! are U Vᵀ (the nearest orthonormal rows to M) and the third is their cross product. Because
//! sx ≠ sy is allowed, the scales are then the per-axis least-squares scales for that rotation
//! (for sx = sy and α = 0 they equal the mean of the singular values of D up to noise), or with
//! [`CameraPrior::equal_scales`] the one least-squares scale of both axes; the translation maps
//! the 3-D centroid of the visible joints onto their 2-D centroid.

use nalgebra::{Matrix2x3, Matrix3, Rotation3, Vector3};

use super::options::{PoseOptions, RotationTarget};
use crate::camera::WeakPerspective;
use crate::error::{Error, Result};
use crate::skeleton::NUM_JOINTS;

/// The camera options of the pursuit's camera step (from [`PoseOptions`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPrior {
    /// α of eq. (4), in [0, 1].
    pub alpha: f64,
    /// What α pulls toward.
    pub target: RotationTarget,
    /// sx = sy.
    pub equal_scales: bool,
}

impl CameraPrior {
    /// The camera options of `o`.
    pub fn of(o: &PoseOptions) -> CameraPrior {
        CameraPrior { alpha: o.alpha, target: o.alpha_target, equal_scales: o.equal_scales }
    }
}

/// `r` with its pitch removed: for r = Rz(roll)·Rx(pitch)·Ry(yaw), Rz(roll)·Ry(yaw). Yaw comes
/// from the third row (−cos p sin y, sin p, cos p cos y), roll from r₀₁ = −sin r cos p and
/// r₁₁ = cos r cos p.
pub fn level_of(r: &Matrix3<f64>) -> Matrix3<f64> {
    let yaw = (-r[(2, 0)]).atan2(r[(2, 2)]);
    let roll = (-r[(0, 1)]).atan2(r[(1, 1)]);
    (Rotation3::from_axis_angle(&Vector3::z_axis(), roll) * Rotation3::from_axis_angle(&Vector3::y_axis(), yaw))
        .into_inner()
}

/// Fits the camera to visible joints `vis` of `x3` (metres) and `uv` (pixels) with `prior`.
pub fn fit_camera(
    x3: &[Vector3<f64>; NUM_JOINTS],
    uv: &[[f64; 2]; NUM_JOINTS],
    vis: &[usize],
    prior: &CameraPrior,
) -> Result<WeakPerspective> {
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
    let sinv =
        s.pseudo_inverse(1e-12 * s.norm().max(f64::MIN_POSITIVE)).map_err(|e| Error::Degenerate(e.to_string()))?;
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
    let alpha = prior.alpha;
    let target = match prior.target {
        RotationTarget::Identity => Matrix3::identity(),
        RotationTarget::Level => level_of(&r_svd),
    };
    let r = project_so3(&(target * alpha + r_svd * (1.0 - alpha)))?;
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
    let (sx, sy) = if prior.equal_scales {
        let (n, d) = (num[0] + num[1], den[0] + den[1]);
        let s = if d > 0.0 && n / d > 1e-6 * fallback { n / d } else { fallback };
        (s, s)
    } else {
        (scale(0), scale(1))
    };
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
        std::array::from_fn(|j| {
            Vector3::new((j as f64 * 0.37).sin() * 0.4, j as f64 * 0.1 - 0.7, (j as f64 * 1.3).cos() * 0.2)
        })
    }

    #[test]
    fn recovers_an_exact_camera_without_pull_and_stays_nearer_identity_with_pull() {
        let x = figure();
        let r = *Rotation3::from_euler_angles(0.1, 0.4, -0.05).matrix();
        let truth = WeakPerspective { sx: 300.0, sy: 280.0, r, t: [250.0, 260.0] };
        let uv: [[f64; 2]; NUM_JOINTS] = std::array::from_fn(|j| truth.project(&x[j]));
        let vis: Vec<usize> = (0..NUM_JOINTS).collect();
        let free = |alpha: f64, target: RotationTarget| CameraPrior { alpha, target, equal_scales: false };
        let cam = fit_camera(&x, &uv, &vis, &free(0.0, RotationTarget::Identity)).unwrap();
        assert!((cam.r - r).norm() < 1e-9, "{}", cam.r);
        assert!((cam.sx - 300.0).abs() < 1e-7 && (cam.sy - 280.0).abs() < 1e-7);
        assert!((cam.t[0] - 250.0).abs() < 1e-7 && (cam.t[1] - 260.0).abs() < 1e-7);
        let pulled = fit_camera(&x, &uv, &vis, &free(0.8, RotationTarget::Identity)).unwrap();
        assert!((pulled.r - Matrix3::identity()).norm() < (r - Matrix3::identity()).norm());
        assert!((pulled.r.determinant() - 1.0).abs() < 1e-12);
        // One scale for both axes: between the two true ones.
        let eq = fit_camera(&x, &uv, &vis, &CameraPrior { equal_scales: true, ..free(0.0, RotationTarget::Identity) })
            .unwrap();
        assert_eq!(eq.sx, eq.sy);
        assert!(eq.sx > 280.0 && eq.sx < 300.0, "{}", eq.sx);
    }

    #[test]
    fn level_target_removes_only_the_pitch() {
        let (yaw, pitch, roll) = (0.4f64, -0.3f64, 0.07f64);
        let rot = |y: f64, p: f64, r: f64| {
            (Rotation3::from_axis_angle(&Vector3::z_axis(), r)
                * Rotation3::from_axis_angle(&Vector3::x_axis(), p)
                * Rotation3::from_axis_angle(&Vector3::y_axis(), y))
            .into_inner()
        };
        assert!((level_of(&rot(yaw, pitch, roll)) - rot(yaw, 0.0, roll)).norm() < 1e-12);
        // Pulled fully toward the level target, a pitched camera comes out level with its yaw kept.
        let x = figure();
        let truth = WeakPerspective { sx: 300.0, sy: 300.0, r: rot(yaw, pitch, roll), t: [250.0, 260.0] };
        let uv: [[f64; 2]; NUM_JOINTS] = std::array::from_fn(|j| truth.project(&x[j]));
        let vis: Vec<usize> = (0..NUM_JOINTS).collect();
        let cam =
            fit_camera(&x, &uv, &vis, &CameraPrior { alpha: 1.0, target: RotationTarget::Level, equal_scales: true })
                .unwrap();
        assert!((cam.r - rot(yaw, 0.0, roll)).norm() < 1e-9, "{}", cam.r);
    }
}

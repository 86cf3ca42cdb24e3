//! The 3-D scene of a sketch: a body shape, non-standard proportions
//! ([`crate::body::proportions`], drawn at random by [`random_proportions`]), a pose applied by IK
//! and skinning ([`crate::body::retarget`]), and a near-frontal weak-perspective camera that fits
//! the figure into the image.
//!
//! The result is the ground-truth *rest* mesh (outside the PCA space when the proportions are not
//! 1) and, posed, the ground-truth joints.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use rand::Rng;

use crate::body::proportions::Proportions;
use crate::camera::WeakPerspective;
use crate::error::{ensure_finite, Error, Result};

/// Random proportions for a synthetic sketch: each factor uniform in the range documented on its
/// [`Proportions`] field, or all 1 with probability `1 − p_custom`.
pub fn random_proportions<R: Rng + ?Sized>(rng: &mut R, p_custom: f64) -> Proportions {
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

/// Camera angles in degrees: the rotation is `Rz(roll) · Rx(pitch) · Ry(yaw)` (yaw turns the
/// figure about the vertical, pitch tips it toward the viewer, roll tilts the image). Yaw 0 is a
/// front view, ±180° a back view, −90° the figure's left side toward the viewer (a left profile)
/// and +90° its right side.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CameraAngles {
    /// Turn about +Y; random range ±30°, valid range ±180°.
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

    /// The rotation matrix. Errors on non-finite angles, a yaw beyond ±180° or a pitch or roll
    /// beyond ±90°.
    pub fn rotation(&self) -> Result<Matrix3<f64>> {
        for (name, v, limit) in [
            ("camera yaw", self.yaw_deg, 180.0),
            ("camera pitch", self.pitch_deg, 90.0),
            ("camera roll", self.roll_deg, 90.0),
        ] {
            ensure_finite(name, v)?;
            if v.abs() > limit {
                return Err(Error::OutOfRange { name, detail: format!("{v}° is beyond ±{limit}°") });
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
        // A back view turns the figure's front (+Z) away from the viewer; a yaw of −90° shows its
        // left side (+X); yaw beyond ±180° and pitch beyond ±90° are refused.
        let back = CameraAngles { yaw_deg: 180.0, ..Default::default() }.rotation().unwrap();
        assert!((back * Vector3::z())[2] < -0.999);
        let left = CameraAngles { yaw_deg: -90.0, ..Default::default() }.rotation().unwrap();
        assert!((left * Vector3::x())[2] > 0.999);
        assert!(CameraAngles { yaw_deg: 181.0, ..Default::default() }.rotation().is_err());
        assert!(CameraAngles { pitch_deg: 91.0, ..Default::default() }.rotation().is_err());
    }
}

//! The weak-perspective camera of paper eq. (1), in DESIGN.md's convention:
//! `u = sx (R X)_x + tx`, `v = -sy (R X)_y + ty`, with X in metres (model frame, +Y up, +Z toward
//! the viewer) and (u, v) in pixels (image frame, y down). `R` near identity means the figure
//! faces the viewer.

use nalgebra::{Matrix3, Vector3};

use crate::error::{ensure_finite, Error, Result};

/// A weak-perspective camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeakPerspective {
    /// Horizontal scale, pixels per metre (> 0).
    pub sx: f64,
    /// Vertical scale, pixels per metre (> 0).
    pub sy: f64,
    /// Rotation from the model frame to the camera frame (in SO(3)).
    pub r: Matrix3<f64>,
    /// Image position of the model origin, pixels.
    pub t: [f64; 2],
}

impl WeakPerspective {
    /// Validates scales (finite, > 0), translation (finite) and rotation (finite, orthonormal with
    /// determinant +1 within 1e-6).
    pub fn validate(&self) -> Result<()> {
        ensure_finite("camera sx", self.sx)?;
        ensure_finite("camera sy", self.sy)?;
        ensure_finite("camera tx", self.t[0])?;
        ensure_finite("camera ty", self.t[1])?;
        if self.sx <= 0.0 || self.sy <= 0.0 {
            return Err(Error::OutOfRange { name: "camera scale", detail: format!("sx = {}, sy = {} must be > 0", self.sx, self.sy) });
        }
        if self.r.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite { name: "camera rotation", value: f64::NAN });
        }
        let ortho = (self.r.transpose() * self.r - Matrix3::identity()).norm();
        if ortho > 1e-6 || (self.r.determinant() - 1.0).abs() > 1e-6 {
            return Err(Error::OutOfRange { name: "camera rotation", detail: "not a rotation matrix".into() });
        }
        Ok(())
    }

    /// Projects a 3-D point (metres) to pixels.
    pub fn project(&self, x: &Vector3<f64>) -> [f64; 2] {
        let c = self.r * x;
        [self.sx * c.x + self.t[0], -self.sy * c.y + self.t[1]]
    }

    /// Depth of a point in the camera frame (larger = nearer the viewer).
    pub fn depth(&self, x: &Vector3<f64>) -> f64 {
        (self.r * x).z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_camera_flips_y_and_keeps_right_at_minus_x() {
        let cam = WeakPerspective { sx: 100.0, sy: 100.0, r: Matrix3::identity(), t: [256.0, 256.0] };
        cam.validate().unwrap();
        // A point up (+Y) maps to smaller v; the character's right (-X) maps to smaller u.
        assert_eq!(cam.project(&Vector3::new(0.0, 1.0, 0.0)), [256.0, 156.0]);
        assert_eq!(cam.project(&Vector3::new(-0.5, 0.0, 0.0)), [206.0, 256.0]);
        let bad = WeakPerspective { sx: -1.0, ..cam };
        assert!(bad.validate().is_err());
    }
}

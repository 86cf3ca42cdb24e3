//! The weak-perspective camera of paper eq. (1), in docs/design.md's convention:
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
            return Err(Error::OutOfRange {
                name: "camera scale",
                detail: format!("sx = {}, sy = {} must be > 0", self.sx, self.sy),
            });
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

    /// The camera of the same view in the image scaled by `f` (pixels × `f`): scales and
    /// translation times `f`, rotation kept.
    pub fn scaled_image(&self, f: f64) -> WeakPerspective {
        WeakPerspective { sx: self.sx * f, sy: self.sy * f, r: self.r, t: [self.t[0] * f, self.t[1] * f] }
    }

    /// Projects a 3-D point (metres) to pixels.
    pub fn project(&self, x: &Vector3<f64>) -> [f64; 2] {
        let c = self.r * x;
        [self.sx * c.x + self.t[0], -self.sy * c.y + self.t[1]]
    }

    /// The camera with its rotation kept and its scales and translation refitted in closed form
    /// so that `points[k]` (metres, model frame) project onto `targets` (`(k, [u, v])`, pixels):
    /// `sx, tx` minimise Σ (sx (R X_k)_x + tx − u_k)² and `sy, ty` minimise
    /// Σ (−sy (R X_k)_y + ty − v_k)² (two independent 1-D least-squares lines). A single
    /// weak-perspective view cannot tell a small near figure from a large far one, so this gives
    /// any skeleton its own image scale. Errors: [`Error::Degenerate`] with fewer than two
    /// targets, targets that do not span an axis, or a non-positive fitted scale;
    /// [`Error::OutOfRange`] for a target index outside `points`.
    pub fn refit_scale(&self, points: &[[f64; 3]], targets: &[(usize, [f64; 2])]) -> Result<WeakPerspective> {
        // Per axis: n, Σa, Σb, Σa², Σab.
        let mut acc = [[0.0f64; 5]; 2];
        for &(k, q) in targets {
            let p = points.get(k).ok_or_else(|| Error::OutOfRange {
                name: "camera refit target",
                detail: format!("joint {k} of {}", points.len()),
            })?;
            let c = self.r * Vector3::from(*p);
            for (axis, a) in [(0, c.x), (1, -c.y)] {
                let b = q[axis];
                let s = &mut acc[axis];
                s[0] += 1.0;
                s[1] += a;
                s[2] += b;
                s[3] += a * a;
                s[4] += a * b;
            }
        }
        let mut fitted = [(0.0, 0.0); 2];
        for (axis, [n, sa, sb, saa, sab]) in acc.into_iter().enumerate() {
            let den = n * saa - sa * sa;
            if n < 2.0 || den.abs() < 1e-12 {
                return Err(Error::Degenerate("cannot refit the camera: the joints do not span the image".into()));
            }
            let scale = (n * sab - sa * sb) / den;
            fitted[axis] = (scale, (sb - scale * sa) / n);
        }
        let [(sx, tx), (sy, ty)] = fitted;
        if !(sx > 0.0 && sy > 0.0) {
            return Err(Error::Degenerate(format!("camera refit gave scales {sx}, {sy}")));
        }
        Ok(WeakPerspective { sx, sy, r: self.r, t: [tx, ty] })
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

    #[test]
    fn refit_scale_recovers_a_camera_and_rejects_degenerate_targets() {
        let r = nalgebra::Rotation3::from_euler_angles(0.1, 0.4, -0.05).into_inner();
        let truth = WeakPerspective { sx: 120.0, sy: 130.0, r, t: [40.0, 300.0] };
        let pts = [[0.0, 0.0, 0.0], [0.2, 1.1, 0.1], [-0.3, 0.5, 0.0], [0.1, -0.8, 0.2]];
        let targets: Vec<(usize, [f64; 2])> = (0..4).map(|k| (k, truth.project(&Vector3::from(pts[k])))).collect();
        let start = WeakPerspective { sx: 1.0, sy: 1.0, r, t: [0.0, 0.0] };
        let c = start.refit_scale(&pts, &targets).unwrap();
        assert!((c.sx - 120.0).abs() < 1e-9 && (c.sy - 130.0).abs() < 1e-9, "{c:?}");
        assert!((c.t[0] - 40.0).abs() < 1e-9 && (c.t[1] - 300.0).abs() < 1e-9, "{c:?}");
        // Twice the skeleton needs half the scale and keeps the image.
        let big: Vec<[f64; 3]> = pts.iter().map(|p| [2.0 * p[0], 2.0 * p[1], 2.0 * p[2]]).collect();
        assert!((start.refit_scale(&big, &targets).unwrap().sx - 60.0).abs() < 1e-9);
        assert!(matches!(start.refit_scale(&pts, &targets[..1]), Err(Error::Degenerate(_))));
        let same = [(0, [1.0, 1.0]), (0, [2.0, 2.0])];
        assert!(matches!(start.refit_scale(&pts, &same), Err(Error::Degenerate(_))));
        assert!(matches!(start.refit_scale(&pts, &[(9, [0.0, 0.0]), (1, [1.0, 1.0])]), Err(Error::OutOfRange { .. })));
        // A mirrored target set gives a negative scale.
        let mirrored: Vec<(usize, [f64; 2])> = targets.iter().map(|&(k, q)| (k, [-q[0], q[1]])).collect();
        assert!(matches!(start.refit_scale(&pts, &mirrored), Err(Error::Degenerate(_))));
    }
}

//! The unit and up axis an FBX or USD file is written in ([`ExportFrame`]). The library's model
//! frame is metres, right-handed, +Y up, +Z toward the viewer (the character faces +Z, its
//! right side at −X). A file may instead be in centimetres and/or Z-up: Z-up turns the model
//! frame +90° about X, (x, y, z) → (x, −z, y), so up becomes +Z and the character faces −Y
//! (the convention of Blender, 3ds Max and Unreal); X stays the character's left. Data are
//! written in that frame (vertices, normals, bind matrices, bone transforms), not by a
//! transform on a parent node. glTF is always metres, Y-up (its specification).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::error::{Error, Result};

/// The length unit of an exported file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Units {
    /// Metres: one file unit is 1 m. Default.
    #[default]
    Metres,
    /// Centimetres: one file unit is 1 cm (coordinates are 100× the metre values).
    Centimetres,
}

impl Units {
    /// Parses `m` or `cm`. Errors: anything else ([`Error::OutOfRange`], naming the value).
    pub fn parse(s: &str) -> Result<Units> {
        match s {
            "m" => Ok(Units::Metres),
            "cm" => Ok(Units::Centimetres),
            _ => Err(Error::OutOfRange { name: "units", detail: format!("{s:?}: expected m or cm") }),
        }
    }

    /// File units per metre: 1 or 100.
    pub fn per_metre(self) -> f64 {
        match self {
            Units::Metres => 1.0,
            Units::Centimetres => 100.0,
        }
    }

    /// Centimetres per file unit (FBX's `UnitScaleFactor`): 100 or 1.
    pub fn centimetres(self) -> f64 {
        100.0 / self.per_metre()
    }

    /// Metres per file unit (USD's `metersPerUnit`): 1 or 0.01.
    pub fn metres(self) -> f64 {
        1.0 / self.per_metre()
    }
}

/// The up axis of an exported file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// +Y up, the character facing +Z (the library's own frame). Default.
    #[default]
    Y,
    /// +Z up, the character facing −Y: the model frame turned +90° about X.
    Z,
}

impl UpAxis {
    /// Parses `y` or `z` (either case). Errors: anything else ([`Error::OutOfRange`], naming
    /// the value).
    pub fn parse(s: &str) -> Result<UpAxis> {
        match s {
            "y" | "Y" => Ok(UpAxis::Y),
            "z" | "Z" => Ok(UpAxis::Z),
            _ => Err(Error::OutOfRange { name: "up axis", detail: format!("{s:?}: expected y or z") }),
        }
    }
}

/// The unit and up axis of an FBX or USD file. `Default`: metres, Y-up (the model frame).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExportFrame {
    /// Length unit.
    pub units: Units,
    /// Up axis.
    pub up: UpAxis,
}

impl ExportFrame {
    /// The rotation from the model frame to the file's axes: the identity for Y-up, +90° about
    /// X for Z-up.
    pub fn rotation(&self) -> UnitQuaternion<f64> {
        match self.up {
            UpAxis::Y => UnitQuaternion::identity(),
            UpAxis::Z => UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2),
        }
    }

    /// A position (model frame, metres) in the file's axes and unit.
    /// The default frame returns it unchanged, bit for bit.
    pub fn point(&self, p: Vector3<f64>) -> Vector3<f64> {
        let turned = match self.up {
            UpAxis::Y => p,
            UpAxis::Z => self.rotation() * p,
        };
        match self.units {
            Units::Metres => turned,
            Units::Centimetres => turned * 100.0,
        }
    }

    /// A single-precision position, as [`ExportFrame::point`]. The default frame returns it
    /// unchanged, bit for bit.
    pub fn point_f32(&self, p: [f32; 3]) -> [f32; 3] {
        if *self == ExportFrame::default() {
            return p;
        }
        let q = self.point(Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        [q.x as f32, q.y as f32, q.z as f32]
    }

    /// A direction (a unit normal) in the file's axes: rotated, not scaled. The default frame
    /// returns it unchanged, bit for bit.
    pub fn direction_f32(&self, n: [f32; 3]) -> [f32; 3] {
        if self.up == UpAxis::Y {
            return n;
        }
        let q = self.rotation() * Vector3::new(n[0] as f64, n[1] as f64, n[2] as f64);
        [q.x as f32, q.y as f32, q.z as f32]
    }

    /// A bone's global transform (model frame, metres) in the file's frame: the same physical
    /// axes (bone +Y still along the bone) expressed in the file's axes, its origin in the
    /// file's unit; no scale, so a bone's local space is in the file's unit too.
    pub fn global(&self, g: &Isometry3<f64>) -> Isometry3<f64> {
        let (t, q) = self.root_local(g.translation.vector, g.rotation);
        Isometry3::from_parts(Translation3::from(t), q)
    }

    /// A root bone's local transform (relative to the model frame: translation, rotation) in
    /// the file's frame, as [`ExportFrame::global`].
    pub fn root_local(&self, t: Vector3<f64>, q: UnitQuaternion<f64>) -> (Vector3<f64>, UnitQuaternion<f64>) {
        match self.up {
            UpAxis::Y => (self.point(t), q),
            UpAxis::Z => (self.point(t), self.rotation() * q),
        }
    }

    /// A child bone's local transform (relative to its parent bone) in the file's frame: the
    /// rotation is unchanged (both bones' axes turn alike), the translation scaled to the unit.
    pub fn child_local(&self, t: Vector3<f64>, q: UnitQuaternion<f64>) -> (Vector3<f64>, UnitQuaternion<f64>) {
        match self.units {
            Units::Metres => (t, q),
            Units::Centimetres => (t * 100.0, q),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Z-up turns up (+Y) to +Z and the facing direction (+Z) to −Y, keeps X; centimetres scale
    /// positions by 100 and leave directions alone; composing the parent's and the child's
    /// converted transforms gives the child's converted global transform.
    #[test]
    fn axes_units_and_composition() {
        let z_cm = ExportFrame { units: Units::Centimetres, up: UpAxis::Z };
        let p = z_cm.point(Vector3::new(1.0, 2.0, 3.0));
        assert!((p - Vector3::new(100.0, -300.0, 200.0)).norm() < 1e-9, "{p}");
        assert_eq!(z_cm.direction_f32([0.0, 1.0, 0.0]).map(|c| c.round()), [0.0, 0.0, 1.0]);
        assert_eq!(z_cm.direction_f32([0.0, 0.0, 1.0]).map(|c| c.round()), [0.0, -1.0, 0.0]);
        assert_eq!(ExportFrame::default().point_f32([0.1, 0.2, 0.3]), [0.1, 0.2, 0.3]);
        let parent = Isometry3::new(Vector3::new(0.1, 1.0, -0.2), Vector3::new(0.3, -0.2, 0.5));
        let local = Isometry3::new(Vector3::new(0.0, 0.25, 0.02), Vector3::new(-0.4, 0.1, 0.2));
        let child = parent * local;
        for frame in [ExportFrame::default(), z_cm, ExportFrame { units: Units::Metres, up: UpAxis::Z }] {
            let (t, q) = frame.child_local(local.translation.vector, local.rotation);
            let composed = frame.global(&parent) * Isometry3::from_parts(Translation3::from(t), q);
            let want = frame.global(&child);
            assert!((composed.to_homogeneous() - want.to_homogeneous()).abs().max() < 1e-9, "{frame:?}");
            // A point in the child's space lands where the converted model-frame point does.
            let x = Vector3::new(0.05, 0.1, -0.03);
            let m = child * nalgebra::Point3::from(x);
            let x_file = x * frame.units.per_metre();
            let got = want * nalgebra::Point3::from(x_file);
            assert!((got.coords - frame.point(m.coords)).norm() < 1e-9);
        }
        assert!(matches!(Units::parse("km"), Err(Error::OutOfRange { name: "units", .. })));
        assert!(matches!(UpAxis::parse("x"), Err(Error::OutOfRange { name: "up axis", .. })));
        assert_eq!((Units::parse("cm").unwrap(), UpAxis::parse("Z").unwrap()), (Units::Centimetres, UpAxis::Z));
        assert_eq!((Units::Centimetres.centimetres(), Units::Metres.centimetres()), (1.0, 100.0));
        assert_eq!(Units::Centimetres.metres(), 0.01);
    }
}

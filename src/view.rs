//! Views of a turnaround (a model sheet): the same character in the same pose drawn from the
//! front, either side and the back. A labelled view's camera is the front camera turned about the
//! body's vertical axis (model +Y) by the label's yaw: `R_view = R_front · R_y(yaw)`, with
//! `R_y(θ) = [[cos θ, 0, sin θ], [0, 1, 0], [−sin θ, 0, cos θ]]`.

use nalgebra::Matrix3;

use crate::camera::WeakPerspective;
use crate::error::{Error, Result};

/// Which view of a turnaround an image is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ViewLabel {
    /// The front view (yaw 0°): the pipeline's main image.
    Front,
    /// The side view (yaw +90°): the character's right side, facing image right.
    Side,
    /// The other side view (yaw −90°): the character's left side, facing image left.
    SideLeft,
    /// The back view (yaw 180°).
    Back,
}

impl ViewLabel {
    /// Every label, front first.
    pub const ALL: [ViewLabel; 4] = [ViewLabel::Front, ViewLabel::Side, ViewLabel::SideLeft, ViewLabel::Back];

    /// The view's yaw relative to the front view, degrees.
    pub fn yaw_deg(self) -> f64 {
        match self {
            ViewLabel::Front => 0.0,
            ViewLabel::Side => 90.0,
            ViewLabel::SideLeft => -90.0,
            ViewLabel::Back => 180.0,
        }
    }

    /// `front`, `side`, `side_left` or `back`.
    pub fn name(self) -> &'static str {
        match self {
            ViewLabel::Front => "front",
            ViewLabel::Side => "side",
            ViewLabel::SideLeft => "side_left",
            ViewLabel::Back => "back",
        }
    }

    /// Parses [`ViewLabel::name`] (case-insensitive). Errors: any other text
    /// ([`Error::OutOfRange`]).
    pub fn parse(text: &str) -> Result<ViewLabel> {
        ViewLabel::ALL.into_iter().find(|l| l.name().eq_ignore_ascii_case(text.trim())).ok_or_else(|| {
            Error::OutOfRange { name: "view label", detail: format!("{text:?} is not front, side, side_left or back") }
        })
    }

    /// The side view facing the other way ([`ViewLabel::Side`] ↔ [`ViewLabel::SideLeft`]): the
    /// label a side drawing has when its depth is mirrored; `None` for the front and back.
    pub fn other_side(self) -> Option<ViewLabel> {
        match self {
            ViewLabel::Side => Some(ViewLabel::SideLeft),
            ViewLabel::SideLeft => Some(ViewLabel::Side),
            ViewLabel::Front | ViewLabel::Back => None,
        }
    }

    /// `R_y(yaw)` of the label (module doc).
    pub fn turn(self) -> Matrix3<f64> {
        let (s, c) = self.yaw_deg().to_radians().sin_cos();
        Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
    }

    /// The front camera's rotation turned to this view (`R_front · R_y(yaw)`), scales and
    /// translation kept.
    pub fn camera_from_front(self, front: &WeakPerspective) -> WeakPerspective {
        WeakPerspective { r: front.r * self.turn(), ..*front }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn the_side_view_sees_the_right_side_facing_image_right() {
        let front = WeakPerspective { sx: 100.0, sy: 100.0, r: Matrix3::identity(), t: [50.0, 50.0] };
        let side = ViewLabel::Side.camera_from_front(&front);
        // A point in front of the body (+Z) lands to the right of the pelvis in the side view.
        let nose = side.project(&Vector3::new(0.0, 0.0, 0.1));
        assert!((nose[0] - 60.0).abs() < 1e-9 && (nose[1] - 50.0).abs() < 1e-9);
        // The body's right (−X) is nearer the side camera (its +Z) than its left.
        let depth = |x: f64| (side.r * Vector3::new(x, 0.0, 0.0)).z;
        assert!(depth(-0.2) > depth(0.2));
        // The back view mirrors the front's horizontal axis.
        let back = ViewLabel::Back.camera_from_front(&front);
        assert!((back.project(&Vector3::new(0.2, 0.0, 0.0))[0] - 30.0).abs() < 1e-9);
        // The left side view: the nose lands left of the pelvis, the body's left nearer.
        let left = ViewLabel::SideLeft.camera_from_front(&front);
        assert!((left.project(&Vector3::new(0.0, 0.0, 0.1))[0] - 40.0).abs() < 1e-9);
        assert!((left.r * Vector3::new(0.2, 0.0, 0.0)).z > (left.r * Vector3::new(-0.2, 0.0, 0.0)).z);
        assert_eq!(ViewLabel::Side.other_side(), Some(ViewLabel::SideLeft));
        assert_eq!(ViewLabel::SideLeft.other_side(), Some(ViewLabel::Side));
        assert_eq!(ViewLabel::Back.other_side(), None);
    }

    #[test]
    fn labels_parse_by_name_only() {
        for l in ViewLabel::ALL {
            assert_eq!(ViewLabel::parse(&l.name().to_uppercase()).unwrap(), l);
        }
        assert!(matches!(ViewLabel::parse("three-quarter"), Err(Error::OutOfRange { .. })));
        assert!(ViewLabel::parse("").is_err());
    }
}

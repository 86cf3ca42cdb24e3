//! Regions of interest for the landmark model, as MediaPipe's pose graph builds them: a square,
//! possibly rotated rectangle in image pixels (continuous coordinates: pixel `i` covers
//! `[i, i + 1)`), from the sketch's ink box (first pass) or from the model's own alignment
//! landmarks (second pass).

use crate::error::{Error, Result};
use crate::image::ImageView;

/// Scale from a box's larger side (first pass) or from the alignment box (second pass) to the
/// ROI side, as MediaPipe's `RectTransformationCalculator` for pose (1.25, square long side).
pub const ROI_SCALE: f64 = 1.25;

/// A gray value below this (on 0..255, RGB averaged, RGBA over white) is ink for the ink box:
/// 40 levels under white keeps paper grain and JPEG ringing out.
pub const INK_LEVEL: u8 = 215;

/// A square crop region: centre (px), side (px) and rotation (radians; positive turns the crop's
/// up direction towards the image's +x, as MediaPipe's `NormalizedRect::rotation`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roi {
    /// Centre x, px.
    pub cx: f64,
    /// Centre y, px.
    pub cy: f64,
    /// Side length, px (> 0).
    pub size: f64,
    /// Rotation, radians in [-π, π).
    pub rotation: f64,
}

impl Roi {
    /// The upright square ROI of side [`ROI_SCALE`] × the larger side of box `(x1, y1, x2, y2)`
    /// (px), centred on it. Errors: `Degenerate` for an empty or non-finite box.
    pub fn from_box(b: [f64; 4]) -> Result<Self> {
        let side = (b[2] - b[0]).max(b[3] - b[1]);
        if !(side > 0.0) || b.iter().any(|v| !v.is_finite()) {
            return Err(Error::Degenerate(format!("ROI box {b:?} is empty")));
        }
        Ok(Self { cx: 0.5 * (b[0] + b[2]), cy: 0.5 * (b[1] + b[3]), size: ROI_SCALE * side, rotation: 0.0 })
    }

    /// MediaPipe's ROI from the pose's two alignment points (image px): centre at `center` (the
    /// hips' midpoint), side [`ROI_SCALE`] × 2 × the distance to `scale_point`, rotated so that the
    /// direction centre → scale point becomes the crop's up. Errors: `Degenerate` when the
    /// points coincide or are not finite.
    pub fn from_alignment(center: [f64; 2], scale_point: [f64; 2]) -> Result<Self> {
        let (dx, dy) = (scale_point[0] - center[0], scale_point[1] - center[1]);
        let dist = dx.hypot(dy);
        if !(dist > 1e-6) || !dist.is_finite() || !center[0].is_finite() || !center[1].is_finite() {
            return Err(Error::Degenerate(format!("alignment points {center:?} and {scale_point:?} coincide")));
        }
        let rotation = normalize_angle(std::f64::consts::FRAC_PI_2 - (-dy).atan2(dx));
        Ok(Self { cx: center[0], cy: center[1], size: ROI_SCALE * 2.0 * dist, rotation })
    }

    /// Maps a point of the crop, normalised to [0, 1]² (0 = the ROI's top-left corner before
    /// rotation), to image px.
    pub fn to_image(&self, u: f64, v: f64) -> [f64; 2] {
        let (s, c) = self.rotation.sin_cos();
        let (x, y) = (u - 0.5, v - 0.5);
        [self.cx + self.size * (c * x - s * y), self.cy + self.size * (s * x + c * y)]
    }
}

/// Sides of the retry ROIs ([`retry_rois`]) over the ink box's larger side. The ink box's own ROI
/// ([`ROI_SCALE`]) misses when the ink is not the figure: a photo's or a stylised photo's
/// background fills the page, so the figure is smaller or off the page's centre, or light
/// strokes leave the network unsure at that framing. Chosen on PARSE training photos 1–100 through
/// the proxy benchmark's stylisations (`examples/landmark_roi.rs`; docs/benchmarks-history.md,
/// "Detector backends: BlazePose, calibrated confidences, `auto`").
pub const RETRY_SCALES: [f64; 3] = [0.8, 1.0, 1.6];

/// The upright square ROIs tried when the ink box's ROI leaves the network unsure: centred on
/// ink box `b` (px), sides [`RETRY_SCALES`] × its larger side.
pub fn retry_rois(b: [f64; 4]) -> Vec<Roi> {
    let side = (b[2] - b[0]).max(b[3] - b[1]);
    let (cx, cy) = (0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3]));
    RETRY_SCALES.iter().map(|&k| Roi { cx, cy, size: k * side, rotation: 0.0 }).collect()
}

/// An angle wrapped to [-π, π).
fn normalize_angle(a: f64) -> f64 {
    use std::f64::consts::PI;
    a - 2.0 * PI * ((a + PI) / (2.0 * PI)).floor()
}

/// The bounding box `(x1, y1, x2, y2)` (px, exclusive ends) of the pixels darker than
/// [`INK_LEVEL`], or `None` on a blank page.
pub fn ink_box(image: &ImageView<'_>) -> Option<[f64; 4]> {
    let (w, h, ch) = (image.width(), image.height(), image.channels());
    let (mut x1, mut y1, mut x2, mut y2) = (usize::MAX, usize::MAX, 0, 0);
    for y in 0..h {
        let row = image.row(y);
        for x in 0..w {
            let p = &row[x * ch..(x + 1) * ch];
            if gray_over_white(p) < INK_LEVEL {
                x1 = x1.min(x);
                x2 = x2.max(x + 1);
                y1 = y1.min(y);
                y2 = y2.max(y + 1);
            }
        }
    }
    (x2 > 0).then_some([x1 as f64, y1 as f64, x2 as f64, y2 as f64])
}

/// Mean of the channels of a gray, RGB or RGBA pixel (RGBA composited over white).
fn gray_over_white(p: &[u8]) -> u8 {
    let rgb = super::crop::rgb_of(p);
    ((rgb[0] as u32 + rgb[1] as u32 + rgb[2] as u32) / 3) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upright_figure_gives_no_rotation_and_head_up_in_the_crop() {
        let r = Roi::from_alignment([100.0, 200.0], [100.0, 100.0]).unwrap();
        assert!(r.rotation.abs() < 1e-12);
        assert!((r.size - 250.0).abs() < 1e-9);
        let top = r.to_image(0.5, 0.0);
        assert!((top[0] - 100.0).abs() < 1e-9 && (top[1] - 75.0).abs() < 1e-9);
    }

    #[test]
    fn figure_lying_head_right_turns_crop_up_to_plus_x() {
        let r = Roi::from_alignment([100.0, 100.0], [180.0, 100.0]).unwrap();
        assert!((r.rotation - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let top = r.to_image(0.5, 0.0);
        assert!((top[0] - 200.0).abs() < 1e-9 && (top[1] - 100.0).abs() < 1e-9, "{top:?}");
    }

    /// The retry ROIs are upright squares centred on the ink box, one per [`RETRY_SCALES`] times
    /// its larger side.
    #[test]
    fn retry_rois_are_centred_on_the_box_at_each_scale() {
        let rois = retry_rois([10.0, 20.0, 50.0, 120.0]);
        let want: Vec<Roi> =
            RETRY_SCALES.iter().map(|&k| Roi { cx: 30.0, cy: 70.0, size: k * 100.0, rotation: 0.0 }).collect();
        assert_eq!(rois, want);
        let wide = retry_rois([0.0, 0.0, 80.0, 10.0]);
        assert_eq!((wide[2].cx, wide[2].cy, wide[2].size), (40.0, 5.0, 1.6 * 80.0));
    }

    /// Angles are wrapped to [−π, π): a figure lying head left turns the crop's up to −x, one
    /// upside down to −π.
    #[test]
    fn rotations_are_wrapped_to_a_half_open_turn() {
        use std::f64::consts::{FRAC_PI_2, PI};
        let left = Roi::from_alignment([100.0, 100.0], [20.0, 100.0]).unwrap();
        assert!((left.rotation + FRAC_PI_2).abs() < 1e-12, "{}", left.rotation);
        let down = Roi::from_alignment([100.0, 100.0], [100.0, 180.0]).unwrap();
        assert!((down.rotation + PI).abs() < 1e-12, "{}", down.rotation);
        for (a, want) in [
            (0.5, 0.5),
            (2.5, 2.5),
            (3.1, 3.1),
            (-3.1, -3.1),
            (PI, -PI),
            (-PI, -PI),
            (3.0 * PI + 0.25, -PI + 0.25),
            (-2.5 * PI, -0.5 * PI),
        ] {
            assert!((normalize_angle(a) - want).abs() < 1e-12, "{a}: {}", normalize_angle(a));
        }
    }

    #[test]
    fn boxes_and_blank_pages() {
        assert!(Roi::from_box([0.0, 0.0, 0.0, 0.0]).is_err());
        assert!(Roi::from_alignment([1.0, 1.0], [1.0, 1.0]).is_err());
        let r = Roi::from_box([10.0, 20.0, 50.0, 120.0]).unwrap();
        assert_eq!((r.cx, r.cy, r.size, r.rotation), (30.0, 70.0, 125.0, 0.0));
        let mut px = vec![255u8; 40 * 30];
        let blank = ImageView::gray(&px, 40, 30).unwrap();
        assert_eq!(ink_box(&blank), None);
        px[5 * 40 + 7] = 0;
        px[20 * 40 + 30] = 100;
        let inked = ImageView::gray(&px, 40, 30).unwrap();
        assert_eq!(ink_box(&inked), Some([7.0, 5.0, 31.0, 21.0]));
    }
}

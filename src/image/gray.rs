//! Colour to gray conversion with OpenCV's `COLOR_RGB2GRAY` weights and rounding.

use rayon::prelude::*;

use super::view::{GrayImage, ImageView};
use crate::error::Result;

/// Fixed-point weights of OpenCV 4.x's 8-bit RGB to gray conversion (0.299, 0.587, 0.114 scaled
/// by 2^15; they sum to exactly 2^15). Checked against `cv::cvtColor` on all 2^24 colours.
const R_WEIGHT: u32 = 9798;
const G_WEIGHT: u32 = 19235;
const B_WEIGHT: u32 = 3735;
const SHIFT: u32 = 15;

/// Gray value of one RGB pixel, exactly as `cv::cvtColor(..., COLOR_RGB2GRAY)` computes it for
/// 8-bit images: `(9798 R + 19235 G + 3735 B + 2^14) >> 15`.
#[inline]
pub fn rgb_to_gray_pixel(r: u8, g: u8, b: u8) -> u8 {
    ((r as u32 * R_WEIGHT + g as u32 * G_WEIGHT + b as u32 * B_WEIGHT + (1 << (SHIFT - 1))) >> SHIFT) as u8
}

/// Converts any view to a packed gray image. Gray views are copied; RGB and RGBA views (channel
/// order R, G, B[, A]; alpha ignored) use OpenCV's `COLOR_RGB2GRAY` arithmetic.
pub fn to_gray(src: &ImageView<'_>) -> Result<GrayImage> {
    let (w, h, c) = (src.width(), src.height(), src.channels());
    let mut data = vec![0u8; w * h];
    // Rows convert independently: in parallel (rayon; the same bytes on any thread count).
    data.par_chunks_exact_mut(w.max(1)).enumerate().take(h).for_each(|(y, out)| {
        let row = src.row(y);
        if c == 1 {
            out.copy_from_slice(&row[..w]);
        } else {
            for (o, p) in out.iter_mut().zip(row.chunks_exact(c)) {
                *o = rgb_to_gray_pixel(p[0], p[1], p[2]);
            }
        }
    });
    GrayImage::from_vec(w, h, data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gray_weights_match_opencv_values() {
        // Values cv::cvtColor(COLOR_RGB2GRAY) gives on OpenCV 4.6 (the whole colour cube is
        // compared in cpp_tests/canny_vs_opencv through colour Canny inputs).
        assert_eq!(rgb_to_gray_pixel(255, 255, 255), 255);
        assert_eq!(rgb_to_gray_pixel(255, 0, 0), 76);
        assert_eq!(rgb_to_gray_pixel(0, 255, 0), 150);
        assert_eq!(rgb_to_gray_pixel(0, 0, 255), 29);
    }

    #[test]
    fn rgba_alpha_is_ignored_and_stride_respected() {
        let data = [255, 0, 0, 9, 0, 0, 0, 255, 0, 0, 255, 0, 0, 0, 0, 0];
        let view = ImageView::new(&data, 2, 2, 4, 8).unwrap();
        let g = to_gray(&view).unwrap();
        assert_eq!(g.as_bytes(), &[76, 0, 29, 0]);
    }
}

//! Colour to gray conversion with OpenCV's `COLOR_RGB2GRAY` weights and rounding.

use super::view::{GrayImage, ImageView};
use crate::error::Result;

/// Fixed-point weights of OpenCV's RGB to gray conversion (0.299, 0.587, 0.114 scaled by 2^14).
const R_WEIGHT: u32 = 4899;
const G_WEIGHT: u32 = 9617;
const B_WEIGHT: u32 = 1868;
const SHIFT: u32 = 14;

/// Gray value of one RGB pixel, exactly as `cv::cvtColor(..., COLOR_RGB2GRAY)` computes it for
/// 8-bit images: `(4899 R + 9617 G + 1868 B + 2^13) >> 14`.
#[inline]
pub fn rgb_to_gray_pixel(r: u8, g: u8, b: u8) -> u8 {
    ((r as u32 * R_WEIGHT + g as u32 * G_WEIGHT + b as u32 * B_WEIGHT + (1 << (SHIFT - 1))) >> SHIFT) as u8
}

/// Converts any view to a packed gray image. Gray views are copied; RGB and RGBA views (channel
/// order R, G, B[, A]; alpha ignored) use OpenCV's `COLOR_RGB2GRAY` arithmetic.
pub fn to_gray(src: &ImageView<'_>) -> Result<GrayImage> {
    let (w, h, c) = (src.width(), src.height(), src.channels());
    let mut data = Vec::with_capacity(w * h);
    for y in 0..h {
        let row = src.row(y);
        if c == 1 {
            data.extend_from_slice(row);
        } else {
            data.extend(row.chunks_exact(c).map(|p| rgb_to_gray_pixel(p[0], p[1], p[2])));
        }
    }
    GrayImage::from_vec(w, h, data)
}

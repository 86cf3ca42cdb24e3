//! Reading images from disk (PNG, JPEG) and writing gray PNGs atomically.

use std::path::Path;

use super::gray::rgb_to_gray_pixel;
use super::view::{check_size, GrayImage};
use crate::error::{Error, Result};

/// Loads a PNG or JPEG file as gray (colour converted with OpenCV's `COLOR_RGB2GRAY` weights,
/// alpha ignored). Errors name the file: missing/unreadable (`Io`), not an image or truncated
/// (`Decode`), oversized (`ImageTooLarge`).
pub fn load_image(path: &Path) -> Result<GrayImage> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    let decode_err = |reason: String| Error::Decode { path: path.to_path_buf(), reason };
    let reader = image::ImageReader::new(std::io::Cursor::new(&bytes))
        .with_guessed_format()
        .map_err(|e| decode_err(e.to_string()))?;
    if reader.format().is_none() {
        return Err(decode_err("unknown format (expected PNG or JPEG)".into()));
    }
    let (w, h) = reader.into_dimensions().map_err(|e| decode_err(e.to_string()))?;
    check_size(w as usize, h as usize)?;
    let img = image::load_from_memory(&bytes).map_err(|e| decode_err(e.to_string()))?;
    let rgb = img.to_rgb8();
    let data = rgb.pixels().map(|p| rgb_to_gray_pixel(p[0], p[1], p[2])).collect();
    GrayImage::from_vec(w as usize, h as usize, data)
}

/// Writes `img` as an 8-bit gray PNG through a temporary file renamed into place, so a failure
/// never leaves a half-written file at `path`.
pub fn save_gray_png(img: &GrayImage, path: &Path) -> Result<()> {
    let mut encoded = Vec::new();
    image::codecs::png::PngEncoder::new(&mut encoded)
        .write_image(img.as_bytes(), img.width() as u32, img.height() as u32, image::ExtendedColorType::L8)
        .map_err(|e| Error::Decode { path: path.to_path_buf(), reason: format!("PNG encoding failed: {e}") })?;
    crate::fsutil::write_atomic(path, &encoded)
}

use image::ImageEncoder;

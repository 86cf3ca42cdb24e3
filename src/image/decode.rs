//! Reading images from disk (PNG, JPEG) and writing gray PNGs atomically.

use std::path::Path;

use super::gray::to_gray;
use super::rgb::load_rgb_image;
use super::view::GrayImage;
use crate::error::{Error, Result};

/// Loads a PNG or JPEG file as gray (colour converted with OpenCV's `COLOR_RGB2GRAY` weights,
/// alpha ignored). Errors name the file: missing/unreadable (`Io`), not an image or truncated
/// (`Decode`), oversized (`ImageTooLarge`).
pub fn load_image(path: &Path) -> Result<GrayImage> {
    to_gray(&load_rgb_image(path)?.view())
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

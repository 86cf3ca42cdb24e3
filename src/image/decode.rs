//! Reading images from disk (PNG, JPEG) as gray.

use std::path::Path;

use super::gray::to_gray;
use super::rgb::load_rgb_image;
use super::view::GrayImage;
use crate::error::Result;

/// Loads a PNG or JPEG file as gray (colour converted with OpenCV's `COLOR_RGB2GRAY` weights,
/// alpha ignored). Errors name the file: missing/unreadable (`Io`), not an image or truncated
/// (`Decode`), oversized (`ImageTooLarge`).
pub fn load_image(path: &Path) -> Result<GrayImage> {
    to_gray(&load_rgb_image(path)?.view())
}

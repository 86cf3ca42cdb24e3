//! Owned 8-bit RGB images and loading them from disk (the detector's HOG uses colour).

use std::path::Path;

use super::view::{check_size, ImageView};
use crate::error::{Error, Result};

/// An owned, tightly packed 8-bit RGB image (`data.len() == 3 * width * height`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbImage {
    width: usize,
    height: usize,
    data: Vec<u8>,
}

impl RgbImage {
    /// Takes ownership of packed RGB pixels. Errors unless `data.len() == 3 * width * height`.
    pub fn from_vec(width: usize, height: usize, data: Vec<u8>) -> Result<Self> {
        check_size(width, height)?;
        if data.len() != 3 * width * height {
            return Err(Error::BufferTooSmall {
                name: "pixels",
                len: data.len(),
                needed: 3 * width * height,
                unit: "bytes",
            });
        }
        Ok(Self { width, height, data })
    }
    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }
    /// The pixels, row-major, `3 * width` bytes per row.
    pub fn as_bytes(&self) -> &[u8] {
        &self.data
    }
    /// A borrowed 3-channel view.
    pub fn view(&self) -> ImageView<'_> {
        // The geometry was validated at construction, so this cannot fail.
        ImageView::new(&self.data, self.width, self.height, 3, 3 * self.width).unwrap_or_else(|_| unreachable!())
    }
}

/// Loads a PNG or JPEG file as 8-bit RGB: gray expanded, palettes resolved, and transparency
/// composited over white paper (a transparent background would otherwise decode as black and
/// hide the drawing). Errors name the file: `Io`, `Decode`, `ImageTooLarge`.
pub fn load_rgb_image(path: &Path) -> Result<RgbImage> {
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
    let rgb = if img.color().has_alpha() {
        img.to_rgba8().pixels().flat_map(|p| over_white(p.0)).collect()
    } else {
        img.to_rgb8().into_raw()
    };
    RgbImage::from_vec(w as usize, h as usize, rgb)
}

/// An RGBA pixel composited over white.
pub fn over_white(p: [u8; 4]) -> [u8; 3] {
    let a = p[3] as u32;
    [0, 1, 2].map(|c| ((p[c] as u32 * a + 255 * (255 - a) + 127) / 255) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_checked_and_missing_files_named() {
        assert!(matches!(
            RgbImage::from_vec(2, 2, vec![0; 11]),
            Err(Error::BufferTooSmall { len: 11, needed: 12, .. })
        ));
        let im = RgbImage::from_vec(2, 1, vec![1, 2, 3, 4, 5, 6]).unwrap();
        assert_eq!(im.view().row(0), &[1, 2, 3, 4, 5, 6]);
        assert!(matches!(load_rgb_image(Path::new("/nonexistent/x.png")), Err(Error::Io { .. })));
    }

    /// Transparent pixels become paper white, opaque ones keep their colour; palette PNGs load.
    #[test]
    fn transparency_is_composited_over_white_and_palettes_load() {
        assert_eq!(over_white([10, 20, 30, 255]), [10, 20, 30]);
        assert_eq!(over_white([0, 0, 0, 0]), [255, 255, 255]);
        let dir = std::env::temp_dir().join(format!("skb-rgba-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.png");
        image::RgbaImage::from_raw(2, 1, vec![0, 0, 0, 0, 200, 10, 10, 255]).unwrap().save(&path).unwrap();
        assert_eq!(load_rgb_image(&path).unwrap().as_bytes(), &[255, 255, 255, 200, 10, 10]);
        // An indexed (palette) PNG with a transparent entry.
        let pal = dir.join("p.png");
        let mut bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut bytes, 2, 1);
            enc.set_color(png::ColorType::Indexed);
            enc.set_depth(png::BitDepth::Eight);
            enc.set_palette(vec![0, 0, 255, 0, 255, 0]);
            enc.set_trns(vec![0, 255]);
            let mut w = enc.write_header().unwrap();
            w.write_image_data(&[0, 1]).unwrap();
        }
        std::fs::write(&pal, bytes).unwrap();
        assert_eq!(load_rgb_image(&pal).unwrap().as_bytes(), &[255, 255, 255, 0, 255, 0]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

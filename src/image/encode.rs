//! Writing PNGs: the library's one PNG encoder (8-bit gray, RGB or RGBA, the `png` crate's
//! default compression through `image`), to bytes or atomically to a file.

use std::borrow::Cow;
use std::path::Path;

use image::ImageEncoder;

use super::view::ImageView;
use crate::error::{Error, Result};

/// The PNG bytes of `image` (1 channel: gray, 3: RGB, 4: RGBA; any stride). Errors: the
/// encoder's ([`Error::CorruptData`]; it has none for a valid view).
pub fn encode_png(image: &ImageView<'_>) -> Result<Vec<u8>> {
    let (w, h, c) = (image.width(), image.height(), image.channels());
    let colour = match c {
        1 => image::ExtendedColorType::L8,
        3 => image::ExtendedColorType::Rgb8,
        _ => image::ExtendedColorType::Rgba8,
    };
    let packed: Cow<[u8]> = match image.packed() {
        Some(bytes) => Cow::Borrowed(bytes),
        None => Cow::Owned((0..h).flat_map(|y| image.row(y).iter().copied()).collect()),
    };
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(&packed, w as u32, h as u32, colour)
        .map_err(|e| Error::CorruptData(format!("PNG encoding failed: {e}")))?;
    Ok(bytes)
}

/// Writes `image` as a PNG ([`encode_png`]) through a temporary file renamed into place, so a
/// failure never leaves a half-written file at `path`. Errors: `Io` naming the file.
pub fn save_png(image: &ImageView<'_>, path: &Path) -> Result<()> {
    crate::fsutil::write_atomic(path, &encode_png(image)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gray, RGB and strided RGBA views round-trip through an independent decoder (`png`).
    #[test]
    fn pngs_decode_to_the_same_pixels() {
        let gray: Vec<u8> = (0..6 * 4).map(|i| (i * 10) as u8).collect();
        let rgb: Vec<u8> = (0..5 * 3 * 3).map(|i| (i * 7) as u8).collect();
        let mut rgba = vec![0u8; 3 * 20];
        for (i, b) in rgba.iter_mut().enumerate() {
            *b = (i * 3) as u8;
        }
        let cases = [
            (ImageView::new(&gray, 6, 4, 1, 6).unwrap(), png::ColorType::Grayscale),
            (ImageView::new(&rgb, 5, 3, 3, 15).unwrap(), png::ColorType::Rgb),
            (ImageView::new(&rgba, 4, 3, 4, 20).unwrap(), png::ColorType::Rgba),
        ];
        for (view, colour) in cases {
            let bytes = encode_png(&view).unwrap();
            let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().unwrap();
            let mut buf = vec![0; reader.output_buffer_size().unwrap()];
            let info = reader.next_frame(&mut buf).unwrap();
            assert_eq!(
                (info.width as usize, info.height as usize, info.color_type),
                (view.width(), view.height(), colour)
            );
            let want: Vec<u8> = (0..view.height()).flat_map(|y| view.row(y).to_vec()).collect();
            assert_eq!(&buf[..info.buffer_size()], &want[..]);
        }
    }
}

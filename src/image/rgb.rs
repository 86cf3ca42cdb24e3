//! Owned 8-bit RGB images and loading them from disk (the detector's HOG uses colour).

use std::path::Path;

use super::view::{check_size, ImageView};
use crate::error::{Error, Result, MAX_DECODED_PIXELS};

/// Largest image file the loaders read, in bytes (256 MiB). Larger files, and anything but a
/// regular file, are `Error::Io`.
pub const MAX_IMAGE_FILE_BYTES: u64 = 256 << 20;

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
    /// An image of `width` × `height` pixels all of colour `rgb`. Errors: empty or oversized
    /// images.
    pub fn filled(width: usize, height: usize, rgb: [u8; 3]) -> Result<Self> {
        check_size(width, height)?;
        Ok(Self { width, height, data: rgb.repeat(width * height) })
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
    /// The pixels for writing, row-major, `3 * width` bytes per row (the size is fixed).
    pub fn as_bytes_mut(&mut self) -> &mut [u8] {
        &mut self.data
    }
    /// A borrowed 3-channel view.
    pub fn view(&self) -> ImageView<'_> {
        // The geometry was validated at construction, so this cannot fail.
        ImageView::new(&self.data, self.width, self.height, 3, 3 * self.width).unwrap_or_else(|_| unreachable!())
    }
}

/// Loads a PNG or JPEG file as 8-bit RGB: gray expanded, palettes resolved, and transparency
/// composited over white paper (a transparent background would otherwise decode as black and
/// hide the drawing). Limits: [`MAX_IMAGE_FILE_BYTES`] on the file, [`MAX_DECODED_PIXELS`] and
/// 16384 px a side on the image (checked from the header, before decoding). JPEGs are decoded
/// strictly: a truncated or corrupt entropy stream is `Decode`, never a partly grey image.
/// Errors name the file: `Io` (missing, not a regular file, too big), `Decode`,
/// `ImageTooLarge`, `TooManyPixels`.
pub fn load_rgb_image(path: &Path) -> Result<RgbImage> {
    let bytes = crate::fsutil::read_capped(path, MAX_IMAGE_FILE_BYTES)?;
    decode_rgb_image(&bytes, path)
}

/// Decodes a PNG or JPEG file's bytes as [`load_rgb_image`] does (same limits, strict JPEG,
/// transparency over white); `path` only names the file in errors. Errors: `Decode`,
/// `ImageTooLarge`, `TooManyPixels`.
pub fn decode_rgb_image(bytes: &[u8], path: &Path) -> Result<RgbImage> {
    let decode_err = |reason: String| Error::Decode { path: path.to_path_buf(), reason };
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| decode_err(e.to_string()))?;
    if reader.format().is_none() {
        return Err(decode_err("unknown format (expected PNG or JPEG)".into()));
    }
    let format = reader.format();
    let (w, h) = reader.into_dimensions().map_err(|e| decode_err(e.to_string()))?;
    check_size(w as usize, h as usize)?;
    if w as usize * h as usize > MAX_DECODED_PIXELS {
        return Err(Error::TooManyPixels { width: w as usize, height: h as usize });
    }
    if format == Some(image::ImageFormat::Jpeg) {
        // Every 8 x 8 luma block costs at least one bit of Huffman code (its DC difference), so
        // a file with fewer bits than blocks cannot hold the image its header claims: it was cut
        // short, or it is a bomb whose decoder would fill the missing blocks and report success
        // (zune-jpeg's strict mode does so for a stream that ends early with a proper EOI).
        // zune-jpeg decodes Huffman-coded JPEGs only (no arithmetic coding), so the bound holds.
        let blocks = (w as usize).div_ceil(8) * (h as usize).div_ceil(8);
        if bytes.len().saturating_mul(8) < blocks {
            return Err(decode_err(format!(
                "truncated: {} bytes cannot hold the {w}x{h} image the header claims",
                bytes.len()
            )));
        }
        let rgb = decode_jpeg_strict(bytes).map_err(decode_err)?;
        return RgbImage::from_vec(w as usize, h as usize, rgb);
    }
    let img = image::load_from_memory(bytes).map_err(|e| decode_err(e.to_string()))?;
    let rgb = if img.color().has_alpha() {
        img.to_rgba8().pixels().flat_map(|p| over_white(p.0)).collect()
    } else {
        img.to_rgb8().into_raw()
    };
    RgbImage::from_vec(w as usize, h as usize, rgb)
}

/// Decodes a JPEG to packed RGB with zune-jpeg in strict mode (the decoder `image` uses, which
/// `image` runs non-strictly: it fills a truncated stream with grey and reports success).
fn decode_jpeg_strict(bytes: &[u8]) -> std::result::Result<Vec<u8>, String> {
    use zune_jpeg::zune_core::{bytestream::ZCursor, colorspace::ColorSpace, options::DecoderOptions};
    let options = DecoderOptions::default()
        .set_strict_mode(true)
        .set_max_width(crate::error::MAX_IMAGE_SIDE)
        .set_max_height(crate::error::MAX_IMAGE_SIDE)
        .jpeg_set_out_colorspace(ColorSpace::RGB);
    zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), options).decode().map_err(|e| e.to_string())
}

/// An RGBA pixel composited over white.
pub fn over_white(p: [u8; 4]) -> [u8; 3] {
    let a = p[3] as u32;
    [0, 1, 2].map(|c| ((p[c] as u32 * a + 255 * (255 - a) + 127) / 255) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::ImageEncoder;

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

    fn scratch(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("skb-rgb-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A 96 x 64 colour-gradient baseline JPEG.
    fn gradient_jpeg(quality: u8) -> Vec<u8> {
        let (w, h) = (96u32, 64u32);
        let px: Vec<u8> =
            (0..w * h).flat_map(|i| [(i % w * 2) as u8, (i / w * 3) as u8, ((i * 7) % 251) as u8]).collect();
        let mut out = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, quality)
            .encode(&px, w, h, image::ExtendedColorType::Rgb8)
            .unwrap();
        out
    }

    /// The strict decoder returns exactly what the `image` crate (the reference decoder path)
    /// returns for whole files: the shipped examples' JPEG fixtures and PARSE images when present.
    #[test]
    fn strict_jpeg_decoding_matches_the_image_crate() {
        let d = scratch("same");
        let mut files = vec![d.join("g.jpg")];
        std::fs::write(&files[0], gradient_jpeg(85)).unwrap();
        let parse = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/parse/images");
        if let Ok(rd) = std::fs::read_dir(&parse) {
            let mut more: Vec<_> =
                rd.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "jpg")).collect();
            more.sort();
            files.extend(more.into_iter().take(40));
        } else {
            println!("{}: absent, only the synthetic JPEG is compared", parse.display());
        }
        for f in &files {
            let ours = load_rgb_image(f).unwrap();
            let reference = image::open(f).unwrap().to_rgb8();
            assert_eq!((ours.width() as u32, ours.height() as u32), reference.dimensions());
            assert!(ours.as_bytes() == reference.as_raw().as_slice(), "{} differs", f.display());
        }
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Finding 2: a JPEG cut in half is `Decode` (the `image` crate alone accepts it).
    #[test]
    fn truncated_jpeg_is_a_decode_error() {
        let d = scratch("cut");
        let full = gradient_jpeg(90);
        let cut = d.join("cut.jpg");
        std::fs::write(&cut, &full[..full.len() / 2]).unwrap();
        assert!(image::load_from_memory(&full[..full.len() / 2]).is_ok(), "the lenient path accepts it");
        assert!(matches!(load_rgb_image(&cut), Err(Error::Decode { .. })), "{:?}", load_rgb_image(&cut).err());
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Finding 2: small files whose headers claim more than 64 Mpx are refused before decoding
    /// (JPEG via its SOF0 segment, PNG via IHDR with the CRC recomputed).
    #[test]
    fn decompression_bombs_are_refused_from_the_header() {
        let d = scratch("bomb");
        let mut jpeg = gradient_jpeg(50);
        let sof = jpeg.windows(2).position(|w| w == [0xFF, 0xC0]).unwrap();
        for (w, h, too_many) in [(16384u16, 16384u16, true), (10000, 7000, true), (8192, 8192, false)] {
            jpeg[sof + 5..sof + 7].copy_from_slice(&h.to_be_bytes());
            jpeg[sof + 7..sof + 9].copy_from_slice(&w.to_be_bytes());
            let f = d.join("bomb.jpg");
            std::fs::write(&f, &jpeg).unwrap();
            let r = load_rgb_image(&f);
            if too_many {
                assert!(matches!(r, Err(Error::TooManyPixels { .. })), "{w}x{h}: {:?}", r.err());
            } else {
                // Exactly 64 Mpx passes the pixel limit, but a 96 x 64 image's stream cannot hold 8192²
                // (strict zune-jpeg alone decoded it to 192 MB of grey, found by the fuzz seeds).
                assert!(
                    matches!(&r, Err(Error::Decode { reason, .. }) if reason.contains("cannot hold")),
                    "{w}x{h}: {:?}",
                    r.err()
                );
            }
        }
        let mut png = Vec::new();
        image::codecs::png::PngEncoder::new(&mut png)
            .write_image(&[0u8; 4], 2, 2, image::ExtendedColorType::L8)
            .unwrap();
        png[16..20].copy_from_slice(&16384u32.to_be_bytes());
        png[20..24].copy_from_slice(&16384u32.to_be_bytes());
        let crc = crc32fast::hash(&png[12..29]);
        png[29..33].copy_from_slice(&crc.to_be_bytes());
        let f = d.join("bomb.png");
        std::fs::write(&f, &png).unwrap();
        assert!(matches!(load_rgb_image(&f), Err(Error::TooManyPixels { .. })), "{:?}", load_rgb_image(&f).err());
        std::fs::remove_dir_all(&d).unwrap();
    }
}

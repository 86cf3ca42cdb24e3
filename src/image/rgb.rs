//! Owned 8-bit RGB images and loading them from disk (the detector's HOG uses colour).

use std::path::Path;

use rayon::prelude::*;

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
    /// An RGB copy of `view`: 3 channels copied, 1 (gray) repeated in R, G and B, 4 with the
    /// fourth (alpha) dropped, as the C API treats 4-channel views (composite a transparent
    /// drawing over white first to match [`load_rgb_image`]).
    pub fn from_view(view: &ImageView<'_>) -> Result<Self> {
        let (w, h, c) = (view.width(), view.height(), view.channels());
        let mut data = Vec::with_capacity(3 * w * h);
        for y in 0..h {
            let row = &view.row(y)[..w * c];
            match c {
                1 => data.extend(row.iter().flat_map(|&g| [g, g, g])),
                3 => data.extend_from_slice(row),
                _ => data.extend(row.chunks_exact(c).flat_map(|p| [p[0], p[1], p[2]])),
            }
        }
        Self::from_vec(w, h, data)
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

/// Most bytes a PNG's metadata (colour profile, text, EXIF chunks after decompression) may take
/// while it is decoded (16 MiB; a colour profile is rarely over 1 MB). A profile or text chunk
/// that would take more is dropped (the pixels are decoded as without it), so a small file
/// cannot make the decoder allocate hundreds of megabytes of metadata.
pub const MAX_IMAGE_METADATA_BYTES: u64 = 16 << 20;

/// Decodes a PNG or JPEG file's bytes as [`load_rgb_image`] does (same limits, strict JPEG,
/// transparency over white, EXIF orientation applied: JPEG APP1 `Exif`, PNG `eXIf`); `path`
/// only names the file in errors. The PNG decoder's metadata is capped at
/// [`MAX_IMAGE_METADATA_BYTES`]. Errors: `Decode`, `ImageTooLarge`, `TooManyPixels`.
pub fn decode_rgb_image(bytes: &[u8], path: &Path) -> Result<RgbImage> {
    match image::guess_format(bytes) {
        Ok(image::ImageFormat::Jpeg) => decode_jpeg(bytes, path),
        Ok(image::ImageFormat::Png) => decode_png(bytes, path),
        _ => Err(decode_error(path, "unknown format (expected PNG or JPEG)")),
    }
}

/// An [`Error::Decode`] naming `path`.
fn decode_error(path: &Path, reason: impl ToString) -> Error {
    Error::Decode { path: path.to_path_buf(), reason: reason.to_string() }
}

/// Refuses an image over 16384 px a side or [`MAX_DECODED_PIXELS`].
fn check_decoded_size(w: u32, h: u32) -> Result<()> {
    check_size(w as usize, h as usize)?;
    if w as usize * h as usize > MAX_DECODED_PIXELS {
        return Err(Error::TooManyPixels { width: w as usize, height: h as usize });
    }
    Ok(())
}

/// A PNG decoder whose metadata (colour profile, text, EXIF) may take at most
/// [`MAX_IMAGE_METADATA_BYTES`], read up to the pixel data, the pixels' own allocation then
/// limited to the largest image allowed ([`MAX_DECODED_PIXELS`] of 16-bit RGBA).
fn png_decoder(bytes: &[u8]) -> image::ImageResult<image::codecs::png::PngDecoder<std::io::Cursor<&[u8]>>> {
    use image::ImageDecoder;
    let mut metadata = image::Limits::default();
    metadata.max_alloc = Some(MAX_IMAGE_METADATA_BYTES);
    let mut decoder = image::codecs::png::PngDecoder::with_limits(std::io::Cursor::new(bytes), metadata)?;
    let mut pixels = image::Limits::default();
    pixels.max_alloc = Some(MAX_DECODED_PIXELS as u64 * 8);
    decoder.set_limits(pixels)?;
    Ok(decoder)
}

/// Decodes a PNG (size checked from the header first), EXIF orientation applied.
fn decode_png(bytes: &[u8], path: &Path) -> Result<RgbImage> {
    use image::ImageDecoder;
    let err = |e: image::ImageError| decode_error(path, e);
    let mut decoder = png_decoder(bytes).map_err(err)?;
    let (w, h) = decoder.dimensions();
    check_decoded_size(w, h)?;
    let orientation = decoder.orientation().map_err(err)?;
    let mut img = image::DynamicImage::from_decoder(decoder).map_err(err)?;
    img.apply_orientation(orientation);
    let rgb = match &img {
        // A gray PNG (the common sketch) expands to equal channels: the conversion `to_rgb8`
        // makes, without its per-pixel colour-space path.
        image::DynamicImage::ImageLuma8(gray) => {
            let row = (gray.width() as usize).max(1);
            let mut rgb = vec![0u8; 3 * gray.as_raw().len()];
            rgb.par_chunks_mut(3 * row).zip(gray.as_raw().par_chunks(row)).for_each(|(out, src)| {
                for (p, &v) in out.chunks_exact_mut(3).zip(src) {
                    p.fill(v);
                }
            });
            rgb
        }
        _ if img.color().has_alpha() => img.to_rgba8().pixels().flat_map(|p| over_white(p.0)).collect(),
        _ => img.to_rgb8().into_raw(),
    };
    RgbImage::from_vec(img.width() as usize, img.height() as usize, rgb)
}

/// Decodes a JPEG strictly (size checked from the header first), EXIF orientation applied.
fn decode_jpeg(bytes: &[u8], path: &Path) -> Result<RgbImage> {
    let err = |e: zune_jpeg::errors::DecodeErrors| decode_error(path, e);
    let mut decoder = jpeg_decoder(bytes);
    decoder.decode_headers().map_err(err)?;
    let (w, h) = decoder.dimensions().ok_or_else(|| decode_error(path, "no frame header"))?;
    let (w, h) = (w as u32, h as u32);
    check_decoded_size(w, h)?;
    // Every 8 x 8 luma block costs at least one bit of Huffman code (its DC difference), so
    // a file with fewer bits than blocks cannot hold the image its header claims: it was cut
    // short, or it is a bomb whose decoder would fill the missing blocks and report success
    // (zune-jpeg's strict mode does so for a stream that ends early with a proper EOI).
    // zune-jpeg decodes Huffman-coded JPEGs only (no arithmetic coding), so the bound holds.
    let blocks = (w as usize).div_ceil(8) * (h as usize).div_ceil(8);
    if bytes.len().saturating_mul(8) < blocks {
        let reason = format!("truncated: {} bytes cannot hold the {w}x{h} image the header claims", bytes.len());
        return Err(decode_error(path, reason));
    }
    let rgb = decoder.decode().map_err(err)?;
    let orientation = decoder.exif().and_then(|e| image::metadata::Orientation::from_exif_chunk(e));
    let Some(orientation) = orientation else {
        return RgbImage::from_vec(w as usize, h as usize, rgb);
    };
    let buffer = image::RgbImage::from_raw(w, h, rgb)
        .ok_or_else(|| decode_error(path, "decoded size differs from the header's"))?;
    let mut img = image::DynamicImage::ImageRgb8(buffer);
    img.apply_orientation(orientation);
    let (w, h) = (img.width() as usize, img.height() as usize);
    RgbImage::from_vec(w, h, img.into_rgb8().into_raw())
}

/// A zune-jpeg decoder in strict mode, RGB output (the decoder `image` uses, which `image` runs
/// non-strictly: it fills a truncated stream with grey and reports success). Any size a JPEG
/// can state is let through its header, so [`check_decoded_size`] gives the error.
fn jpeg_decoder(bytes: &[u8]) -> zune_jpeg::JpegDecoder<zune_jpeg::zune_core::bytestream::ZCursor<&[u8]>> {
    use zune_jpeg::zune_core::{bytestream::ZCursor, colorspace::ColorSpace, options::DecoderOptions};
    let options = DecoderOptions::default()
        .set_strict_mode(true)
        .set_max_width(usize::from(u16::MAX))
        .set_max_height(usize::from(u16::MAX))
        .jpeg_set_out_colorspace(ColorSpace::RGB);
    zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), options)
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
    fn from_view_expands_gray_and_drops_alpha() {
        let gray = [10u8, 20, 0, 30, 40, 0];
        let g = RgbImage::from_view(&ImageView::new(&gray, 2, 2, 1, 3).unwrap()).unwrap();
        assert_eq!(g.as_bytes(), &[10, 10, 10, 20, 20, 20, 30, 30, 30, 40, 40, 40]);
        let rgba = [1u8, 2, 3, 0, 4, 5, 6, 255];
        let c = RgbImage::from_view(&ImageView::new(&rgba, 2, 1, 4, 8).unwrap()).unwrap();
        assert_eq!(c.as_bytes(), &[1, 2, 3, 4, 5, 6]);
        let rgb = [9u8, 8, 7, 99, 6, 5, 4, 99];
        let r = RgbImage::from_view(&ImageView::new(&rgb, 1, 2, 3, 4).unwrap()).unwrap();
        assert_eq!(r.as_bytes(), &[9, 8, 7, 6, 5, 4]);
    }

    /// A gray PNG decodes to the RGB image the image crate's own conversion gives (every gray
    /// level, rows of odd width), and to the same gray image again.
    #[test]
    fn gray_png_decodes_as_the_image_crates_rgb_conversion() {
        let (w, h) = (37u32, 7u32);
        let levels: Vec<u8> = (0..w * h).map(|i| (i * 7 % 256) as u8).collect();
        let mut png = Vec::new();
        image::codecs::png::PngEncoder::new(&mut png).write_image(&levels, w, h, image::ExtendedColorType::L8).unwrap();
        let ours = decode_rgb_image(&png, Path::new("gray.png")).unwrap();
        let theirs =
            image::DynamicImage::ImageLuma8(image::GrayImage::from_raw(w, h, levels.clone()).unwrap()).to_rgb8();
        assert_eq!(ours.as_bytes(), theirs.as_raw().as_slice());
        assert!((0..=255u8).all(|v| image::DynamicImage::ImageLuma8(image::GrayImage::from_pixel(
            1,
            1,
            image::Luma([v])
        ))
        .to_rgb8()
        .as_raw()[..]
            == [v; 3]));
        assert_eq!(crate::image::to_gray(&ours.view()).unwrap().as_bytes(), &levels[..]);
    }

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

    /// A 32 x 16 RGB image: its left half black, its right half white, a red top-left block.
    fn halves() -> Vec<u8> {
        (0..16u32 * 32)
            .flat_map(|i| {
                let (x, y) = (i % 32, i / 32);
                if x < 8 && y < 8 {
                    [255, 0, 0]
                } else if x < 16 {
                    [0, 0, 0]
                } else {
                    [255, 255, 255]
                }
            })
            .collect()
    }

    /// Issue 52 finding 5: EXIF orientation 8 (stored rotated 90° clockwise, shown turned 90°
    /// counter-clockwise) is applied to JPEGs (APP1) and PNGs (`eXIf`): the 32 x 16 image whose
    /// left half is black decodes as 16 x 32 with its bottom half black, the red top-left block
    /// at the bottom-left. Orientation 1 and no EXIF leave it as stored.
    #[test]
    fn exif_orientation_is_applied_to_jpeg_and_png() {
        use super::super::metadata_files::{exif_orientation, jpeg_with_orientation, rgb_png_with};
        let px = halves();
        let mut jpeg = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 95)
            .encode(&px, 32, 16, image::ExtendedColorType::Rgb8)
            .unwrap();
        let p = Path::new("t");
        let dark = |im: &RgbImage, x: usize, y: usize| im.as_bytes()[3 * (y * im.width() + x) + 1] < 60;
        let red = |im: &RgbImage, x: usize, y: usize| {
            let q = &im.as_bytes()[3 * (y * im.width() + x)..][..3];
            q[0] > 200 && q[1] < 60
        };
        for (name, bytes) in [
            ("jpeg", jpeg_with_orientation(&jpeg, 8)),
            ("png", rgb_png_with(&px, 32, 16, None, Some(exif_orientation(8)))),
        ] {
            let im = decode_rgb_image(&bytes, p).unwrap();
            assert_eq!((im.width(), im.height()), (16, 32), "{name}");
            assert!(dark(&im, 12, 28) && !dark(&im, 12, 3), "{name}: the black half is not at the bottom");
            assert!(red(&im, 2, 29) && !red(&im, 13, 29) && !red(&im, 2, 2), "{name}: red block misplaced");
        }
        for bytes in [jpeg.clone(), jpeg_with_orientation(&jpeg, 1), rgb_png_with(&px, 32, 16, None, None)] {
            let im = decode_rgb_image(&bytes, p).unwrap();
            assert_eq!((im.width(), im.height()), (32, 16));
            assert!(red(&im, 2, 2) && dark(&im, 12, 12) && !dark(&im, 20, 12));
        }
    }

    /// Issue 52 finding 6: a PNG whose colour profile inflates past
    /// [`MAX_IMAGE_METADATA_BYTES`] (a 32 kB chunk of 32 MiB; the `image` crate's default limit
    /// let it take up to 512 MiB) has it dropped while its pixels decode as without it; a
    /// profile within the limit is kept.
    #[test]
    fn a_huge_colour_profile_is_dropped_within_the_metadata_limit() {
        use super::super::metadata_files::rgb_png_with;
        use image::ImageDecoder;
        let px = halves();
        let plain = decode_rgb_image(&rgb_png_with(&px, 32, 16, None, None), Path::new("t")).unwrap();
        let huge = rgb_png_with(&px, 32, 16, Some(vec![0; 32 << 20]), None);
        assert!(huge.len() < 64 << 10, "{} bytes", huge.len());
        assert_eq!(png_decoder(&huge).unwrap().icc_profile().unwrap(), None);
        assert_eq!(decode_rgb_image(&huge, Path::new("t")).unwrap(), plain);
        let small = rgb_png_with(&px, 32, 16, Some(vec![7; 4096]), None);
        assert_eq!(png_decoder(&small).unwrap().icc_profile().unwrap().map(|p| p.len()), Some(4096));
        assert_eq!(decode_rgb_image(&small, Path::new("t")).unwrap(), plain);
    }
}

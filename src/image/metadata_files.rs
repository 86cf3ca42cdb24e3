//! Test files with image metadata (for the decoder's tests and the fuzz seeds): an EXIF
//! orientation in a JPEG's APP1 segment or a PNG's `eXIf` chunk, and a PNG with a colour
//! profile (`iCCP`) of any size.

/// A little-endian TIFF/EXIF block holding only the Orientation tag (0x0112, SHORT) = `o`.
pub fn exif_orientation(o: u16) -> Vec<u8> {
    let mut b = b"II*\0".to_vec();
    b.extend(8u32.to_le_bytes());
    b.extend(1u16.to_le_bytes());
    b.extend(0x0112u16.to_le_bytes());
    b.extend(3u16.to_le_bytes());
    b.extend(1u32.to_le_bytes());
    b.extend(o.to_le_bytes());
    b.extend([0, 0]);
    b.extend(0u32.to_le_bytes());
    b
}

/// `jpeg` with an APP1 `Exif` segment holding orientation `o` right after its SOI marker.
pub fn jpeg_with_orientation(jpeg: &[u8], o: u16) -> Vec<u8> {
    let exif = exif_orientation(o);
    let mut out = jpeg[..2].to_vec();
    out.extend([0xFF, 0xE1]);
    out.extend(((2 + 6 + exif.len()) as u16).to_be_bytes());
    out.extend(b"Exif\0\0");
    out.extend(exif);
    out.extend(&jpeg[2..]);
    out
}

/// An 8-bit RGB PNG of `px` (`w` x `h`) with an optional colour profile (compressed into an
/// `iCCP` chunk; a profile of zeros compresses about 1000:1) and an optional `eXIf` block.
pub fn rgb_png_with(px: &[u8], w: u32, h: u32, icc: Option<Vec<u8>>, exif: Option<Vec<u8>>) -> Vec<u8> {
    let mut info = png::Info::with_size(w, h);
    info.color_type = png::ColorType::Rgb;
    info.bit_depth = png::BitDepth::Eight;
    info.icc_profile = icc.map(Into::into);
    info.exif_metadata = exif.map(Into::into);
    let mut out = Vec::new();
    let mut writer = png::Encoder::with_info(&mut out, info).unwrap().write_header().unwrap();
    writer.write_image_data(px).unwrap();
    writer.finish().unwrap();
    out
}

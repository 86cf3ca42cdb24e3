//! Borrowed image views and owned gray images.

use crate::error::{Error, Result, MAX_IMAGE_SIDE};

/// A borrowed, validated 8-bit image: `channels` interleaved bytes per pixel (1 gray, 3 RGB,
/// 4 RGBA), rows `stride` bytes apart (`stride >= width * channels`). The last row only needs
/// `width * channels` bytes.
#[derive(Clone, Copy, Debug)]
pub struct ImageView<'a> {
    data: &'a [u8],
    width: usize,
    height: usize,
    channels: usize,
    stride: usize,
}

/// Checks a width/height pair against the empty and [`MAX_IMAGE_SIDE`] limits.
pub(crate) fn check_size(width: usize, height: usize) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::EmptyImage { width, height });
    }
    if width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(Error::ImageTooLarge { width, height });
    }
    Ok(())
}

/// Bytes needed by an image of this geometry: `stride * (height - 1) + width * channels`, with
/// checked arithmetic (a caller's stride near `usize::MAX` is an error, never a wrapped length).
/// `height` must be at least 1.
pub(crate) fn needed_bytes(width: usize, height: usize, channels: usize, stride: usize) -> Result<usize> {
    stride
        .checked_mul(height.saturating_sub(1))
        .and_then(|rows| width.checked_mul(channels).and_then(|row| rows.checked_add(row)))
        .ok_or_else(|| Error::OutOfRange {
            name: "stride",
            detail: format!("{stride} bytes x {height} rows overflows the address space"),
        })
}

impl<'a> ImageView<'a> {
    /// Validates geometry and wraps `data`. Errors: empty or oversized images, channel counts
    /// other than 1/3/4, strides shorter than a row, buffers too short for the geometry.
    pub fn new(data: &'a [u8], width: usize, height: usize, channels: usize, stride: usize) -> Result<Self> {
        let needed = Self::required_len(width, height, channels, stride)?;
        if data.len() < needed {
            return Err(Error::BufferTooSmall { name: "image data", len: data.len(), needed, unit: "bytes" });
        }
        Ok(Self { data, width, height, channels, stride })
    }

    /// Validates a geometry (size limits, channel count, stride) and returns the number of bytes
    /// a buffer needs for it: `stride * (height - 1) + width * channels`.
    pub fn required_len(width: usize, height: usize, channels: usize, stride: usize) -> Result<usize> {
        check_size(width, height)?;
        if !matches!(channels, 1 | 3 | 4) {
            return Err(Error::UnsupportedChannels(channels));
        }
        let row_bytes = width * channels;
        if stride < row_bytes {
            return Err(Error::BadStride { stride, row_bytes });
        }
        needed_bytes(width, height, channels, stride)
    }

    /// A tightly packed single-channel view of `data` (`stride == width`).
    pub fn gray(data: &'a [u8], width: usize, height: usize) -> Result<Self> {
        Self::new(data, width, height, 1, width)
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }
    /// Interleaved channels per pixel: 1, 3 or 4.
    pub fn channels(&self) -> usize {
        self.channels
    }
    /// Bytes between the starts of consecutive rows.
    pub fn stride(&self) -> usize {
        self.stride
    }
    /// Row `y` (`width * channels` bytes). Panics if `y >= height` (internal use only).
    pub fn row(&self, y: usize) -> &'a [u8] {
        let start = y * self.stride;
        &self.data[start..start + self.width * self.channels]
    }
    /// All pixels as one slice when the rows are tightly packed (`stride == width * channels`).
    pub(crate) fn packed(&self) -> Option<&'a [u8]> {
        let row = self.width * self.channels;
        (self.stride == row).then(|| &self.data[..row * self.height])
    }
}

/// An owned, tightly packed 8-bit gray image (`data.len() == width * height`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GrayImage {
    width: usize,
    height: usize,
    data: Vec<u8>,
}

impl GrayImage {
    /// A `width` x `height` image filled with `value`. Errors on empty or oversized sizes.
    pub fn filled(width: usize, height: usize, value: u8) -> Result<Self> {
        check_size(width, height)?;
        Ok(Self { width, height, data: vec![value; width * height] })
    }

    /// Takes ownership of tightly packed pixels. Errors unless `data.len() == width * height`.
    pub fn from_vec(width: usize, height: usize, data: Vec<u8>) -> Result<Self> {
        check_size(width, height)?;
        if data.len() != width * height {
            return Err(Error::BufferTooSmall {
                name: "pixels",
                len: data.len(),
                needed: width * height,
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
    /// The pixels, row-major, `width` bytes per row.
    pub fn as_bytes(&self) -> &[u8] {
        &self.data
    }
    /// Mutable pixels, row-major.
    pub fn as_bytes_mut(&mut self) -> &mut [u8] {
        &mut self.data
    }
    /// Consumes the image, returning its pixels.
    pub fn into_vec(self) -> Vec<u8> {
        self.data
    }
    /// Pixel at (x, y); `None` outside the image.
    pub fn get(&self, x: usize, y: usize) -> Option<u8> {
        (x < self.width && y < self.height).then(|| self.data[y * self.width + x])
    }
    /// A borrowed single-channel view of this image.
    pub fn view(&self) -> ImageView<'_> {
        ImageView { data: &self.data, width: self.width, height: self.height, channels: 1, stride: self.width }
    }
    /// This image shrunk by the whole factor `n` (≥ 1): ⌈width / n⌉ × ⌈height / n⌉ pixels, each
    /// the rounded mean of its n × n block (clipped at the right and bottom edges). `n` = 1 gives
    /// a copy.
    pub fn box_shrunk(&self, n: usize) -> GrayImage {
        let n = n.max(1);
        let (w, h) = (self.width.div_ceil(n), self.height.div_ceil(n));
        let mut sums = vec![0u32; w];
        let mut data = Vec::with_capacity(w * h);
        for by in 0..h {
            sums.fill(0);
            let rows = (by * n)..((by + 1) * n).min(self.height);
            let row_count = rows.len();
            for y in rows {
                let row = &self.data[y * self.width..(y + 1) * self.width];
                for (x, &v) in row.iter().enumerate() {
                    sums[x / n] += u32::from(v);
                }
            }
            for (bx, &sum) in sums.iter().enumerate() {
                let cols = ((bx + 1) * n).min(self.width) - bx * n;
                let count = (cols * row_count) as u32;
                data.push(((sum + count / 2) / count) as u8);
            }
        }
        GrayImage { width: w, height: h, data }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_shrunk_averages_whole_blocks_and_clips_the_edges() {
        // 5 × 3: columns 0-1 of rows 0-1 are 0, 10, 20, 30 (mean 15); the last column and row
        // make partial blocks.
        let img =
            GrayImage::from_vec(5, 3, vec![0, 10, 100, 100, 7, 20, 30, 100, 101, 9, 1, 3, 255, 255, 200]).unwrap();
        let s = img.box_shrunk(2);
        assert_eq!((s.width(), s.height()), (3, 2));
        assert_eq!(s.as_bytes(), &[15, 100, 8, 2, 255, 200]);
        assert_eq!(img.box_shrunk(1).as_bytes(), img.as_bytes());
        assert_eq!(img.box_shrunk(0).as_bytes(), img.as_bytes());
        let one = img.box_shrunk(8);
        assert_eq!((one.width(), one.height(), one.as_bytes()[0]), (1, 1, 79));
    }

    /// Finding 1: lengths derived from caller strides never wrap.
    #[test]
    fn required_len_is_checked_against_overflow() {
        assert_eq!(ImageView::required_len(4, 3, 1, 10).unwrap(), 24);
        assert_eq!(ImageView::required_len(4, 1, 3, usize::MAX).unwrap(), 12, "one row needs no stride");
        for (h, stride) in [(3, 1usize << 63), (2, usize::MAX), (16384, usize::MAX / 1000)] {
            let e = ImageView::required_len(4, h, 1, stride).unwrap_err();
            assert!(matches!(e, Error::OutOfRange { name: "stride", .. }), "{h} rows x {stride}: {e}");
        }
        let data = [0u8; 16];
        assert!(ImageView::new(&data, 4, 3, 1, 1 << 63).is_err());
    }
}

//! `skb_image` views and the image functions (Canny, Gaussian blur).

use sketchbody_core::image::{canny_into, gaussian_blur, CannyParams, ImageView};

use super::error::fail;
use super::ptr::*;
use super::status::skb_status;

/// A borrowed 8-bit image owned by the caller: `height` rows of `width` pixels, each pixel
/// `channels` interleaved bytes (1 gray, 3 R,G,B, 4 R,G,B,A with alpha ignored), rows `stride`
/// bytes apart (`stride >= width * channels`). sketchbody only reads it during the call and
/// never keeps the pointer. A plain struct: copy it freely; its layout is part of the ABI.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct skb_image {
    /// First byte of the first row.
    pub data: *const u8,
    /// Width in pixels, 1..=16384.
    pub width: u32,
    /// Height in pixels, 1..=16384.
    pub height: u32,
    /// Bytes between the starts of consecutive rows.
    pub stride: u32,
    /// Bytes per pixel: 1, 3 or 4.
    pub channels: u32,
}

const _: () = assert!(std::mem::size_of::<skb_image>() == 24 || std::mem::size_of::<usize>() != 8);

/// Validates an `skb_image` and borrows it as a core view.
///
/// # Safety
/// `img` must be NULL or point to an `skb_image` whose `data` is valid for the described rows.
pub(crate) unsafe fn view_of<'a>(img: *const skb_image) -> Result<ImageView<'a>, skb_status> {
    unsafe {
        let img = try_ref(img, "image")?;
        let (w, h, c, s) = (img.width as usize, img.height as usize, img.channels as usize, img.stride as usize);
        let len = ImageView::required_len(w, h, c, s).map_err(|e| fail(&e))?;
        let data = try_slice(img.data, len, "image->data")?;
        ImageView::new(data, w, h, c, s).map_err(|e| fail(&e))
    }
}

/// Canny edges of `src`, bit-exact with OpenCV 4.6
/// `cv::Canny(gray, dst, threshold1, threshold2, aperture, l2_gradient)` where `gray` is `src`
/// (1 channel) or `cv::cvtColor(src, COLOR_RGB2GRAY)` (3/4 channels). On error nothing is
/// written. Thread-safe; runs on the rayon thread pool.
/// @param src the image (1, 3 or 4 channels), only read.
/// @param threshold1 one hysteresis threshold (the two may be given in either order).
/// @param threshold2 the other hysteresis threshold.
/// @param aperture the Sobel aperture: 3, 5 or 7.
/// @param l2_gradient true for the L2 gradient magnitude, false for L1 (as OpenCV's flag).
/// @param dst receives `src->height` rows of `src->width` bytes (255 edge, 0 not).
/// @param dst_stride bytes between the starts of consecutive rows of `dst`.
/// @param dst_len the size of `dst` in bytes; at least `dst_stride * (height - 1) + width`.
/// @return SKB_OK; SKB_ERR_INVALID_APERTURE for an aperture other than 3, 5 or 7;
///         SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_image_canny(
    src: *const skb_image,
    threshold1: f64,
    threshold2: f64,
    aperture: i32,
    l2_gradient: bool,
    dst: *mut u8,
    dst_stride: usize,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let view = try_status!(view_of(src));
            if !matches!(aperture, 3 | 5 | 7) {
                return fail(&sketchbody_core::Error::InvalidAperture(aperture as i64));
            }
            let params = CannyParams { threshold1, threshold2, aperture: aperture as u32, l2_gradient };
            let out = try_status!(try_slice_mut(dst, dst_len, "dst"));
            try_core!(canny_into(&view, &params, out, dst_stride));
            skb_status::SKB_OK
        }
    }
}

/// Gaussian blur of a 1-channel `src`, compatible with OpenCV 4.x
/// `cv::GaussianBlur(src, dst, cv::Size(0, 0), sigma)`. On error nothing is written. Thread-safe.
/// @param src the 1-channel image, only read.
/// @param sigma the standard deviation in pixels, 0 < sigma <= 1024.
/// @param dst receives `src->height` rows of `src->width` bytes, as in [`skb_image_canny`].
/// @param dst_stride bytes between the starts of consecutive rows of `dst`.
/// @param dst_len the size of `dst` in bytes; at least `dst_stride * (height - 1) + width`.
/// @return SKB_OK; SKB_ERR_OUT_OF_RANGE for `sigma` outside its range;
///         SKB_ERR_BUFFER_TOO_SMALL for a short `dst`; argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_image_gaussian_blur(
    src: *const skb_image,
    sigma: f64,
    dst: *mut u8,
    dst_stride: usize,
    dst_len: usize,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            let view = try_status!(view_of(src));
            let out = try_status!(try_slice_mut(dst, dst_len, "dst"));
            let (w, h) = (view.width(), view.height());
            let needed = try_core!(ImageView::required_len(w, h, 1, dst_stride));
            if dst_len < needed {
                return fail(&sketchbody_core::Error::BufferTooSmall { name: "dst", len: dst_len, needed, unit: "bytes" });
            }
            let blurred = try_core!(gaussian_blur(&view, sigma));
            for (y, row) in blurred.as_bytes().chunks_exact(w).enumerate() {
                out[y * dst_stride..y * dst_stride + w].copy_from_slice(row);
            }
            skb_status::SKB_OK
        }
    }
}

/// Largest accepted image width or height, in pixels.
pub const SKB_MAX_IMAGE_SIDE: u32 = 16384;
const _: () = assert!(SKB_MAX_IMAGE_SIDE as usize == sketchbody_core::error::MAX_IMAGE_SIDE);

//! Status codes. Numbers are part of the ABI: never renumber or reuse one.

use std::ffi::c_char;

use sketchbody_core::error::Error;

/// Result of every sketchbody C function. 0 is success; any other value is an error whose text
/// is given by [`skb_status_str`] (generic) and `skb_last_error_message` (specific).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum skb_status {
    /// Success.
    SKB_OK = 0,
    /// A required pointer argument was NULL.
    SKB_ERR_NULL_POINTER = 1,
    /// An argument is invalid in a way no more specific code describes.
    SKB_ERR_INVALID_ARGUMENT = 2,
    /// Width or height is zero.
    SKB_ERR_EMPTY_IMAGE = 3,
    /// Width or height exceeds 16384 pixels.
    SKB_ERR_IMAGE_TOO_LARGE = 4,
    /// A row stride is smaller than one row of pixels.
    SKB_ERR_BAD_STRIDE = 5,
    /// A caller buffer is smaller than the geometry requires.
    SKB_ERR_BUFFER_TOO_SMALL = 6,
    /// The image channel count is not 1, 3 or 4.
    SKB_ERR_UNSUPPORTED_CHANNELS = 7,
    /// The Sobel aperture is not 3, 5 or 7.
    SKB_ERR_INVALID_APERTURE = 8,
    /// A numeric argument is NaN or infinite.
    SKB_ERR_NON_FINITE = 9,
    /// A numeric argument is outside its documented range.
    SKB_ERR_OUT_OF_RANGE = 10,
    /// A file could not be read or written.
    SKB_ERR_IO = 11,
    /// A file is not a readable image.
    SKB_ERR_DECODE = 12,
    /// A model or data file is corrupt, truncated or of an unsupported version.
    SKB_ERR_CORRUPT_DATA = 13,
    /// The progress callback asked to stop.
    SKB_ERR_CANCELLED = 14,
    /// A bug: Rust code panicked. The library stays usable; please report the message.
    SKB_ERR_PANIC = 15,
    /// Too few usable (finite, visible) joints for the 3-D pose solver.
    SKB_ERR_TOO_FEW_JOINTS = 16,
    /// Two joints that must be distinct coincide.
    SKB_ERR_COINCIDENT_JOINTS = 17,
    /// The input geometry is degenerate (collinear joints, zero extent, rank-deficient fit).
    SKB_ERR_DEGENERATE = 18,
    /// Two joints of a bone coincide (zero-length bone).
    SKB_ERR_DEGENERATE_BONE = 19,
    /// The projected mesh lies wholly outside the image.
    SKB_ERR_MESH_OUTSIDE_IMAGE = 20,
    /// The detector found no figure scoring at least the threshold.
    SKB_ERR_NO_FIGURE = 21,
    /// The image is too small to search for a figure.
    SKB_ERR_IMAGE_TOO_SMALL = 22,
    /// Retired, no longer returned: before the embedded detector landed, `skb_pipeline_run`
    /// without joints failed with it; now the detector finds them.
    SKB_ERR_NO_JOINTS = 23,
    /// A visible 2-D joint lies outside the image.
    SKB_ERR_JOINT_OUTSIDE_IMAGE = 24,
    /// The sketch has no edges (blank, uniform or too faint).
    SKB_ERR_BLANK_IMAGE = 25,
    /// A turnaround's views do not show one character in one pose (their joints disagree, match
    /// only upside down, or a side view is drawn facing the other way than its label).
    SKB_ERR_VIEWS_DISAGREE = 26,
}

impl From<&Error> for skb_status {
    fn from(e: &Error) -> Self {
        use skb_status::*;
        match e {
            Error::EmptyImage { .. } => SKB_ERR_EMPTY_IMAGE,
            Error::ImageTooLarge { .. } => SKB_ERR_IMAGE_TOO_LARGE,
            Error::TooManyPixels { .. } => SKB_ERR_IMAGE_TOO_LARGE,
            Error::BadStride { .. } => SKB_ERR_BAD_STRIDE,
            Error::BufferTooSmall { .. } => SKB_ERR_BUFFER_TOO_SMALL,
            Error::UnsupportedChannels(_) => SKB_ERR_UNSUPPORTED_CHANNELS,
            Error::InvalidAperture(_) => SKB_ERR_INVALID_APERTURE,
            Error::NonFinite { .. } => SKB_ERR_NON_FINITE,
            Error::OutOfRange { .. } => SKB_ERR_OUT_OF_RANGE,
            Error::Io { .. } => SKB_ERR_IO,
            Error::Decode { .. } => SKB_ERR_DECODE,
            Error::CorruptData(_) => SKB_ERR_CORRUPT_DATA,
            Error::Cancelled => SKB_ERR_CANCELLED,
            Error::TooFewJoints { .. } => SKB_ERR_TOO_FEW_JOINTS,
            Error::CoincidentJoints { .. } => SKB_ERR_COINCIDENT_JOINTS,
            Error::Degenerate(_) => SKB_ERR_DEGENERATE,
            Error::DegenerateBone { .. } => SKB_ERR_DEGENERATE_BONE,
            Error::MeshOutsideImage { .. } => SKB_ERR_MESH_OUTSIDE_IMAGE,
            Error::NoFigure { .. } => SKB_ERR_NO_FIGURE,
            Error::ImageTooSmall { .. } => SKB_ERR_IMAGE_TOO_SMALL,
            Error::JointOutsideImage { .. } => SKB_ERR_JOINT_OUTSIDE_IMAGE,
            Error::BlankImage { .. } => SKB_ERR_BLANK_IMAGE,
            Error::ViewsDisagree(_) => SKB_ERR_VIEWS_DISAGREE,
        }
    }
}

/// English text for a status code. Thread-safe.
/// @param status a `skb_status` value (any `uint32_t` is accepted).
/// @return a static, NUL-terminated string, valid for the life of the process ("unknown status"
///         for numbers this version does not know); never NULL; never free it.
#[no_mangle]
pub extern "C" fn skb_status_str(status: u32) -> *const c_char {
    let s: &'static [u8] = match status {
        0 => b"ok\0",
        1 => b"a required pointer argument was NULL\0",
        2 => b"invalid argument\0",
        3 => b"image width or height is zero\0",
        4 => b"image is larger than 16384 pixels a side\0",
        5 => b"row stride is smaller than one row\0",
        6 => b"buffer is too small\0",
        7 => b"unsupported channel count (expected 1, 3 or 4)\0",
        8 => b"invalid Sobel aperture (expected 3, 5 or 7)\0",
        9 => b"a numeric argument is NaN or infinite\0",
        10 => b"a numeric argument is out of range\0",
        11 => b"file input/output error\0",
        12 => b"not a readable image\0",
        13 => b"corrupt, truncated or unsupported data\0",
        14 => b"cancelled by the progress callback\0",
        15 => b"internal error (Rust panic)\0",
        16 => b"too few usable joints\0",
        17 => b"two joints that must be distinct coincide\0",
        18 => b"degenerate joint configuration\0",
        19 => b"two joints of a bone coincide (zero-length bone)\0",
        20 => b"the projected mesh lies wholly outside the image\0",
        21 => b"no figure found (best score below the threshold)\0",
        22 => b"image is too small to detect a figure\0",
        23 => b"retired: no 2-D joints given and no joint detector available\0",
        24 => b"a 2-D joint lies outside the image\0",
        25 => b"the sketch has no edges (blank or too faint)\0",
        26 => b"the views do not show one character in one pose\0",
        _ => b"unknown status\0",
    };
    s.as_ptr().cast()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_status_has_its_own_text() {
        // SAFETY: skb_status_str returns a static NUL-terminated string for every code (never NULL).
        let text = |c: u32| unsafe { std::ffi::CStr::from_ptr(skb_status_str(c)) }.to_str().unwrap().to_owned();
        let all: Vec<String> = (0..=26).map(text).collect();
        let unique: std::collections::HashSet<_> = all.iter().collect();
        assert_eq!(unique.len(), all.len());
        assert!(!all.contains(&"unknown status".to_owned()));
        assert_eq!(text(27), "unknown status");
        assert_eq!(std::mem::size_of::<skb_status>(), 4);
    }
}

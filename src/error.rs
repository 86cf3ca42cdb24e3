//! The library's error type. Every fallible core function returns [`Result`]; the C ABI maps
//! each variant to one `skb_status` code (see `capi/src/status.rs`).

use std::path::PathBuf;

/// Largest accepted image side, in pixels (inputs larger than this are rejected).
pub const MAX_IMAGE_SIDE: usize = 16384;

/// Largest image a loader decodes, in pixels (64 Mpx = 2^26, e.g. 8192 x 8192): checked from
/// the file's header before any pixel memory is allocated, so a small file claiming a huge
/// image is refused instead of allocating gigabytes.
pub const MAX_DECODED_PIXELS: usize = 1 << 26;

/// Everything that can go wrong in sketchbody. Messages carry the offending value. Deliberately
/// exhaustive: the C API (`capi/src/status.rs`) matches every variant, so a new variant cannot
/// compile until it has its own status code.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A width or height is zero.
    #[error("image size {width}x{height} is empty: width and height must be at least 1")]
    EmptyImage {
        /// Image width, pixels.
        width: usize,
        /// Image height, pixels.
        height: usize,
    },
    /// A width or height exceeds [`MAX_IMAGE_SIDE`].
    #[error("image size {width}x{height} exceeds the limit of {MAX_IMAGE_SIDE} px a side")]
    ImageTooLarge {
        /// Image width, pixels.
        width: usize,
        /// Image height, pixels.
        height: usize,
    },
    /// An image file's header claims more than [`MAX_DECODED_PIXELS`] pixels.
    #[error("image size {width}x{height} exceeds the decoding limit of {MAX_DECODED_PIXELS} pixels")]
    TooManyPixels {
        /// Image width, pixels.
        width: usize,
        /// Image height, pixels.
        height: usize,
    },
    /// A row stride is smaller than one row of pixels.
    #[error("row stride {stride} bytes is smaller than one row ({row_bytes} bytes)")]
    BadStride {
        /// The given row stride, bytes.
        stride: usize,
        /// Bytes of one row of pixels.
        row_bytes: usize,
    },
    /// A buffer (named as the caller knows it: a C argument such as `dst`, or `image data`)
    /// holds fewer `unit`s ("bytes", "elements") than the call needs.
    #[error("buffer `{name}` holds {len} {unit}, {needed} needed")]
    BufferTooSmall {
        /// The buffer's name as the caller knows it.
        name: &'static str,
        /// What the buffer holds, in `unit`s.
        len: usize,
        /// What the call needs, in `unit`s.
        needed: usize,
        /// "bytes" or "elements".
        unit: &'static str,
    },
    /// The channel count is not 1, 3 or 4.
    #[error("unsupported channel count {0}: expected 1 (gray), 3 (RGB) or 4 (RGBA)")]
    UnsupportedChannels(usize),
    /// The Sobel aperture is not 3, 5 or 7.
    #[error("invalid aperture {0}: expected 3, 5 or 7")]
    InvalidAperture(i64),
    /// A parameter that must be finite is NaN or infinite.
    #[error("{name} must be finite (got {value})")]
    NonFinite {
        /// The parameter's name.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A parameter is outside its documented range.
    #[error("{name} is out of range: {detail}")]
    OutOfRange {
        /// The parameter's name.
        name: &'static str,
        /// What was expected and what was given.
        detail: String,
    },
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A file is not a decodable image (or is truncated).
    #[error("{}: not a readable image: {reason}", path.display())]
    Decode {
        /// The file.
        path: PathBuf,
        /// Why decoding failed.
        reason: String,
    },
    /// A model or data file is corrupt, truncated or of the wrong format version.
    #[error("corrupt or unsupported data: {0}")]
    CorruptData(String),
    /// An image is too small to search for a figure.
    #[error("image size {width}x{height} is too small to detect a figure: both sides must be at least {min} px")]
    ImageTooSmall {
        /// Image width, pixels.
        width: usize,
        /// Image height, pixels.
        height: usize,
        /// The least side length accepted, pixels.
        min: usize,
    },
    /// The detector found no figure scoring at least the threshold.
    #[error("no figure found: score {score:.3} is below the threshold {threshold:.3}")]
    NoFigure {
        /// The best figure's score: the calibrated probability that the image holds a figure
        /// for the single-figure detector's default, the backend's raw score when strict or
        /// for the sketch model alone.
        score: f64,
        /// The threshold `score` had to reach.
        threshold: f64,
    },
    /// The operation was cancelled by the caller's progress callback.
    #[error("cancelled by the progress callback")]
    Cancelled,
    /// Too few usable (finite, visible) 2-D joints for the 3-D pose solver.
    #[error("too few usable joints: {detail}")]
    TooFewJoints {
        /// What was expected and what was given.
        detail: String,
    },
    /// Two joints that must be distinct coincide (e.g. both ends of a bone at one pixel).
    #[error("joints {a} and {b} coincide at ({x}, {y}) px")]
    CoincidentJoints {
        /// Name of the first joint.
        a: &'static str,
        /// Name of the second joint.
        b: &'static str,
        /// Horizontal position, pixels.
        x: f64,
        /// Vertical position, pixels.
        y: f64,
    },
    /// The input has no usable geometry (all joints collinear, zero extent, rank-deficient fit).
    #[error("degenerate configuration: {0}")]
    Degenerate(String),
    /// A bone of a skeleton has (near) zero length: its two joints coincide.
    #[error("bone {from}-{to} has length {length:e} m: its joints coincide")]
    DegenerateBone {
        /// Name of the bone's parent joint.
        from: &'static str,
        /// Name of the bone's child joint.
        to: &'static str,
        /// The bone's length, metres.
        length: f64,
    },
    /// A mesh to rasterise projects wholly outside the image.
    #[error("the projected mesh lies wholly outside the {width}x{height} image")]
    MeshOutsideImage {
        /// Image width, pixels.
        width: usize,
        /// Image height, pixels.
        height: usize,
    },
    /// A visible 2-D joint lies outside the image it belongs to.
    #[error("joint {joint} at ({x}, {y}) px lies outside the {width}x{height} image")]
    JointOutsideImage {
        /// Name of the joint.
        joint: &'static str,
        /// Horizontal position, pixels.
        x: f64,
        /// Vertical position, pixels.
        y: f64,
        /// Image width, pixels.
        width: usize,
        /// Image height, pixels.
        height: usize,
    },
    /// The sketch has no edges at all (blank, uniform or too faint for the edge detector).
    #[error("the {width}x{height} sketch has no edges: it is blank or too faint (Canny thresholds {low}/{high})")]
    BlankImage {
        /// Image width, pixels.
        width: usize,
        /// Image height, pixels.
        height: usize,
        /// Canny's low threshold.
        low: f64,
        /// Canny's high threshold.
        high: f64,
    },
    /// A turnaround's views do not show one character in one pose: their joints disagree beyond
    /// the limit, match only upside down, or a side view's depth comes out mirrored (drawn facing
    /// the other way than its label). The text says which view and why.
    #[error("the views disagree: {0}")]
    ViewsDisagree(String),
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Checks that `value` is finite, naming it in the error otherwise.
pub fn ensure_finite(name: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::NonFinite { name, value })
    }
}

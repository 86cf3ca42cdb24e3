//! Images: borrowed 8-bit views with an explicit row stride, owned gray images, decoding,
//! colour conversion and the OpenCV-compatible filters (Gaussian blur, Sobel, Canny).

mod blur;
mod canny;
mod decode;
mod gray;
mod encode;
#[cfg(test)]
pub(crate) mod metadata_files;
mod rgb;
mod sobel;
mod view;

pub use blur::{gaussian_blur, gaussian_kernel_size};
pub use canny::{canny, canny_into, CannyParams};
pub use decode::load_image;
pub use encode::{encode_png, save_png};
pub use gray::{rgb_to_gray_pixel, to_gray};
pub use rgb::{decode_rgb_image, load_rgb_image, over_white, RgbImage};
pub use view::{GrayImage, ImageView};

//! PNG/JPEG decoding through the library's loader (`decode_rgb_image`, what `load_rgb_image`,
//! `skb_gray_image_new_from_file`, `run` and `detect` use), then the gray conversion. Any input must give
//! an image within the limits or an error; never a panic or an allocation past 64 Mpx.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use sketchbody::error::{MAX_DECODED_PIXELS, MAX_IMAGE_SIDE};

fuzz_target!(|data: &[u8]| {
    if let Ok(img) = sketchbody::image::decode_rgb_image(data, Path::new("fuzz")) {
        assert!(img.width() <= MAX_IMAGE_SIDE && img.height() <= MAX_IMAGE_SIDE);
        assert!(img.width() * img.height() <= MAX_DECODED_PIXELS);
        assert_eq!(img.as_bytes().len(), 3 * img.width() * img.height());
        let gray = sketchbody::image::to_gray(&img.view()).expect("a decoded image converts to gray");
        assert_eq!((gray.width(), gray.height()), (img.width(), img.height()));
    }
});

//! Library version: header macros and the runtime string.

use std::ffi::c_char;

/// Major version of the library this header belongs to.
pub const SKB_VERSION_MAJOR: u32 = 1;
/// Minor version of the library this header belongs to.
pub const SKB_VERSION_MINOR: u32 = 0;
/// Patch version of the library this header belongs to.
pub const SKB_VERSION_PATCH: u32 = 0;
/// `"MAJOR.MINOR.PATCH"` of this library. The C header derives its `SKB_VERSION_STRING` macro
/// from the three numeric macros above (cbindgen emits no string constants).
pub const SKB_VERSION_STRING: &str = "1.0.0";

/// The version of the loaded library (compare with the header's `SKB_VERSION_STRING`).
/// Thread-safe.
/// @return a static, NUL-terminated `"MAJOR.MINOR.PATCH"` string, valid for the life of the
///         process; never NULL; never free it.
#[no_mangle]
pub extern "C" fn skb_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_constants_match_cargo_toml_and_runtime() {
        assert_eq!(SKB_VERSION_MAJOR.to_string(), env!("CARGO_PKG_VERSION_MAJOR"));
        assert_eq!(SKB_VERSION_MINOR.to_string(), env!("CARGO_PKG_VERSION_MINOR"));
        assert_eq!(SKB_VERSION_PATCH.to_string(), env!("CARGO_PKG_VERSION_PATCH"));
        assert_eq!(SKB_VERSION_STRING, env!("CARGO_PKG_VERSION"));
        // SAFETY: skb_version returns a static NUL-terminated string (never NULL).
        let runtime = unsafe { std::ffi::CStr::from_ptr(skb_version()) };
        assert_eq!(runtime.to_str().unwrap(), SKB_VERSION_STRING);
    }
}

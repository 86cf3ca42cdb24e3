//! Reading and writing 2-D joints files (`sketchbody-joints2d`, docs/formats.md): what
//! `sketchbody detect` and `run` write and `run --joints` reads, through the library's one
//! reader (the same size cap, regular-file check and JSON rules as the CLI and the Python
//! package), so a plug-in exchanges joints with the CLI without a JSON parser of its own.

use std::ffi::c_char;

use sketchbody_core::export::joints::MAX_JOINTS_FILE_BYTES;
use sketchbody_core::export::joints2d::{load_joints2d, parse_joints2d_text, write_joints2d_with};
use sketchbody_core::skeleton::Joints2;

use super::error::fail_with;
use super::pose::{joints_in, skb_joints2d};
use super::ptr::*;
use super::status::skb_status;

/// Largest joints JSON the readers accept, in bytes (1 MiB; a joints file is about 2 kB).
pub const SKB_JOINTS_JSON_MAX_BYTES: u32 = 1_048_576;

const _: () = assert!(SKB_JOINTS_JSON_MAX_BYTES as u64 == MAX_JOINTS_FILE_BYTES);

fn joints_out(j: &Joints2) -> skb_joints2d {
    skb_joints2d { xy: j.xy, visible: j.visible.map(u8::from), reserved: 0 }
}

/// Reads a `sketchbody-joints2d` file (joints listed in `missing` get `visible = 0`). A leading
/// UTF-8 byte-order mark is accepted. Thread-safe.
/// @param path NUL-terminated UTF-8; must name a regular file of at most
///             `SKB_JOINTS_JSON_MAX_BYTES` (a FIFO, a device or a folder is refused without
///             blocking).
/// @param out receives the joints, written only on success; not NULL.
/// @return SKB_OK; SKB_ERR_IO (missing, unreadable, not a regular file, too large);
///         SKB_ERR_CORRUPT_DATA (not JSON, a key given twice, another format or version, a
///         missing, unknown or malformed joint); SKB_ERR_INVALID_ARGUMENT (`path` not UTF-8);
///         argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_joints2d_read_json(path: *const c_char, out: *mut skb_joints2d) -> skb_status {
    unsafe {
        ffi_boundary! {
            let p = try_status!(path_arg(path, "path"));
            if out.is_null() {
                return null("out");
            }
            let j = try_core!(load_joints2d(p));
            try_status!(write_out(out, joints_out(&j), "out"));
            skb_status::SKB_OK
        }
    }
}

/// Parses a `sketchbody-joints2d` document held in memory, with the rules of
/// `skb_joints2d_read_json`. Thread-safe.
/// @param json the document's bytes, UTF-8, not NUL-terminated.
/// @param len the byte count of `json`, at most `SKB_JOINTS_JSON_MAX_BYTES`.
/// @param out receives the joints, written only on success; not NULL.
/// @return SKB_OK; SKB_ERR_CORRUPT_DATA (as for `skb_joints2d_read_json`, or not UTF-8);
///         SKB_ERR_OUT_OF_RANGE (`len` over the limit); argument errors as docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_joints2d_parse_json(
    json: *const c_char,
    len: usize,
    out: *mut skb_joints2d,
) -> skb_status {
    unsafe {
        ffi_boundary! {
            if len as u64 > MAX_JOINTS_FILE_BYTES {
                return fail_with(
                    skb_status::SKB_ERR_OUT_OF_RANGE,
                    &format!("len {len} exceeds the {MAX_JOINTS_FILE_BYTES}-byte limit of a joints file"),
                );
            }
            let bytes = try_status!(try_slice(json.cast(), len, "json"));
            if out.is_null() {
                return null("out");
            }
            let Ok(text) = std::str::from_utf8(bytes) else {
                return fail_with(skb_status::SKB_ERR_CORRUPT_DATA, "2-D joints JSON: not UTF-8 text");
            };
            let j = try_core!(parse_joints2d_text(text));
            try_status!(write_out(out, joints_out(&j), "out"));
            skb_status::SKB_OK
        }
    }
}

/// Writes joints as a `sketchbody-joints2d` file (joints with `visible == 0` listed in
/// `missing`), atomically: a temporary file renamed over `path`, which is replaced only when it
/// is a regular file. Thread-safe.
/// @param joints the joints, only read.
/// @param path the output file path, NUL-terminated UTF-8.
/// @return SKB_OK; SKB_ERR_NON_FINITE (a coordinate is NaN or infinite; nothing written);
///         SKB_ERR_IO; SKB_ERR_INVALID_ARGUMENT (`path` not UTF-8); argument errors as
///         docs/c-api.md.
#[no_mangle]
pub unsafe extern "C" fn skb_joints2d_write_json(joints: *const skb_joints2d, path: *const c_char) -> skb_status {
    unsafe {
        ffi_boundary! {
            let j = try_status!(try_ref(joints, "joints"));
            let p = try_status!(path_arg(path, "path"));
            try_core!(write_joints2d_with(p, &joints_in(j), None));
            skb_status::SKB_OK
        }
    }
}

#[cfg(test)]
mod tests {
    use std::ffi::{CStr, CString};

    use super::*;
    use crate::skb_last_error_message;

    fn message() -> String {
        // SAFETY: never NULL; valid until the next call on this thread.
        unsafe { CStr::from_ptr(skb_last_error_message()) }.to_string_lossy().into_owned()
    }

    fn zeroed() -> skb_joints2d {
        skb_joints2d { xy: [[0.0; 2]; 15], visible: [0; 15], reserved: 0 }
    }

    /// Writing then reading gives the same joints (missing ones kept), from a file and from
    /// memory; the example's joints file reads as the core reads it.
    #[test]
    fn joints_round_trip_through_files_and_memory() {
        let dir = std::env::temp_dir().join(format!("skb-capi-joints-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut j = zeroed();
        for k in 0..15 {
            j.xy[k] = [10.25 * k as f64, 300.0 - k as f64 / 3.0];
            j.visible[k] = u8::from(k != 4);
        }
        let p = CString::new(dir.join("j.json").to_str().unwrap()).unwrap();
        let mut back = zeroed();
        // SAFETY: live values and NUL-terminated paths.
        unsafe {
            assert_eq!(skb_joints2d_write_json(&j, p.as_ptr()), skb_status::SKB_OK, "{}", message());
            assert_eq!(skb_joints2d_read_json(p.as_ptr(), &mut back), skb_status::SKB_OK, "{}", message());
        }
        assert_eq!((back.xy, back.visible), (j.xy, j.visible));
        let text = std::fs::read(dir.join("j.json")).unwrap();
        let mut mem = zeroed();
        // SAFETY: `text` is valid for its length.
        let s = unsafe { skb_joints2d_parse_json(text.as_ptr().cast(), text.len(), &mut mem) };
        assert_eq!(s, skb_status::SKB_OK, "{}", message());
        assert_eq!((mem.xy, mem.visible), (j.xy, j.visible));
        let example = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch_joints.json");
        let core = load_joints2d(std::path::Path::new(example)).unwrap();
        let c = CString::new(example).unwrap();
        // SAFETY: as above.
        assert_eq!(unsafe { skb_joints2d_read_json(c.as_ptr(), &mut back) }, skb_status::SKB_OK);
        assert_eq!((back.xy, back.visible), (core.xy, core.visible.map(u8::from)));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Bad documents are statuses with nothing written: a key twice, an unknown joint, not
    /// UTF-8, over the size limit; a non-finite joint is not written.
    #[test]
    fn bad_documents_are_statuses_and_write_nothing() {
        let example =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/examples/sketch_joints.json"))
                .unwrap();
        let twice = example.replacen("\"head\":", "\"head\": [1, 2], \"head\":", 1);
        let unknown = example.replacen("\"head\":", "\"tail\": [1, 2], \"head\":", 1);
        let big = vec![b' '; (1 << 20) + 1];
        let cases: [(&[u8], skb_status); 4] = [
            (twice.as_bytes(), skb_status::SKB_ERR_CORRUPT_DATA),
            (unknown.as_bytes(), skb_status::SKB_ERR_CORRUPT_DATA),
            (b"{\"format\": \"\xff\"}", skb_status::SKB_ERR_CORRUPT_DATA),
            (&big, skb_status::SKB_ERR_OUT_OF_RANGE),
        ];
        for (bytes, want) in cases {
            let mut out = zeroed();
            out.reserved = 7;
            // SAFETY: `bytes` is valid for its length.
            let s = unsafe { skb_joints2d_parse_json(bytes.as_ptr().cast(), bytes.len(), &mut out) };
            assert_eq!(s, want, "{}", message());
            assert_eq!(out.reserved, 7, "written on failure");
        }
        assert!(message().contains("limit"));
        let mut j = zeroed();
        j.xy[3][1] = f64::NAN;
        let p = std::env::temp_dir().join(format!("skb-capi-joints-nan-{}.json", std::process::id()));
        let c = CString::new(p.to_str().unwrap()).unwrap();
        // SAFETY: live value, NUL-terminated path.
        assert_eq!(unsafe { skb_joints2d_write_json(&j, c.as_ptr()) }, skb_status::SKB_ERR_NON_FINITE);
        assert!(!p.exists());
    }
}

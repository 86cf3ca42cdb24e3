//! The thread-local last-error message.

use std::cell::RefCell;
use std::ffi::{c_char, CString};

use super::status::skb_status;

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

/// Stores `message` as this thread's last error (interior NULs are replaced).
pub(crate) fn set_last_error(message: &str) {
    let clean = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = clean);
}

/// Clears this thread's last error (called at the start of every entry point).
pub(crate) fn clear_last_error() {
    LAST_ERROR.with(|e| *e.borrow_mut() = CString::default());
}

/// Records a core error and returns its status.
pub(crate) fn fail(e: &sketchbody_core::Error) -> skb_status {
    set_last_error(&e.to_string());
    skb_status::from(e)
}

/// Records `message` and returns `status`.
pub(crate) fn fail_with(status: skb_status, message: &str) -> skb_status {
    set_last_error(message);
    status
}

/// The message of the last failed sketchbody call on this thread.
/// @return a NUL-terminated string owned by the library ("" after a success), valid until the
///         next sketchbody call on the same thread; never NULL; do not free it.
#[no_mangle]
pub extern "C" fn skb_last_error_message() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

//! Typed pointer checks: NULL becomes `SKB_ERR_NULL_POINTER` with the argument's name.

use super::error::fail_with;
use super::status::skb_status;

/// Borrows `*p`, or fails naming `name` when `p` is NULL.
///
/// # Safety
/// `p` must be NULL or point to a valid `T` that outlives `'a`.
pub(crate) unsafe fn try_ref<'a, T>(p: *const T, name: &str) -> Result<&'a T, skb_status> {
    p.as_ref().ok_or_else(|| null(name))
}

/// Borrows `len` bytes at `p`, or fails naming `name` when `p` is NULL.
///
/// # Safety
/// `p` must be NULL or valid for reads of `len` bytes for `'a`.
pub(crate) unsafe fn try_slice<'a>(p: *const u8, len: usize, name: &str) -> Result<&'a [u8], skb_status> {
    if p.is_null() {
        return Err(null(name));
    }
    Ok(std::slice::from_raw_parts(p, len))
}

/// Mutably borrows `len` bytes at `p`, or fails naming `name` when `p` is NULL.
///
/// # Safety
/// `p` must be NULL or valid for writes of `len` bytes for `'a`, with no other live reference.
pub(crate) unsafe fn try_slice_mut<'a>(p: *mut u8, len: usize, name: &str) -> Result<&'a mut [u8], skb_status> {
    if p.is_null() {
        return Err(null(name));
    }
    Ok(std::slice::from_raw_parts_mut(p, len))
}

/// Frees a handle made by `Box::into_raw`: NULL is a no-op, and a panic in the value's `Drop`
/// is contained (a `_free` function never unwinds into C).
///
/// # Safety
/// `p` must be NULL or a pointer from `Box::into_raw` not freed before.
pub(crate) unsafe fn free_box<T>(p: *mut T) {
    if !p.is_null() {
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| drop(Box::from_raw(p))));
    }
}

/// The caller's handle slot `*out` of a constructor, or fails with `out is NULL`.
///
/// # Safety
/// `out` must be NULL or valid for writes of one pointer for `'a`.
pub(crate) unsafe fn out_slot<'a, T>(out: *mut *mut T) -> Result<&'a mut *mut T, skb_status> {
    out.as_mut().ok_or_else(|| null("out"))
}

/// Stores `value` in `slot` as a new handle the caller owns (released with the type's `_free`,
/// see [`free_box`]) and returns `SKB_OK`.
pub(crate) fn give<T>(slot: &mut *mut T, value: T) -> skb_status {
    *slot = Box::into_raw(Box::new(value));
    skb_status::SKB_OK
}

fn null(name: &str) -> skb_status {
    fail_with(skb_status::SKB_ERR_NULL_POINTER, &format!("{name} is NULL"))
}

/// Evaluates a `Result<T, skb_status>`, returning the status from the enclosing function on error.
macro_rules! try_status {
    ($e:expr) => {
        match $e {
            Ok(v) => v,
            Err(status) => return status,
        }
    };
}

/// Evaluates a core `Result<T, Error>`, recording the error and returning its status on failure.
macro_rules! try_core {
    ($e:expr) => {
        match $e {
            Ok(v) => v,
            Err(e) => return $crate::error_fail(&e),
        }
    };
}

/// Borrows `len` elements of `T` at `p`, or fails naming `name` when `p` is NULL or `len`
/// elements would exceed the address space.
///
/// # Safety
/// `p` must be NULL or valid for reads of `len` elements of `T` for `'a`, suitably aligned.
pub(crate) unsafe fn try_slice_of<'a, T>(p: *const T, len: usize, name: &str) -> Result<&'a [T], skb_status> {
    if p.is_null() {
        return Err(null(name));
    }
    if len.checked_mul(std::mem::size_of::<T>()).is_none_or(|b| b > isize::MAX as usize) {
        return Err(fail_with(skb_status::SKB_ERR_OUT_OF_RANGE, &format!("{name}: {len} elements is absurd")));
    }
    Ok(std::slice::from_raw_parts(p, len))
}

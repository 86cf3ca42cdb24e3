//! The only module that turns the caller's raw pointers into references and slices: NULL
//! becomes `SKB_ERR_NULL_POINTER` with the argument's name, a length whose byte size exceeds
//! `isize::MAX` becomes `SKB_ERR_OUT_OF_RANGE`, a short output buffer `SKB_ERR_BUFFER_TOO_SMALL`.
//!
//! Each helper is `unsafe` with one contract: the pointer is NULL or valid as the header
//! documents for the called function (lib.rs § Safety). The helpers check everything a pointer
//! and a length can be checked for (NULL, alignment of typed pointers is the caller's, the
//! address-space bound) before building the reference.

use std::ffi::{c_char, CStr};
use std::path::Path;

use sketchbody_core::error::Error;

use super::error::{fail, fail_with};
use super::status::skb_status;

/// Records `SKB_ERR_NULL_POINTER` with "`name` is NULL" and returns the status.
pub(crate) fn null(name: &str) -> skb_status {
    fail_with(skb_status::SKB_ERR_NULL_POINTER, &format!("{name} is NULL"))
}

/// Borrows `*p`, or fails naming `name` when `p` is NULL.
///
/// # Safety
/// `p` must be NULL or point to a valid `T` that outlives `'a`.
pub(crate) unsafe fn try_ref<'a, T>(p: *const T, name: &str) -> Result<&'a T, skb_status> {
    // SAFETY: the caller guarantees `p` is NULL or valid for `'a`; `as_ref` maps NULL to None.
    unsafe { p.as_ref() }.ok_or_else(|| null(name))
}

/// Mutably borrows `*p`, or fails naming `name` when `p` is NULL.
///
/// # Safety
/// `p` must be NULL or point to a valid `T` with no other live reference for `'a`.
pub(crate) unsafe fn try_mut<'a, T>(p: *mut T, name: &str) -> Result<&'a mut T, skb_status> {
    // SAFETY: the caller guarantees `p` is NULL or valid and unaliased for `'a`; NULL is None.
    unsafe { p.as_mut() }.ok_or_else(|| null(name))
}

/// Borrows `*p` if `p` is not NULL (an optional argument: NULL means "use the default").
///
/// # Safety
/// `p` must be NULL or point to a valid `T` that outlives `'a`.
pub(crate) unsafe fn opt_ref<'a, T>(p: *const T) -> Option<&'a T> {
    // SAFETY: the caller guarantees `p` is NULL or valid for `'a`; `as_ref` maps NULL to None.
    unsafe { p.as_ref() }
}

/// Mutably borrows `*p` if `p` is not NULL (an optional argument).
///
/// # Safety
/// `p` must be NULL or point to a valid `T` with no other live reference for `'a`.
pub(crate) unsafe fn opt_mut<'a, T>(p: *mut T) -> Option<&'a mut T> {
    // SAFETY: the caller guarantees `p` is NULL or valid and unaliased for `'a`; NULL is None.
    unsafe { p.as_mut() }
}

/// Writes `value` through the out-pointer `out`, or fails naming `name` when it is NULL.
///
/// # Safety
/// `out` must be NULL or valid for a write of `T`.
pub(crate) unsafe fn write_out<T>(out: *mut T, value: T, name: &str) -> Result<(), skb_status> {
    // SAFETY: forwarded contract: `out` is NULL or valid and unaliased for this write.
    *unsafe { try_mut(out, name) }? = value;
    Ok(())
}

/// Writes `value` through the optional out-pointer `out`; NULL skips the write.
///
/// # Safety
/// `out` must be NULL or valid for a write of `T`.
pub(crate) unsafe fn write_opt<T>(out: *mut T, value: T) {
    // SAFETY: the caller guarantees `out` is NULL or valid and unaliased; NULL is None.
    if let Some(o) = unsafe { out.as_mut() } {
        *o = value;
    }
}

/// Fails with `SKB_ERR_OUT_OF_RANGE` when `len` elements of `T` exceed `isize::MAX` bytes (no
/// real buffer is that large; `std::slice::from_raw_parts` requires the bound).
fn check_len<T>(len: usize, name: &str) -> Result<(), skb_status> {
    if len.checked_mul(std::mem::size_of::<T>()).is_none_or(|b| b > isize::MAX as usize) {
        return Err(fail_with(skb_status::SKB_ERR_OUT_OF_RANGE, &format!("{name}: {len} elements is absurd")));
    }
    Ok(())
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
    check_len::<T>(len, name)?;
    // SAFETY: `p` is not NULL (checked), the byte size is within `isize::MAX` (checked), and the
    // caller guarantees `p` is valid and aligned for `len` elements for `'a`.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// Mutably borrows `len` elements of `T` at `p`, or fails naming `name` when `p` is NULL or
/// `len` elements would exceed the address space.
///
/// # Safety
/// `p` must be NULL or valid for writes of `len` elements of `T` for `'a`, suitably aligned,
/// with no other live reference.
pub(crate) unsafe fn try_slice_mut_of<'a, T>(p: *mut T, len: usize, name: &str) -> Result<&'a mut [T], skb_status> {
    if p.is_null() {
        return Err(null(name));
    }
    check_len::<T>(len, name)?;
    // SAFETY: `p` is not NULL (checked), the byte size is within `isize::MAX` (checked), and the
    // caller guarantees `p` is valid, aligned and unaliased for `len` elements for `'a`.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// Borrows `len` bytes at `p` (see [`try_slice_of`]).
///
/// # Safety
/// `p` must be NULL or valid for reads of `len` bytes for `'a`.
pub(crate) unsafe fn try_slice<'a>(p: *const u8, len: usize, name: &str) -> Result<&'a [u8], skb_status> {
    // SAFETY: forwarded contract.
    unsafe { try_slice_of(p, len, name) }
}

/// Mutably borrows `len` bytes at `p` (see [`try_slice_mut_of`]).
///
/// # Safety
/// `p` must be NULL or valid for writes of `len` bytes for `'a`, with no other live reference.
pub(crate) unsafe fn try_slice_mut<'a>(p: *mut u8, len: usize, name: &str) -> Result<&'a mut [u8], skb_status> {
    // SAFETY: forwarded contract.
    unsafe { try_slice_mut_of(p, len, name) }
}

/// Mutable view of an output array of `len` elements at `p`, which must hold at least `needed`:
/// NULL gives `SKB_ERR_NULL_POINTER`, a short buffer `SKB_ERR_BUFFER_TOO_SMALL`, an absurd `len`
/// `SKB_ERR_OUT_OF_RANGE` (lengths in elements).
///
/// # Safety
/// `p` must be NULL or valid for writes of `len` elements of `T`, with no other live reference.
pub(crate) unsafe fn out_slice<'a, T>(
    p: *mut T,
    len: usize,
    needed: usize,
    name: &'static str,
) -> Result<&'a mut [T], skb_status> {
    if p.is_null() {
        return Err(null(name));
    }
    if len < needed {
        let unit = if std::mem::size_of::<T>() == 1 { "bytes" } else { "elements" };
        return Err(fail(&Error::BufferTooSmall { name, len, needed, unit }));
    }
    // SAFETY: forwarded contract.
    unsafe { try_slice_mut_of(p, len, name) }
}

/// Writes `text` NUL-terminated into `dst` of `len` bytes (at least `text.len() + 1`). Errors as
/// [`out_slice`].
///
/// # Safety
/// `dst` must be NULL or valid for writes of `len` bytes, with no other live reference.
pub(crate) unsafe fn write_c_string(
    dst: *mut c_char,
    len: usize,
    text: &str,
    name: &'static str,
) -> Result<(), skb_status> {
    let bytes = text.as_bytes();
    // SAFETY: forwarded contract.
    let o = unsafe { out_slice(dst, len, bytes.len() + 1, name) }?;
    for (o, &c) in o.iter_mut().zip(bytes) {
        *o = c as c_char;
    }
    o[bytes.len()] = 0;
    Ok(())
}

/// The optional fixed-size output array `p[0..len]`: `None` when `p` is NULL.
///
/// # Safety
/// `p` must be NULL or valid for writes of `len` elements of `T`, with no other live reference.
pub(crate) unsafe fn opt_slice_mut<'a, T>(
    p: *mut T,
    len: usize,
    name: &str,
) -> Result<Option<&'a mut [T]>, skb_status> {
    if p.is_null() {
        return Ok(None);
    }
    // SAFETY: forwarded contract.
    unsafe { try_slice_mut_of(p, len, name) }.map(Some)
}

/// Borrows a NUL-terminated UTF-8 string, failing naming `name` when it is NULL
/// (`SKB_ERR_NULL_POINTER`) or not UTF-8 (`SKB_ERR_INVALID_ARGUMENT`).
///
/// # Safety
/// `p` must be NULL or point to a NUL-terminated string that outlives `'a`.
pub(crate) unsafe fn try_str<'a>(p: *const c_char, name: &str) -> Result<&'a str, skb_status> {
    if p.is_null() {
        return Err(null(name));
    }
    // SAFETY: `p` is not NULL (checked) and the caller guarantees it is NUL-terminated.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| fail_with(skb_status::SKB_ERR_INVALID_ARGUMENT, &format!("{name} is not UTF-8")))
}

/// Frees a handle made by `Box::into_raw`: NULL is a no-op, and a panic in the value's `Drop`
/// is contained (a `_free` function never unwinds into C).
///
/// # Safety
/// `p` must be NULL or a pointer from `Box::into_raw` not freed before.
pub(crate) unsafe fn free_box<T>(p: *mut T) {
    if !p.is_null() {
        // SAFETY: `p` is not NULL (checked) and the caller guarantees it came from
        // `Box::into_raw` and is freed only now.
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| drop(unsafe { Box::from_raw(p) })));
    }
}

/// The caller's handle slot `*out` of a constructor, or fails with `out is NULL`.
///
/// # Safety
/// `out` must be NULL or valid for writes of one pointer for `'a`.
pub(crate) unsafe fn out_slot<'a, T>(out: *mut *mut T) -> Result<&'a mut *mut T, skb_status> {
    // SAFETY: forwarded contract.
    unsafe { try_mut(out, "out") }
}

/// Stores `value` in `slot` as a new handle the caller owns (released with the type's `_free`,
/// see [`free_box`]) and returns `SKB_OK`.
pub(crate) fn give<T>(slot: &mut *mut T, value: T) -> skb_status {
    *slot = Box::into_raw(Box::new(value));
    skb_status::SKB_OK
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

/// Borrows a NUL-terminated UTF-8 path.
///
/// # Safety
/// `p` must be NULL or point to a NUL-terminated string that outlives `'a`.
pub(crate) unsafe fn path_arg<'a>(p: *const c_char, name: &str) -> Result<&'a Path, skb_status> {
    // SAFETY: forwarded contract: `p` is NULL or a NUL-terminated string outliving `'a`.
    Ok(Path::new(unsafe { try_str(p, name) }?))
}

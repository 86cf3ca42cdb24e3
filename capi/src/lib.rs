//! The C ABI: the only module with `extern "C"` functions and raw pointers.
//!
//! Conventions (see `docs/c-api.md`): every function returns an [`skb_status`] (0 = OK) and
//! writes results through trailing out-parameters; on failure a thread-local message is
//! available from [`skb_last_error_message`] and no output is written. Every entry point checks
//! its pointers and sizes and runs inside a panic boundary, so a Rust panic becomes
//! `SKB_ERR_PANIC` instead of aborting the host. Only the three text getters (`skb_version`,
//! `skb_status_str`, `skb_last_error_message`) return a pointer instead of a status, and the
//! `skb_*_free` functions return nothing (freeing NULL is a no-op).
//!
//! # Safety (every `unsafe extern "C"` function)
//! Pointer arguments must be NULL (reported as `SKB_ERR_NULL_POINTER` where a value is needed)
//! or valid for the documented number of elements for the duration of the call; handles must
//! come from the matching `skb_*_new` and not be freed yet; strings are NUL-terminated UTF-8.
//! The per-function docs state only what differs, so clippy's per-function `# Safety` section is
//! not repeated 100 times.
#![allow(non_camel_case_types)]
#![allow(clippy::missing_safety_doc)]
#![deny(unsafe_op_in_unsafe_fn)]

// Macros first; then the modules in the order the header presents them (cbindgen follows it):
// status, errors and version, then images, bodies, poses, detection, the fit and the pipeline.
#[macro_use]
mod panic;
#[macro_use]
mod ptr;
mod status;
mod error;
mod version;
mod image;
mod body;
mod mesh_ops;
mod export;
mod rig;
mod pose;
mod joints_io;
mod detect;
mod facing;
mod fit;
mod pipeline;
mod views;
mod texture;
mod sketch;

#[cfg(test)]
mod tests;

// Every `pub` item of these modules is part of the C API (helpers are `pub(crate)`), so the
// Rust-side list cannot drift from the header: the header is generated from the same items.
pub use body::*;
pub use detect::*;
pub use error::*;
pub use export::*;
pub use facing::*;
pub use fit::*;
pub use image::*;
pub use joints_io::*;
pub use mesh_ops::*;
pub use pipeline::*;
pub use pose::*;
pub use rig::*;
pub use sketch::*;
pub use status::*;
pub use texture::*;
pub use version::*;
pub use views::*;

pub(crate) use error::{clear_last_error as error_reset, fail as error_fail};
pub(crate) use panic::panic_status;

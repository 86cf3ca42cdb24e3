//! sketchbody: turn a 2-D concept sketch of a human character into a rigged 3-D base mesh.
//!
//! The core library: safe Rust that returns [`Error`] values and never panics on bad input (the
//! C ABI is the workspace member `capi/`, the command-line tool `cli/`). Conventions (joint order, image and 3-D frames, camera) are those of
//! `docs/design.md`: image space is pixels with the origin at the top-left corner of the top-left
//! pixel, x right, y down; 3-D space is metres, right-handed, +Y up, +Z toward the viewer.

#![deny(missing_docs)]

pub mod body;
pub mod camera;
pub mod detect;
pub mod error;
pub mod export;
pub mod fit;
pub mod fsutil;
#[cfg(test)]
mod fuzz_seeds;
pub mod image;
pub mod pipeline;
pub mod pose;
pub mod raster;
pub mod render;
pub mod sheet;
pub mod skeleton;
pub mod strict_json;
pub mod view;

pub use error::{Error, Result};

/// The library version, `MAJOR.MINOR.PATCH`, taken from Cargo.toml at build time.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

//! sketchbody's research lab: the code that makes and measures the assets the core library
//! ships, kept apart so that a C consumer or the artist's CLI compiles none of it.
//!
//! - [`eval`]: scoring results against synthetic datasets (AED, MPJPE, PCK) and the detector's
//!   and backends' benchmarks.
//! - [`detect`]: training the sketch detector and the PARSE evaluation protocol.
//! - [`pose`]: learning the pose dictionary from mocap and BVH files, training the factor
//!   prior, 3-D pose error metrics.
//! - [`render`]: stylisations of photos (benchmark and training filters) and capsule mannequins
//!   (extra detector-training positives).

#![deny(missing_docs)]

pub mod detect;
pub mod eval;
pub mod fit;
pub mod pose;
pub mod render;

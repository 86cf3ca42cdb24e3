//! Rendering for people and for data: preview images of a body, and the synthetic concept-sketch
//! renderer (the data generator of training and benchmark sets). The rasteriser the shape fit
//! uses is [`crate::raster`]. `photo_npr`: drawing-like filters for training photos (never the
//! benchmark's `stylise`).

pub mod photo_npr;
pub mod preview;
pub mod sketch;
pub mod stylise;

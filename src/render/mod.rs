//! Rendering for people and for data: preview images of a body, and the synthetic concept-sketch
//! renderer (the data generator of training and benchmark sets). The rasteriser the shape fit
//! uses is [`crate::raster`]. The stylisations of photos are in the `sketchbody-lab` crate.

pub mod preview;
pub mod sketch;

//! Rendering: the silhouette/depth rasteriser used by the shape fit, preview images, and the
//! synthetic concept-sketch renderer.

pub mod preview;
pub mod raster;
pub mod sketch;

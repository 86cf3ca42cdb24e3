//! Rendering: the silhouette/depth rasteriser used by the shape fit, and preview images.

pub mod preview;
pub mod raster;

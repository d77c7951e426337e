//! The photogrammetry crate's images as cacheable artifacts: raw little-endian `f32` rasters (the engine's
//! raster encoding, `codec::encode_raster`), so the store moves their samples with one write and one read.

use skytie_stages::imaging::{GrayImage, RgbImage};

crate::raster_artifact!(GrayImage, b"GRAY", "gray image", 1);
crate::raster_artifact!(RgbImage, b"RGB3", "RGB image", 3);

//! Image buffers and the low-level operations on them (sampling, filters, I/O).
//!
//! Pixel convention everywhere (campaign-format.md): continuous coordinates, the image's top-left corner is
//! (0, 0), u grows right, v down, the centre of the first pixel is (0.5, 0.5).

pub mod image;
pub mod io;

pub use image::{GrayImage, RgbImage};

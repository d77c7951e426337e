//! Decoding image files into rows of grey samples, in bounded memory: JPEG (baseline and progressive), PNG
//! (8/16-bit, any colour type, interlaced or not) and TIFF / BigTIFF (8/16-bit grey, RGB, RGBA or YCbCr;
//! strips or tiles; uncompressed, LZW, Deflate, PackBits or JPEG). The format comes from the file's first
//! bytes, not its name.
//!
//! Rows go to a [`GreyRowSink`] top to bottom — the pyramid builder, or [`collect::GreyCollector`] for a
//! whole in-memory image. What each format holds in memory at once:
//! - PNG (non-interlaced) and TIFF are streamed: one row (PNG) or one row of strips/tiles (TIFF);
//! - JPEG and interlaced PNG are decoded whole, as one grey plane (width × height bytes, × 2 at 16 bits).
//!
//! Before anything is decoded, the file is probed ([`crate::imaging::probe`]): its format comes from its
//! content, a truncated or damaged file is refused with the reason, and a header whose size the file cannot
//! hold (100000 × 100000 pixels in 1 KB) is refused before any allocation. The decoding buffers are then
//! reserved from the memory budget ([`limits::reserve`], [`crate::imaging::budget`]).
//!
//! Grey is the luma of JPEG/JFIF, `Y = 0.299 R + 0.587 G + 0.114 B` on the stored (gamma-encoded) values:
//! a JPEG's own Y plane is taken as it is, RGB samples are converted with these weights
//! ([`grey::luma8`], [`grey::luma16`]); alpha is ignored. 16-bit images stay 16-bit.

pub mod collect;
pub mod geotiff;
pub mod grey;
pub mod jpeg;
pub mod limits;
pub mod png;
pub mod tiff;
mod tiff_jpeg;
mod tiff_lzw;

pub use geotiff::GeoTiffTags;

use super::io_error::ImageIoError;
use super::probe::probe;
pub use super::probe::{ImageFormat, ImageHeader};
use super::pyramid::SampleDepth;
use std::path::Path;

/// What a decoder announces before the rows.
#[derive(Clone, Debug, PartialEq)]
pub struct GreyInfo {
    pub width: usize,
    pub height: usize,
    /// Depth of the samples the rows carry.
    pub depth: SampleDepth,
    pub format: ImageFormat,
    /// GeoTIFF georeferencing tags, when the file has them.
    pub geotiff: Option<GeoTiffTags>,
}

/// Receives a decoded image: [`GreyRowSink::begin`] once, then `height` rows of `width` samples, top to
/// bottom, all of the announced depth.
pub trait GreyRowSink {
    fn begin(&mut self, info: &GreyInfo) -> std::io::Result<()>;
    fn row_u8(&mut self, row: &[u8]) -> std::io::Result<()>;
    fn row_u16(&mut self, row: &[u16]) -> std::io::Result<()>;
}

/// Decodes `path` into `sink` (see the module documentation). Errors name the file and the reason.
pub fn decode_grey(path: &Path, sink: &mut dyn GreyRowSink) -> Result<GreyInfo, ImageIoError> {
    let header = probe_file(path)?;
    match header.format {
        ImageFormat::Jpeg => jpeg::decode(path, &header, sink),
        ImageFormat::Png => png::decode(path, sink),
        ImageFormat::Tiff | ImageFormat::BigTiff => tiff::decode(path, &header, sink),
    }
}

/// The header of `path` after [`probe`] found the file complete and its claimed size storable (a truncated
/// file, an absurd header or a format the decoders do not read is an error naming the file and what to do).
pub fn probe_file(path: &Path) -> Result<ImageHeader, ImageIoError> {
    probe(path).map_err(|e| ImageIoError::new(path, format!("{e}; {}", e.hint())))
}

/// A sink failure (e.g. the pyramid file could not be written) as an error naming the source image.
pub(crate) fn sink_error(path: &Path, e: std::io::Error) -> ImageIoError {
    ImageIoError::new(path, format!("cannot store the decoded image ({e})"))
}

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
//! Before anything large is allocated, the header's size is checked against the file's length (a 1 KB
//! file cannot hold 100000 × 100000 pixels, [`limits`]) and the buffers are reserved from the memory
//! budget ([`crate::imaging::budget`]).
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
mod tiff_lzw;

pub use geotiff::GeoTiffTags;

use super::io::ImageIoError;
use super::pyramid::SampleDepth;
use std::io::Read;
use std::path::Path;

/// The container formats skytie reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum FileFormat {
    Jpeg,
    Png,
    Tiff,
    BigTiff,
}

impl FileFormat {
    pub fn name(self) -> &'static str {
        match self {
            FileFormat::Jpeg => "JPEG",
            FileFormat::Png => "PNG",
            FileFormat::Tiff => "TIFF",
            FileFormat::BigTiff => "BigTIFF",
        }
    }
}

/// What a decoder announces before the rows.
#[derive(Clone, Debug, PartialEq)]
pub struct GreyInfo {
    pub width: usize,
    pub height: usize,
    /// Depth of the samples the rows carry.
    pub depth: SampleDepth,
    pub format: FileFormat,
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

/// The format of `path` from its first bytes.
pub fn detect_format(path: &Path) -> Result<FileFormat, ImageIoError> {
    let mut head = [0u8; 8];
    let mut file = std::fs::File::open(path).map_err(|e| {
        ImageIoError::new(
            path,
            format!("cannot open ({e}); check that the file exists and is readable"),
        )
    })?;
    let n = read_up_to(&mut file, &mut head)
        .map_err(|e| ImageIoError::new(path, format!("cannot read ({e})")))?;
    let head = &head[..n];
    if head.starts_with(&[0xFF, 0xD8, 0xFF]) {
        Ok(FileFormat::Jpeg)
    } else if head.starts_with(b"\x89PNG\r\n\x1a\n") {
        Ok(FileFormat::Png)
    } else if head.starts_with(b"II*\0") || head.starts_with(b"MM\0*") {
        Ok(FileFormat::Tiff)
    } else if head.starts_with(b"II+\0") || head.starts_with(b"MM\0+") {
        Ok(FileFormat::BigTiff)
    } else if n == 0 {
        Err(ImageIoError::new(
            path,
            "is empty (0 bytes); replace it with the image",
        ))
    } else {
        Err(ImageIoError::new(
            path,
            format!(
                "is not a JPEG, PNG or TIFF file (it starts with bytes {:02x?}); skytie reads only these",
                head
            ),
        ))
    }
}

fn read_up_to(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

/// Decodes `path` into `sink` (see the module documentation). Errors name the file and the reason.
pub fn decode_grey(path: &Path, sink: &mut dyn GreyRowSink) -> Result<GreyInfo, ImageIoError> {
    match detect_format(path)? {
        FileFormat::Jpeg => jpeg::decode(path, sink),
        FileFormat::Png => png::decode(path, sink),
        FileFormat::Tiff | FileFormat::BigTiff => tiff::decode(path, sink),
    }
}

/// A sink failure (e.g. the pyramid file could not be written) as an error naming the source image.
pub(crate) fn sink_error(path: &Path, e: std::io::Error) -> ImageIoError {
    ImageIoError::new(path, format!("cannot store the decoded image ({e})"))
}

//! Ingestion: an image file decoded once ([`super::decode`]) straight into a pyramid file
//! ([`super::pyramid`]), row by row — the one full pass over an image's pixels the pipeline makes.

use super::decode::{decode_grey, GreyInfo, GreyRowSink};
use super::io_error::ImageIoError;
use super::pyramid::{PyramidBuilder, PyramidSummary, DEFAULT_TILE_SIDE};
use std::io;
use std::path::{Path, PathBuf};

/// What ingesting a file produced.
#[derive(Clone, Debug, PartialEq)]
pub struct Ingested {
    pub info: GreyInfo,
    pub pyramid: PyramidSummary,
}

/// Sends decoded rows into a pyramid builder created when the size is known.
struct PyramidSink {
    dest: PathBuf,
    tile_side: usize,
    builder: Option<PyramidBuilder>,
}

impl GreyRowSink for PyramidSink {
    fn begin(&mut self, info: &GreyInfo) -> io::Result<()> {
        self.builder = Some(PyramidBuilder::create(
            &self.dest,
            info.width,
            info.height,
            info.depth,
            self.tile_side,
        )?);
        Ok(())
    }

    fn row_u8(&mut self, row: &[u8]) -> io::Result<()> {
        self.builder
            .as_mut()
            .ok_or_else(|| io::Error::other("internal: rows before the size"))?
            .push_row_u8(row)
    }

    fn row_u16(&mut self, row: &[u16]) -> io::Result<()> {
        self.builder
            .as_mut()
            .ok_or_else(|| io::Error::other("internal: rows before the size"))?
            .push_row_u16(row)
    }
}

/// Decodes `source` into the pyramid file `dest` (written atomically; nothing is left at `dest` on error).
pub fn ingest(source: &Path, dest: &Path) -> Result<Ingested, ImageIoError> {
    ingest_with_tiles(source, dest, DEFAULT_TILE_SIDE)
}

/// [`ingest`] with a chosen tile side (pixels).
pub fn ingest_with_tiles(
    source: &Path,
    dest: &Path,
    tile_side: usize,
) -> Result<Ingested, ImageIoError> {
    let mut sink = PyramidSink {
        dest: dest.to_path_buf(),
        tile_side,
        builder: None,
    };
    let info = decode_grey(source, &mut sink)?;
    let builder = sink
        .builder
        .ok_or_else(|| ImageIoError::new(source, "internal: the decoder produced no image"))?;
    let pyramid = builder.finish().map_err(|e| {
        ImageIoError::new(
            source,
            format!("cannot complete its pyramid in {} ({e})", dest.display()),
        )
    })?;
    Ok(Ingested { info, pyramid })
}

//! A pyramid held in memory, built from an image already decoded (tools, tests, small images): the same
//! tiles and levels as a pyramid file, so stages read it through the same windows.

use super::builder::{Chain, TileSink};
use super::layout::{PyramidLayout, SampleDepth, DEFAULT_TILE_SIDE};
use super::reader::{PyramidError, PyramidHeader, TileId, TileSource};
use crate::imaging::GrayImage;
use std::io;
use std::path::Path;
use std::sync::{Arc, Mutex};

/// Tiles collected in memory, by index.
struct MemorySink(Mutex<Vec<Option<Arc<[u8]>>>>);

impl TileSink for MemorySink {
    fn put_tile(&self, _layout: &PyramidLayout, index: usize, bytes: Vec<u8>) -> io::Result<()> {
        let mut tiles = self.0.lock().unwrap_or_else(|p| p.into_inner());
        tiles[index] = Some(bytes.into());
        Ok(())
    }
}

/// A pyramid in memory.
pub struct MemoryPyramid {
    header: PyramidHeader,
    tiles: Vec<Arc<[u8]>>,
}

impl MemoryPyramid {
    /// The pyramid of a grey image (values 0..1, clamped), stored as 16-bit samples (`round(v · 65535)`).
    pub fn from_gray(img: &GrayImage) -> Self {
        let layout = PyramidLayout::new(
            img.width.max(1),
            img.height.max(1),
            SampleDepth::U16,
            DEFAULT_TILE_SIDE,
        )
        .expect("an in-memory image has a layout");
        let sink = MemorySink(Mutex::new(vec![None; layout.tile_count()]));
        let mut chain: Chain<u16, MemorySink> = Chain::new(layout.clone(), sink);
        let mut row: Vec<u16> = Vec::with_capacity(layout.width);
        for r in 0..layout.height {
            row.clear();
            if img.width == 0 || img.height == 0 {
                row.push(0);
            } else {
                row.extend(
                    img.row(r)
                        .iter()
                        .map(|&v| (v.clamp(0.0, 1.0) * 65535.0).round() as u16),
                );
            }
            chain.push_row(&row).expect("memory sink never fails");
        }
        let done = chain.finish().expect("all rows were pushed");
        let tiles = done
            .sink
            .0
            .into_inner()
            .unwrap_or_else(|p| p.into_inner())
            .into_iter()
            .map(|t| t.expect("every tile was written"))
            .collect();
        // Grey = sample / 65535 whatever the largest value (the image's own 0..1 scale).
        Self {
            header: PyramidHeader {
                layout: done.layout,
                white: u16::MAX,
            },
            tiles,
        }
    }
}

impl TileSource for MemoryPyramid {
    fn header(&self) -> &PyramidHeader {
        &self.header
    }

    fn tile(&self, id: TileId) -> Result<Arc<[u8]>, PyramidError> {
        match self.header.layout.existing_tile_index(id) {
            Some(index) => Ok(Arc::clone(&self.tiles[index])),
            None => Err(PyramidError::missing_tile(
                Path::new("(memory)"),
                id,
                "does not exist",
            )),
        }
    }
}

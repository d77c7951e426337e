//! A pyramid decoded from an image file straight into memory, keeping only the tiles under the regions the
//! caller will read: views of a whole campaign image at a coarse level, or a window of it, in memory bounded
//! by what is kept (plus the decoder's own buffers), never by the image's size. The tiles are the ones
//! ingestion writes ([`super::pyramid::PyramidBuilder`]: same decoder, same levels), so a window read from it
//! equals the window a stage reads from the ingested pyramid.

use super::pyramid::builder::{DepthChain, TileSink};
use super::pyramid::layout::{PyramidLayout, DEFAULT_TILE_SIDE};
use super::pyramid::reader::{PyramidError, PyramidHeader, TileId, TileSource};
use crate::imaging::decode::{decode_grey, limits, GreyInfo, GreyRowSink};
use crate::imaging::io_error::ImageIoError;
use std::collections::HashMap;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// A part of one pyramid level that will be read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    /// The level (beyond the coarsest: the coarsest).
    pub level: usize,
    /// The continuous box [u0, v0, u1, v1) in full-resolution pixels; `None` for the whole level.
    pub box_full_px: Option<[f64; 4]>,
}

impl Region {
    /// All of `level`.
    pub fn whole(level: usize) -> Self {
        Self {
            level,
            box_full_px: None,
        }
    }

    /// The box [u0, v0, u1, v1) (full-resolution pixels) of `level`.
    pub fn window(level: usize, box_full_px: [f64; 4]) -> Self {
        Self {
            level,
            box_full_px: Some(box_full_px),
        }
    }

    /// Marks in `kept` (one flag per tile index of `layout`) the tiles under this region, one pixel of margin
    /// on every side (bilinear neighbours, whole-pixel rounding of a window's box).
    fn mark(&self, layout: &PyramidLayout, kept: &mut [bool]) {
        let level = self.level.min(layout.levels() - 1);
        let (lw, lh) = layout.level_sizes[level];
        let (across, down) = layout.tiles(level);
        let ts = layout.tile_side as f64;
        let (tx0, ty0, tx1, ty1) = match self.box_full_px {
            None => (0, 0, across, down),
            Some([u0, v0, u1, v1]) => {
                let s = (1u64 << level) as f64;
                // Pixel ranges of the level, clamped to it (NaN clamps to the low end).
                let lo = |x: f64, n: usize| ((x / s).floor() - 1.0).clamp(0.0, n as f64 - 1.0);
                let hi = |x: f64, n: usize| ((x / s).ceil() + 1.0).clamp(1.0, n as f64);
                let (c0, c1) = (lo(u0, lw), hi(u1, lw).max(lo(u0, lw) + 1.0));
                let (r0, r1) = (lo(v0, lh), hi(v1, lh).max(lo(v0, lh) + 1.0));
                (
                    (c0 / ts) as usize,
                    (r0 / ts) as usize,
                    ((c1 / ts).ceil() as usize).min(across),
                    ((r1 / ts).ceil() as usize).min(down),
                )
            }
        };
        for ty in ty0..ty1 {
            for tx in tx0..tx1 {
                kept[layout.tile_index(level, tx, ty)] = true;
            }
        }
    }
}

/// Tiles kept by index; the others are dropped as soon as they are made.
struct KeepSink {
    kept: Vec<bool>,
    tiles: Mutex<HashMap<usize, Arc<[u8]>>>,
}

impl TileSink for KeepSink {
    fn put_tile(&self, _layout: &PyramidLayout, index: usize, bytes: Vec<u8>) -> io::Result<()> {
        if self.kept[index] {
            let mut tiles = self.tiles.lock().unwrap_or_else(|p| p.into_inner());
            tiles.insert(index, bytes.into());
        }
        Ok(())
    }
}

/// Receives the decoder's rows; sets up the chain once the size is known.
struct PartialBuild<F> {
    path: PathBuf,
    regions: Option<F>,
    chain: Option<DepthChain<KeepSink>>,
    reservation: Option<crate::imaging::budget::Reservation<'static>>,
}

impl<F> PartialBuild<F> {
    /// The chain the decoder's rows go to, once it has said the image's size.
    fn started(&mut self) -> io::Result<&mut DepthChain<KeepSink>> {
        self.chain
            .as_mut()
            .ok_or_else(|| io::Error::other("internal: rows before the size"))
    }
}

impl<F: FnOnce(&PyramidLayout) -> Vec<Region>> GreyRowSink for PartialBuild<F> {
    fn begin(&mut self, info: &GreyInfo) -> io::Result<()> {
        let layout = PyramidLayout::new(info.width, info.height, info.depth, DEFAULT_TILE_SIDE)
            .ok_or_else(|| {
                io::Error::other(format!(
                    "no pyramid layout for a {} × {} image",
                    info.width, info.height
                ))
            })?;
        let regions = self
            .regions
            .take()
            .ok_or_else(|| io::Error::other("internal: the decoder began twice"))?(
            &layout
        );
        let mut kept = vec![false; layout.tile_count()];
        for r in &regions {
            r.mark(&layout, &mut kept);
        }
        let bytes = kept.iter().filter(|k| **k).count() * layout.tile_bytes();
        self.reservation = Some(
            limits::reserve(
                &self.path,
                info.format.name(),
                info.width,
                info.height,
                bytes,
                "the tiles of the part of it that is read",
            )
            .map_err(io::Error::other)?,
        );
        let sink = KeepSink {
            kept,
            tiles: Mutex::new(HashMap::new()),
        };
        self.chain = Some(DepthChain::new(layout, sink));
        Ok(())
    }

    fn row_u8(&mut self, row: &[u8]) -> io::Result<()> {
        self.started()?.push_row(row)
    }

    fn row_u16(&mut self, row: &[u16]) -> io::Result<()> {
        self.started()?.push_row(row)
    }
}

/// The tiles of some regions of an image file's pyramid, in memory; see the module documentation.
pub struct PartialPyramid {
    path: PathBuf,
    header: PyramidHeader,
    tiles: HashMap<usize, Arc<[u8]>>,
}

impl PartialPyramid {
    /// Decodes `path` once, keeping the tiles under the regions `regions` names once the image's layout is
    /// known. The kept tiles are reserved from the memory budget while the file is decoded.
    pub fn decode(
        path: &Path,
        regions: impl FnOnce(&PyramidLayout) -> Vec<Region>,
    ) -> Result<Self, ImageIoError> {
        let mut build = PartialBuild {
            path: path.to_path_buf(),
            regions: Some(regions),
            chain: None,
            reservation: None,
        };
        decode_grey(path, &mut build)?;
        let fail =
            |e: io::Error| ImageIoError::new(path, format!("cannot complete its pyramid ({e})"));
        let (layout, white, sink) = match build.chain.take() {
            Some(c) => {
                let f = c.finish().map_err(fail)?;
                (f.layout, f.white, f.sink)
            }
            None => {
                return Err(ImageIoError::new(
                    path,
                    "internal: the decoder produced no image",
                ))
            }
        };
        Ok(Self {
            path: path.to_path_buf(),
            header: PyramidHeader { layout, white },
            tiles: sink.tiles.into_inner().unwrap_or_else(|p| p.into_inner()),
        })
    }

    /// Bytes of the tiles held.
    pub fn kept_bytes(&self) -> usize {
        self.tiles.len() * self.header.layout.tile_bytes()
    }
}

impl TileSource for PartialPyramid {
    fn header(&self) -> &PyramidHeader {
        &self.header
    }

    fn tile(&self, id: TileId) -> Result<Arc<[u8]>, PyramidError> {
        let why = "was not kept when the file was decoded";
        self.header
            .layout
            .existing_tile_index(id)
            .and_then(|i| self.tiles.get(&i))
            .map(Arc::clone)
            .ok_or_else(|| PyramidError::missing_tile(&self.path, id, why))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imaging::pyramid::{read_window, PixelRect, ScaledWindow, TiledPyramid};

    /// A 600 × 420 grey PNG with varied content and its ingested pyramid.
    fn image_and_pyramid(dir: &Path) -> (PathBuf, TiledPyramid) {
        let (w, h) = (600u32, 420u32);
        let img = image::GrayImage::from_fn(w, h, |x, y| {
            image::Luma([((x * 7 + y * 13 + (x * y) % 29) % 256) as u8])
        });
        let png = dir.join("a.png");
        img.save(&png).unwrap();
        let pyr = dir.join("a.pyr");
        let done = crate::imaging::ingest::ingest(&png, &pyr).unwrap();
        let file = TiledPyramid::open(&pyr, &done.pyramid.index_hash).unwrap();
        (png, file)
    }

    #[test]
    fn windows_equal_the_ingested_pyramid_and_only_their_tiles_are_kept() {
        let dir = tempfile::tempdir().unwrap();
        let (png, file) = image_and_pyramid(dir.path());
        let boxes = [[10.0, 20.0, 90.5, 61.0], [300.0, 260.0, 599.0, 419.0]];
        let p = PartialPyramid::decode(&png, |_| {
            vec![
                Region::window(0, boxes[0]),
                Region::window(1, boxes[1]),
                Region::whole(3),
            ]
        })
        .unwrap();
        for (level, b) in [(0, boxes[0]), (1, boxes[1])] {
            let a = ScaledWindow::read(&p, level, b).unwrap().unwrap();
            let e = ScaledWindow::read(&file, level, b).unwrap().unwrap();
            assert_eq!(a, e, "level {level}");
        }
        let (lw, lh) = file.layout().level_sizes[3];
        let rect = PixelRect::new(0, 0, lw, lh);
        assert_eq!(
            read_window(&p, 3, rect).unwrap(),
            read_window(&file, 3, rect).unwrap()
        );
        // Level 0: the one tile under the first box; level 1 (300 × 210, two tiles across): both, the box
        // straddles them; level 3: its only tile.
        assert_eq!(p.kept_bytes(), (1 + 2 + 1) * p.layout().tile_bytes());
        let e = read_window(&p, 0, PixelRect::new(500, 400, 10, 10)).unwrap_err();
        assert!(e.to_string().contains("not kept"), "{e}");
    }
}

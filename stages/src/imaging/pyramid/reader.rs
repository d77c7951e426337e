//! Reading a pyramid file: the index is verified once against the hash its builder returned, every tile
//! against its entry of the index when it is read. Tiles are read with positional reads (no memory map, so
//! the pages read do not count towards the process' resident memory), windows are assembled from them.

use super::layout::{PixelRect, PyramidLayout, SampleDepth, HEADER_LEN, TILE_HASH_LEN};
use super::sample::Sample;
use crate::imaging::GrayImage;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A pyramid file that cannot be used; the message names the file and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct PyramidError {
    pub path: String,
    pub message: String,
}

impl PyramidError {
    pub fn new(path: &Path, message: impl Into<String>) -> Self {
        Self {
            path: path.display().to_string(),
            message: message.into(),
        }
    }

    /// Tile `id` of the pyramid at `path` is not there (`why`: "does not exist", "was not kept …").
    pub fn missing_tile(path: &Path, (level, tx, ty): TileId, why: &str) -> Self {
        Self::new(path, format!("internal: tile ({level}, {tx}, {ty}) {why}"))
    }
}

/// Identity of one tile: (level, tx, ty).
pub type TileId = (usize, usize, usize);

/// Something that hands out the verified bytes of a pyramid's tiles (the file itself, or a cache in front of
/// it), from which windows are assembled.
pub trait TileSource: Send + Sync {
    /// Layout and white value of the pyramid.
    fn header(&self) -> &PyramidHeader;
    /// Layout of the pyramid.
    fn layout(&self) -> &PyramidLayout {
        &self.header().layout
    }
    /// The sample value that maps to grey 1.0.
    fn white(&self) -> u16 {
        self.header().white
    }
    /// The verified bytes of a tile (`layout().tile_bytes()` of them).
    fn tile(&self, id: TileId) -> Result<Arc<[u8]>, PyramidError>;
}

/// What a pyramid's header says of it: its layout and the sample value that maps to grey 1.0.
#[derive(Clone, Debug, PartialEq)]
pub struct PyramidHeader {
    pub layout: PyramidLayout,
    pub white: u16,
}

/// An opened pyramid file with its verified index.
pub struct TiledPyramid {
    path: PathBuf,
    file: File,
    header: PyramidHeader,
    hashes: Vec<u8>,
}

impl TiledPyramid {
    /// Opens `path` and checks that its header and tile hash table hash to `index_hash` (from
    /// [`super::PyramidSummary::index_hash`]); a file that differs is an error, never read.
    pub fn open(path: &Path, index_hash: &[u8; 32]) -> Result<Self, PyramidError> {
        let err = |m: String| PyramidError::new(path, m);
        let file = File::open(path).map_err(|e| err(format!("cannot open ({e})")))?;
        let mut header = [0u8; HEADER_LEN];
        file.read_exact_at(&mut header, 0)
            .map_err(|e| err(format!("cannot read the header ({e})")))?;
        let (layout, white) = PyramidLayout::decode_header(&header).map_err(err)?;
        let len = file
            .metadata()
            .map_err(|e| err(format!("cannot stat ({e})")))?
            .len();
        if len != layout.file_len() {
            return Err(err(format!(
                "is {len} bytes, its header implies {}: truncated or overwritten",
                layout.file_len()
            )));
        }
        let mut hashes = vec![0u8; layout.hash_table_len()];
        file.read_exact_at(&mut hashes, layout.hash_table_offset())
            .map_err(|e| err(format!("cannot read the tile index ({e})")))?;
        let mut h = blake3::Hasher::new();
        h.update(&header);
        h.update(&hashes);
        if h.finalize().as_bytes() != index_hash {
            return Err(err(
                "its index does not match the hash recorded when it was built (changed on disk)"
                    .into(),
            ));
        }
        Ok(Self {
            path: path.to_path_buf(),
            file,
            header: PyramidHeader { layout, white },
            hashes,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl TileSource for TiledPyramid {
    fn header(&self) -> &PyramidHeader {
        &self.header
    }

    fn tile(&self, id: TileId) -> Result<Arc<[u8]>, PyramidError> {
        let l = &self.header.layout;
        let index = l
            .existing_tile_index(id)
            .ok_or_else(|| PyramidError::missing_tile(&self.path, id, "does not exist"))?;
        let mut bytes = vec![0u8; l.tile_bytes()];
        self.file
            .read_exact_at(&mut bytes, l.tile_offset(index))
            .map_err(|e| {
                PyramidError::new(&self.path, format!("cannot read tile {index} ({e})"))
            })?;
        let expected = &self.hashes[index * TILE_HASH_LEN..(index + 1) * TILE_HASH_LEN];
        if blake3::hash(&bytes).as_bytes()[..TILE_HASH_LEN] != *expected {
            return Err(PyramidError::new(
                &self.path,
                format!(
                    "tile {index} (level {}) is damaged: its hash does not match the index",
                    id.0
                ),
            ));
        }
        Ok(bytes.into())
    }
}

/// Grey values (sample / white, so 0..1) of `rect` at `level` of `source`. Pixels of the rectangle outside
/// the level repeat the nearest edge pixel.
pub fn read_window(
    source: &dyn TileSource,
    level: usize,
    rect: PixelRect,
) -> Result<GrayImage, PyramidError> {
    let layout = source.layout();
    let level = level.min(layout.levels() - 1);
    let (lw, lh) = layout.level_sizes[level];
    let clamp = |v: i64, n: usize| v.clamp(0, n as i64 - 1) as usize;
    let cols: Vec<usize> = (0..rect.width)
        .map(|c| clamp(rect.x0 + c as i64, lw))
        .collect();
    let rows: Vec<usize> = (0..rect.height)
        .map(|r| clamp(rect.y0 + r as i64, lh))
        .collect();
    let mut out = GrayImage::filled(rect.width, rect.height, 0.0);
    if rect.width == 0 || rect.height == 0 {
        return Ok(out);
    }
    let white = f32::from(source.white());
    match layout.depth {
        SampleDepth::U8 => {
            let lut: Vec<f32> = (0..=255u16).map(|v| f32::from(v) / white).collect();
            fill::<u8>(source, level, &cols, &rows, &mut out, |s| lut[s as usize])
        }
        SampleDepth::U16 => fill::<u16>(source, level, &cols, &rows, &mut out, |s| {
            f32::from(s) / white
        }),
    }?;
    Ok(out)
}

/// Copies the samples at (`cols` × `rows`) of `level` into `out`, tile by tile (the column and row lists are
/// non-decreasing, so each tile covers one contiguous block of the output).
fn fill<S: Sample>(
    source: &dyn TileSource,
    level: usize,
    cols: &[usize],
    rows: &[usize],
    out: &mut GrayImage,
    to_grey: impl Fn(S) -> f32,
) -> Result<(), PyramidError> {
    let ts = source.layout().tile_side;
    let runs = |v: &[usize]| -> Vec<(usize, usize, usize)> {
        // (tile index, first output position, end output position)
        let mut runs: Vec<(usize, usize, usize)> = Vec::new();
        for (i, &p) in v.iter().enumerate() {
            let t = p / ts;
            match runs.last_mut() {
                Some(r) if r.0 == t => r.2 = i + 1,
                _ => runs.push((t, i, i + 1)),
            }
        }
        runs
    };
    let (col_runs, row_runs) = (runs(cols), runs(rows));
    let width = out.width;
    for &(ty, r0, r1) in &row_runs {
        for &(tx, c0, c1) in &col_runs {
            let tile = source.tile((level, tx, ty))?;
            for r in r0..r1 {
                let in_row = (rows[r] - ty * ts) * ts;
                let dst = &mut out.data[r * width + c0..r * width + c1];
                for (d, &c) in dst.iter_mut().zip(&cols[c0..c1]) {
                    *d = to_grey(S::read_le(&tile, in_row + c - tx * ts));
                }
            }
        }
    }
    Ok(())
}

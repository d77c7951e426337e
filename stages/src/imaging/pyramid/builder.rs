//! Streaming construction of a pyramid file: rows of the full-resolution grey image come in top to bottom,
//! tiles of every level go out as soon as a band of `tile_side` rows of that level is complete. Memory is one
//! band per level (≈ 2 × `tile_side` rows of the full width), whatever the image's height.
//!
//! The file is written under a temporary name next to the destination and renamed into place by
//! [`PyramidBuilder::finish`] (atomic, not fsynced: see there); a builder dropped before that removes its
//! temporary file.

use super::layout::{PyramidLayout, SampleDepth, HEADER_LEN, TILE_HASH_LEN};
use super::sample::{reduce_rows, Sample};
use rayon::prelude::*;
use std::fs::{self, File, OpenOptions};
use std::io;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

/// What a finished pyramid file holds: its layout, white level and the hash that authenticates it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PyramidSummary {
    pub layout: PyramidLayout,
    /// The sample value that maps to grey 1.0 (255 for 8-bit images; for 16-bit images the smallest
    /// `2^k − 1`, k = 8…16, not below the image's largest sample).
    pub white: u16,
    /// blake3 of the header and the tile hash table: with it, [`super::TiledPyramid::open`] verifies the index
    /// and through it every tile.
    pub index_hash: [u8; 32],
    pub file_len: u64,
}

/// One level's band of rows on its way into tiles, and its row awaiting a partner for the next level.
struct Level<S> {
    width: usize,
    height: usize,
    /// Row stride of the band: the width rounded up to whole tiles.
    stride: usize,
    band: Vec<S>,
    band_rows: usize,
    next_band: usize,
    rows_received: usize,
    pending: Vec<S>,
    has_pending: bool,
    reduced: Vec<S>,
    /// Every 2 × 2 block of this level seen so far holds one value: the level repeats the next one's pixels
    /// (false for an odd width or height).
    repeats_next: bool,
}

impl<S: Sample> Level<S> {
    fn new(width: usize, height: usize, tile_side: usize) -> Self {
        let stride = width.div_ceil(tile_side) * tile_side;
        Self {
            width,
            height,
            stride,
            band: vec![S::default(); stride * tile_side],
            band_rows: 0,
            next_band: 0,
            rows_received: 0,
            pending: Vec::with_capacity(width),
            has_pending: false,
            reduced: Vec::with_capacity(width.div_ceil(2)),
            repeats_next: width.is_multiple_of(2) && height.is_multiple_of(2),
        }
    }

    /// Copy `row` into the band, repeating its last sample up to the tile boundary.
    fn append(&mut self, row: &[S]) {
        let start = self.band_rows * self.stride;
        let dst = &mut self.band[start..start + self.stride];
        dst[..self.width].copy_from_slice(row);
        let last = row[self.width - 1];
        dst[self.width..].fill(last);
        self.band_rows += 1;
        self.rows_received += 1;
    }
}

/// Where finished tiles go: the pyramid file, or memory ([`super::MemoryPyramid`]).
pub(crate) trait TileSink: Sync {
    fn put_tile(&self, layout: &PyramidLayout, index: usize, bytes: Vec<u8>) -> io::Result<()>;
}

impl TileSink for File {
    fn put_tile(&self, layout: &PyramidLayout, index: usize, bytes: Vec<u8>) -> io::Result<()> {
        self.write_all_at(&bytes, layout.tile_offset(index))
    }
}

/// Turns rows of samples `S` (u8 or u16) into the tiles of every level, hashed, in `sink`.
pub(crate) struct Chain<S, K> {
    layout: PyramidLayout,
    sink: K,
    levels: Vec<Level<S>>,
    hashes: Vec<[u8; 32]>,
    max_sample: u16,
}

impl<S: Sample, K: TileSink> Chain<S, K> {
    pub(crate) fn new(layout: PyramidLayout, sink: K) -> Self {
        let levels = layout
            .level_sizes
            .iter()
            .map(|&(w, h)| Level::new(w, h, layout.tile_side))
            .collect();
        let hashes = vec![[0u8; 32]; layout.tile_count()];
        Self {
            layout,
            sink,
            levels,
            hashes,
            max_sample: 0,
        }
    }

    pub(crate) fn push_row(&mut self, row: &[S]) -> io::Result<()> {
        if row.len() != self.layout.width {
            return Err(io::Error::other(format!(
                "internal: a row of {} samples for an image {} wide",
                row.len(),
                self.layout.width
            )));
        }
        if self.levels[0].rows_received >= self.layout.height {
            return Err(io::Error::other(format!(
                "more than the {} rows the header announced",
                self.layout.height
            )));
        }
        // The white level of 8-bit samples is 255 whatever they hold: only 16-bit rows need their maximum.
        if S::BYTES > 1 {
            let row_max = row.iter().map(|s| s.as_u16()).max().unwrap_or(0);
            self.max_sample = self.max_sample.max(row_max);
        }
        self.push_at(0, row)
    }

    fn push_at(&mut self, level: usize, row: &[S]) -> io::Result<()> {
        self.levels[level].append(row);
        if self.levels[level].band_rows == self.layout.tile_side {
            self.flush_band(level)?;
        }
        if level + 1 == self.levels.len() {
            return Ok(());
        }
        let lv = &mut self.levels[level];
        if !lv.has_pending {
            lv.pending.clear();
            lv.pending.extend_from_slice(row);
            lv.has_pending = true;
            return Ok(());
        }
        lv.has_pending = false;
        lv.repeats_next = lv.repeats_next && blocks_repeat(&lv.pending, row);
        let mut reduced = std::mem::take(&mut lv.reduced);
        reduce_rows(&lv.pending, row, &mut reduced);
        let result = self.push_at(level + 1, &reduced);
        self.levels[level].reduced = reduced;
        result
    }

    /// Writes the band of `level` as one row of tiles (a partial band repeats its last row) and hashes them.
    fn flush_band(&mut self, level: usize) -> io::Result<()> {
        let ts = self.layout.tile_side;
        let layout = &self.layout;
        let sink = &self.sink;
        let lv = &mut self.levels[level];
        if lv.band_rows == 0 {
            return Ok(());
        }
        let stride = lv.stride;
        for r in lv.band_rows..ts {
            let (done, rest) = lv.band.split_at_mut(r * stride);
            rest[..stride]
                .copy_from_slice(&done[(lv.band_rows - 1) * stride..lv.band_rows * stride]);
        }
        let ty = lv.next_band;
        let (across, _) = layout.tiles(level);
        let band = &lv.band;
        let written: Vec<io::Result<(usize, [u8; 32])>> = (0..across)
            .into_par_iter()
            .map(|tx| {
                let mut bytes = Vec::with_capacity(layout.tile_bytes());
                for r in 0..ts {
                    S::extend_le(
                        &band[r * stride + tx * ts..r * stride + (tx + 1) * ts],
                        &mut bytes,
                    );
                }
                let index = layout.tile_index(level, tx, ty);
                let hash = *blake3::hash(&bytes).as_bytes();
                sink.put_tile(layout, index, bytes)?;
                Ok((index, hash))
            })
            .collect();
        for w in written {
            let (index, hash) = w?;
            self.hashes[index] = hash;
        }
        lv.band_rows = 0;
        lv.next_band += 1;
        Ok(())
    }

    /// Completes every level (an odd last row pairs with itself); returns the layout, the white level, the
    /// header and the tile hash table, and the sink.
    pub(crate) fn finish(mut self) -> io::Result<Finished<K>> {
        if self.levels[0].rows_received != self.layout.height {
            return Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                format!(
                    "the image data ended after {} of {} rows",
                    self.levels[0].rows_received, self.layout.height
                ),
            ));
        }
        for level in 0..self.levels.len() {
            if level + 1 < self.levels.len() && self.levels[level].has_pending {
                let lv = &mut self.levels[level];
                lv.has_pending = false;
                let pending = std::mem::take(&mut lv.pending);
                let mut reduced = std::mem::take(&mut lv.reduced);
                reduce_rows(&pending, &pending, &mut reduced);
                self.push_at(level + 1, &reduced)?;
            }
            self.flush_band(level)?;
            let lv = &self.levels[level];
            if lv.rows_received != lv.height {
                return Err(io::Error::other(format!(
                    "internal: level {level} got {} of {} rows ({} wide)",
                    lv.rows_received, lv.height, lv.width
                )));
            }
        }
        let white = match self.layout.depth {
            SampleDepth::U8 => 255,
            SampleDepth::U16 => white_for(self.max_sample),
        };
        // The detail level: how many levels from the finest on repeat the next one's pixels.
        let levels = self.levels.len();
        self.layout.detail_level = self.levels[..levels - 1]
            .iter()
            .take_while(|lv| lv.repeats_next)
            .count();
        let header = self.layout.encode_header(white);
        let mut table = Vec::with_capacity(self.layout.hash_table_len());
        for h in &self.hashes {
            table.extend_from_slice(&h[..TILE_HASH_LEN]);
        }
        let mut index = blake3::Hasher::new();
        index.update(&header[..HEADER_LEN]);
        index.update(&table);
        Ok(Finished {
            layout: self.layout,
            white,
            header,
            table,
            index_hash: *index.finalize().as_bytes(),
            sink: self.sink,
        })
    }
}

/// Whether rows `a` and `b` (a pair of rows of one level, even length) hold one value per 2 × 2 block.
fn blocks_repeat<S: Sample>(a: &[S], b: &[S]) -> bool {
    a.len() == b.len()
        && a.chunks_exact(2)
            .zip(b.chunks_exact(2))
            .all(|(x, y)| x[0] == x[1] && y[0] == y[1] && x[0] == y[0])
}

/// A completed chain: what the file's header and hash table hold, and the sink the tiles went to.
pub(crate) struct Finished<K> {
    pub layout: PyramidLayout,
    pub white: u16,
    pub header: [u8; HEADER_LEN],
    pub table: Vec<u8>,
    pub index_hash: [u8; 32],
    pub sink: K,
}

/// The smallest `2^k − 1` (k = 8…16) not below `max`: 16-bit frames that use only 10, 12 or 14 bits map to
/// the full grey range instead of a dark corner of it.
pub fn white_for(max: u16) -> u16 {
    (8..=16)
        .map(|k| ((1u32 << k) - 1) as u16)
        .find(|&w| w >= max)
        .unwrap_or(u16::MAX)
}

enum AnyChain<K> {
    U8(Chain<u8, K>),
    U16(Chain<u16, K>),
}

/// A [`Chain`] at its layout's sample depth, taking rows of either depth.
pub(crate) struct DepthChain<K> {
    chain: AnyChain<K>,
    /// u16 rows converted to u8 (or back) when the source's depth differs from the stored one.
    scratch8: Vec<u8>,
    scratch16: Vec<u16>,
}

impl<K: TileSink> DepthChain<K> {
    /// The chain of `layout`'s tiles into `sink`.
    pub(crate) fn new(layout: PyramidLayout, sink: K) -> Self {
        let chain = match layout.depth {
            SampleDepth::U8 => AnyChain::U8(Chain::new(layout, sink)),
            SampleDepth::U16 => AnyChain::U16(Chain::new(layout, sink)),
        };
        Self {
            chain,
            scratch8: Vec::new(),
            scratch16: Vec::new(),
        }
    }

    /// Appends one full-width row of samples of either depth.
    pub(crate) fn push_row<T: Sample>(&mut self, row: &[T]) -> io::Result<()> {
        match &mut self.chain {
            AnyChain::U8(c) => c.push_row(T::row_as_u8(row, &mut self.scratch8)),
            AnyChain::U16(c) => c.push_row(T::row_as_u16(row, &mut self.scratch16)),
        }
    }

    /// [`Chain::finish`].
    pub(crate) fn finish(self) -> io::Result<Finished<K>> {
        match self.chain {
            AnyChain::U8(c) => c.finish(),
            AnyChain::U16(c) => c.finish(),
        }
    }
}

/// Builds one pyramid file from rows pushed top to bottom; see the module documentation.
pub struct PyramidBuilder {
    chain: Option<DepthChain<File>>,
    tmp: PathBuf,
    dest: PathBuf,
}

impl PyramidBuilder {
    /// Starts `dest` for a `width × height` image stored at `depth` with `tile_side`-pixel tiles.
    pub fn create(
        dest: &Path,
        width: usize,
        height: usize,
        depth: SampleDepth,
        tile_side: usize,
    ) -> io::Result<Self> {
        let layout = PyramidLayout::new(width, height, depth, tile_side).ok_or_else(|| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "no pyramid layout for a {width} × {height} image with {tile_side}-px tiles"
                ),
            )
        })?;
        let name = dest
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "pyramid".into());
        let tmp = dest.with_file_name(format!(".{name}.{}.partial", std::process::id()));
        if let Some(dir) = dest.parent().filter(|d| !d.as_os_str().is_empty()) {
            fs::create_dir_all(dir)?;
        }
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&tmp)?;
        file.set_len(layout.file_len())?;
        Ok(Self {
            chain: Some(DepthChain::new(layout, file)),
            tmp,
            dest: dest.to_path_buf(),
        })
    }

    /// Appends one full-width row of 8-bit samples.
    pub fn push_row_u8(&mut self, row: &[u8]) -> io::Result<()> {
        self.chain.as_mut().expect("not finished").push_row(row)
    }

    /// Appends one full-width row of 16-bit samples.
    pub fn push_row_u16(&mut self, row: &[u16]) -> io::Result<()> {
        self.chain.as_mut().expect("not finished").push_row(row)
    }

    /// Completes the file (all rows must have been pushed) and renames it into place.
    ///
    /// The file is not fsynced: the rename is atomic, so readers and an interrupted process see either no
    /// pyramid or the whole one, and what reaches the disk is left to the caller (a run flushes its cache's
    /// file system once at its end, with `syncfs`). After a crash of the machine before that
    /// flush, a pyramid may be in place with some of its pages never written; its index and every tile are
    /// checked against their hashes when read ([`super::TiledPyramid::open`]), so such a file is refused,
    /// never read as an image.
    pub fn finish(mut self) -> io::Result<PyramidSummary> {
        let done = self.chain.take().expect("not finished").finish()?;
        let file = done.sink;
        file.write_all_at(&done.table, done.layout.hash_table_offset())?;
        file.write_all_at(&done.header, 0)?;
        drop(file);
        fs::rename(&self.tmp, &self.dest)?;
        let file_len = done.layout.file_len();
        Ok(PyramidSummary {
            layout: done.layout,
            white: done.white,
            index_hash: done.index_hash,
            file_len,
        })
    }
}

impl Drop for PyramidBuilder {
    fn drop(&mut self) {
        // After a successful finish the temporary name no longer exists; after a failure it goes.
        let _ = fs::remove_file(&self.tmp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_is_the_smallest_all_ones_value_holding_the_maximum() {
        let cases = [
            (0, 255),
            (255, 255),
            (256, 511),
            (4095, 4095),
            (4096, 8191),
            (65535, 65535),
        ];
        for (max, white) in cases {
            assert_eq!(white_for(max), white, "white for the maximum {max}");
        }
    }

    #[test]
    fn a_short_image_is_an_error_and_leaves_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("p.pyr");
        let mut b = PyramidBuilder::create(&dest, 10, 3, SampleDepth::U8, 16).unwrap();
        b.push_row_u8(&[1; 10]).unwrap();
        let e = b.finish().unwrap_err();
        assert!(e.to_string().contains("after 1 of 3 rows"), "{e}");
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
        let mut b = PyramidBuilder::create(&dest, 10, 1, SampleDepth::U8, 16).unwrap();
        b.push_row_u8(&[1; 10]).unwrap();
        assert!(b.push_row_u8(&[1; 10]).is_err());
        assert!(b.push_row_u8(&[1; 9]).is_err());
    }

    /// The pyramid file of `w × h` samples `at(col, row)`, reopened: its layout as read back.
    fn built(w: usize, h: usize, at: impl Fn(usize, usize) -> u8) -> PyramidLayout {
        use super::super::TileSource;
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("p.pyr");
        let mut b = PyramidBuilder::create(&dest, w, h, SampleDepth::U8, 16).unwrap();
        for r in 0..h {
            let row: Vec<u8> = (0..w).map(|c| at(c, r)).collect();
            b.push_row_u8(&row).unwrap();
        }
        let summary = b.finish().unwrap();
        let opened = super::super::TiledPyramid::open(&dest, &summary.index_hash).unwrap();
        assert_eq!(opened.layout(), &summary.layout);
        summary.layout
    }

    #[test]
    fn an_image_enlarged_by_pixel_repetition_has_the_detail_level_of_its_original() {
        let texture = |c: usize, r: usize| ((c * 37 + r * 91 + (c * r) % 13) % 251) as u8;
        assert_eq!(built(40, 24, texture).detail_level, 0);
        // Each pixel repeated 4 × 4 times: levels 0 and 1 only repeat level 2.
        assert_eq!(built(160, 96, |c, r| texture(c / 4, r / 4)).detail_level, 2);
        assert_eq!(built(80, 48, |c, r| texture(c / 2, r / 2)).detail_level, 1);
        // One pixel off the repetition, or an odd size: every level holds detail.
        let spoiled =
            |c: usize, r: usize| texture(c / 4, r / 4).wrapping_add(u8::from((c, r) == (5, 7)));
        assert_eq!(built(160, 96, spoiled).detail_level, 0);
        assert_eq!(built(159, 96, |c, r| texture(c / 4, r / 4)).detail_level, 0);
    }
}

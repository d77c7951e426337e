//! A streaming writer of tiled TIFF and BigTIFF images — the form large-format aerial cameras deliver: rows
//! go in top to bottom, each band of `tile_side` rows leaves as compressed tiles (compressed in parallel,
//! written in order), so memory is one band whatever the image's height. 8- or 16-bit, grey or RGB;
//! compression none, LZW, Deflate or JPEG ([`TiffCompression`]). The file is written under a temporary name
//! and renamed into place when complete.

pub mod compress;
mod ifd;

pub use compress::TiffCompression;

use crate::imaging::decode::GeoTiffTags;
use ifd::Entry;
use rayon::prelude::*;
use std::fs::{self, File};
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// What the TIFF holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TiledTiffSpec {
    pub width: usize,
    pub height: usize,
    /// 1 (grey) or 3 (RGB).
    pub channels: usize,
    /// 1 or 2 bytes per sample.
    pub bytes_per_sample: usize,
    pub tile_side: usize,
    pub compression: TiffCompression,
    /// BigTIFF (8-byte offsets) instead of classic TIFF; needed beyond 4 GiB.
    pub big: bool,
}

impl TiledTiffSpec {
    fn check(&self) -> io::Result<()> {
        let ok = self.width > 0
            && self.height > 0
            && matches!(self.channels, 1 | 3)
            && matches!(self.bytes_per_sample, 1 | 2)
            && self.tile_side.is_multiple_of(16)
            && self.tile_side > 0
            && !(matches!(self.compression, TiffCompression::Jpeg(_))
                && self.bytes_per_sample != 1);
        if ok {
            Ok(())
        } else {
            Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("unsupported tiled TIFF: {self:?}"),
            ))
        }
    }

    fn row_bytes(&self) -> usize {
        self.width * self.channels * self.bytes_per_sample
    }

    fn tiles_across(&self) -> usize {
        self.width.div_ceil(self.tile_side)
    }
}

/// Writes one tiled TIFF; see the module documentation.
pub struct TiledTiffWriter {
    spec: TiledTiffSpec,
    out: BufWriter<File>,
    pos: u64,
    band: Vec<u8>,
    band_rows: usize,
    rows: usize,
    offsets: Vec<u64>,
    counts: Vec<u64>,
    tmp: PathBuf,
    dest: PathBuf,
    done: bool,
    geotiff: Vec<Entry>,
}

impl TiledTiffWriter {
    /// Starts writing `dest`.
    pub fn create(dest: &Path, spec: TiledTiffSpec) -> io::Result<Self> {
        spec.check()?;
        let name = dest
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let tmp = dest.with_file_name(format!(".{name}.{}.partial", std::process::id()));
        if let Some(dir) = dest.parent().filter(|d| !d.as_os_str().is_empty()) {
            fs::create_dir_all(dir)?;
        }
        let mut out = BufWriter::with_capacity(1 << 20, File::create(&tmp)?);
        out.write_all(&ifd::header(0, spec.big))?;
        Ok(Self {
            spec,
            out,
            pos: ifd::header_len(spec.big),
            band: Vec::with_capacity(
                spec.tiles_across()
                    * spec.tile_side
                    * spec.tile_side
                    * spec.channels
                    * spec.bytes_per_sample,
            ),
            band_rows: 0,
            rows: 0,
            offsets: Vec::new(),
            counts: Vec::new(),
            tmp,
            dest: dest.to_path_buf(),
            done: false,
            geotiff: Vec::new(),
        })
    }

    /// Writes these GeoTIFF tags (georeference, CRS, no-data) into the directory.
    pub fn set_geotiff(&mut self, tags: &GeoTiffTags) {
        self.geotiff = geotiff_entries(tags);
    }

    /// Appends one row of 8-bit samples (`width × channels`).
    pub fn push_row_u8(&mut self, row: &[u8]) -> io::Result<()> {
        if self.spec.bytes_per_sample != 1 {
            return Err(io::Error::other("internal: 8-bit row for a 16-bit TIFF"));
        }
        self.push_bytes(row)
    }

    /// Appends one row of 16-bit samples (`width × channels`).
    pub fn push_row_u16(&mut self, row: &[u16]) -> io::Result<()> {
        if self.spec.bytes_per_sample != 2 {
            return Err(io::Error::other("internal: 16-bit row for an 8-bit TIFF"));
        }
        let bytes: Vec<u8> = row.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.push_bytes(&bytes)
    }

    fn push_bytes(&mut self, row: &[u8]) -> io::Result<()> {
        let s = self.spec;
        if row.len() != s.row_bytes() || self.rows >= s.height {
            return Err(io::Error::other(format!(
                "internal: row {} of {} bytes for a {} × {} TIFF",
                self.rows,
                row.len(),
                s.width,
                s.height
            )));
        }
        // Pad the row to whole tiles by repeating its last pixel.
        let px = s.channels * s.bytes_per_sample;
        self.band.extend_from_slice(row);
        let last = row[row.len() - px..].to_vec();
        for _ in s.width..s.tiles_across() * s.tile_side {
            self.band.extend_from_slice(&last);
        }
        self.band_rows += 1;
        self.rows += 1;
        if self.band_rows == s.tile_side {
            self.flush_band()?;
        }
        Ok(())
    }

    /// Compresses and writes the band's tiles (a partial band repeats its last row).
    fn flush_band(&mut self) -> io::Result<()> {
        let s = self.spec;
        if self.band_rows == 0 {
            return Ok(());
        }
        let stride = s.tiles_across() * s.tile_side * s.channels * s.bytes_per_sample;
        while self.band_rows < s.tile_side {
            let last = self.band[self.band.len() - stride..].to_vec();
            self.band.extend_from_slice(&last);
            self.band_rows += 1;
        }
        let tile_row = s.tile_side * s.channels * s.bytes_per_sample;
        let band = &self.band;
        let tiles: Vec<io::Result<Vec<u8>>> = (0..s.tiles_across())
            .into_par_iter()
            .map(|tx| {
                let mut tile = Vec::with_capacity(tile_row * s.tile_side);
                for r in 0..s.tile_side {
                    let start = r * stride + tx * tile_row;
                    tile.extend_from_slice(&band[start..start + tile_row]);
                }
                compress::compress(
                    tile,
                    s.tile_side,
                    s.channels,
                    s.bytes_per_sample,
                    s.compression,
                )
            })
            .collect();
        for t in tiles {
            let t = t?;
            if self.pos % 2 == 1 {
                self.out.write_all(&[0])?;
                self.pos += 1;
            }
            self.offsets.push(self.pos);
            self.counts.push(t.len() as u64);
            self.out.write_all(&t)?;
            self.pos += t.len() as u64;
        }
        self.band.clear();
        self.band_rows = 0;
        Ok(())
    }

    /// Writes the last band and the directory, syncs and renames the file into place.
    pub fn finish(mut self) -> io::Result<()> {
        let s = self.spec;
        if self.rows != s.height {
            return Err(io::Error::other(format!(
                "internal: {} of {} rows written",
                self.rows, s.height
            )));
        }
        self.flush_band()?;
        let too_big = || io::Error::other("the TIFF exceeds 4 GiB: write it as BigTIFF");
        let bits = vec![8 * s.bytes_per_sample as u16; s.channels];
        let photometric = match (s.channels, s.compression) {
            (1, _) => 1,
            (_, TiffCompression::Jpeg(_)) => 6,
            _ => 2,
        };
        let mut entries = vec![
            Entry::longs(256, &[s.width as u32]),
            Entry::longs(257, &[s.height as u32]),
            Entry::shorts(258, &bits),
            Entry::shorts(259, &[s.compression.tag_value()]),
            Entry::shorts(262, &[photometric]),
            Entry::shorts(277, &[s.channels as u16]),
            Entry::shorts(284, &[1]),
            Entry::longs(322, &[s.tile_side as u32]),
            Entry::longs(323, &[s.tile_side as u32]),
            Entry::offsets(324, &self.offsets, s.big).ok_or_else(too_big)?,
            Entry::offsets(325, &self.counts, s.big).ok_or_else(too_big)?,
            Entry::shorts(339, &vec![1; s.channels]),
        ];
        entries.append(&mut self.geotiff);
        if s.compression.predicts() {
            entries.push(Entry::shorts(317, &[2]));
        }
        if photometric == 6 {
            entries.push(Entry::shorts(530, &[1, 1]));
        }
        let at = self.pos + self.pos % 2;
        let (bytes, ifd_offset) = ifd::encode(entries, at, s.big);
        if !s.big && ifd_offset + bytes.len() as u64 > u32::MAX as u64 {
            return Err(too_big());
        }
        if self.pos % 2 == 1 {
            self.out.write_all(&[0])?;
        }
        self.out.write_all(&bytes)?;
        self.out.seek(SeekFrom::Start(0))?;
        self.out.write_all(&ifd::header(ifd_offset, s.big))?;
        self.out.flush()?;
        self.out.get_ref().sync_all()?;
        fs::rename(&self.tmp, &self.dest)?;
        self.done = true;
        Ok(())
    }
}

/// The directory entries of GeoTIFF tags (OGC GeoTIFF 1.1 tag numbers; GDAL's no-data 42113).
pub(crate) fn geotiff_entries(t: &GeoTiffTags) -> Vec<Entry> {
    let mut out = Vec::new();
    let doubles = [
        (33550, &t.model_pixel_scale),
        (33922, &t.model_tiepoints),
        (34264, &t.model_transformation),
        (34736, &t.geo_double_params),
    ];
    for (tag, v) in doubles {
        if let Some(v) = v {
            out.push(Entry::doubles(tag, v));
        }
    }
    if let Some(keys) = &t.geo_key_directory {
        out.push(Entry::shorts(34735, keys));
    }
    if let Some(text) = &t.geo_ascii_params {
        out.push(Entry::ascii(34737, text));
    }
    if let Some(text) = &t.gdal_nodata {
        out.push(Entry::ascii(42113, text));
    }
    out
}

impl Drop for TiledTiffWriter {
    fn drop(&mut self) {
        if !self.done {
            let _ = fs::remove_file(&self.tmp);
        }
    }
}

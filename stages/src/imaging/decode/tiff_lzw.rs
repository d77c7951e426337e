//! LZW-compressed TIFF strips and tiles, decompressed here instead of by the `tiff` crate: its 0.11 releases
//! read a tile narrower than its padded width row by row through `weezl` 0.1 with small output buffers,
//! where the decoder can stop short of the end code ("no lzw end code found", reported upstream to image-tiff
//! as #395) — every LZW-tiled image whose width is not a multiple of the tile width fails there. A whole chunk is decoded in
//! one call into a buffer of its full size, which does not hit that path; a chunk whose end code is missing
//! but whose pixels are complete is accepted, as libtiff does.

use crate::imaging::io_error::ImageIoError;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::Path;

/// How one chunk's decompressed bytes are laid out and predicted.
pub struct ChunkCoding {
    /// Pixels per row of the chunk as stored (the tile width, or the image width for strips).
    pub row_px: usize,
    /// Samples per pixel in this chunk (1 for a plane of a planar image).
    pub samples: usize,
    pub bytes_per_sample: usize,
    /// TIFF predictor 2 (horizontal differencing).
    pub horizontal_predictor: bool,
    pub big_endian: bool,
}

/// Reads `count` bytes at `offset` of `file` and decompresses them into `expected` bytes of samples in
/// native little-endian order, the predictor undone.
pub fn read_lzw_chunk(
    path: &Path,
    file: &File,
    offset: u64,
    count: u64,
    expected: usize,
    coding: &ChunkCoding,
) -> Result<Vec<u8>, ImageIoError> {
    let corrupt =
        |what: String| ImageIoError::new(path, format!("{what}; the file is truncated or corrupt"));
    let count =
        usize::try_from(count).map_err(|_| corrupt("an LZW chunk is larger than memory".into()))?;
    if count > 2 * expected + (1 << 16) {
        return Err(corrupt(format!(
            "an LZW chunk of {count} bytes is larger than its {expected} decoded bytes could need"
        )));
    }
    let mut compressed = vec![0u8; count];
    file.read_exact_at(&mut compressed, offset)
        .map_err(|e| corrupt(format!("cannot read an LZW chunk at byte {offset} ({e})")))?;
    let mut out = vec![0u8; expected];
    let mut decoder = weezl::decode::Decoder::with_tiff_size_switch(weezl::BitOrder::Msb, 8);
    let (mut read, mut written) = (0, 0);
    while written < expected {
        let r = decoder.decode_bytes(&compressed[read..], &mut out[written..]);
        read += r.consumed_in;
        written += r.consumed_out;
        match r.status {
            Ok(weezl::LzwStatus::Ok) if r.consumed_in + r.consumed_out > 0 => {}
            Ok(_) => break,
            Err(e) => return Err(corrupt(format!("an LZW chunk does not decode ({e})"))),
        }
    }
    if written < expected {
        return Err(corrupt(format!(
            "an LZW chunk holds {written} of its {expected} bytes"
        )));
    }
    if coding.big_endian && coding.bytes_per_sample == 2 {
        for pair in out.chunks_exact_mut(2) {
            pair.swap(0, 1);
        }
    }
    if coding.horizontal_predictor {
        undo_horizontal_predictor(&mut out, coding);
    }
    Ok(out)
}

/// Adds each sample to the one `samples` before it along every row (TIFF 6.0 section 14).
fn undo_horizontal_predictor(data: &mut [u8], c: &ChunkCoding) {
    let row_samples = c.row_px * c.samples;
    if c.bytes_per_sample == 1 {
        for row in data.chunks_exact_mut(row_samples) {
            for i in c.samples..row.len() {
                row[i] = row[i].wrapping_add(row[i - c.samples]);
            }
        }
    } else {
        for row in data.chunks_exact_mut(row_samples * 2) {
            for i in c.samples..row_samples {
                let prev =
                    u16::from_le_bytes([row[2 * (i - c.samples)], row[2 * (i - c.samples) + 1]]);
                let cur = u16::from_le_bytes([row[2 * i], row[2 * i + 1]]);
                row[2 * i..2 * i + 2].copy_from_slice(&cur.wrapping_add(prev).to_le_bytes());
            }
        }
    }
}

//! JPEG-compressed TIFF strips and tiles (TIFF Technote 2), decoded here instead of by the `tiff` crate: the
//! crate decodes every component of a chunk (Y, Cb and Cr, chroma upsampled and interleaved) and copies it
//! twice on its way out, where a grey image needs the Y plane only. A chunk whose JPEG stream is YCbCr or
//! grey is decoded to its luma plane alone (zune-jpeg's `Luma` output: the Y samples as decoded, the same
//! values as the first sample of each pixel of a full decode); any other colour model is decoded in full,
//! as the crate does, and its first sample per pixel taken.

use super::limits::MAX_SIDE_PX;
use crate::imaging::io_error::ImageIoError;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::Path;
use zune_jpeg::zune_core::bytestream::ZCursor;
use zune_jpeg::zune_core::colorspace::ColorSpace;
use zune_jpeg::zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;

/// One decoded chunk: its grey samples, `width` per row, `height` rows.
pub struct GreyChunk {
    pub samples: Vec<u8>,
    pub width: usize,
    pub height: usize,
}

/// The JPEG stream of a chunk: the shared `JPEGTables` (when the file has them) followed by the chunk's own
/// bytes, the tables' end-of-image and the chunk's start-of-image marker left out (Technote 2).
fn stream(tables: Option<&[u8]>, chunk: Vec<u8>) -> Vec<u8> {
    match tables {
        Some(t) if t.len() >= 4 && chunk.starts_with(&[0xFF, 0xD8]) => {
            let mut s = Vec::with_capacity(t.len() + chunk.len());
            s.extend_from_slice(&t[..t.len() - 2]);
            s.extend_from_slice(&chunk[2..]);
            s
        }
        _ => chunk,
    }
}

/// Reads the chunk of `count` bytes at `offset` of `file` and decodes it to grey (see the module
/// documentation). `max_bytes` bounds the compressed size a chunk of its dimensions may have.
pub fn read_jpeg_chunk(
    path: &Path,
    file: &File,
    (offset, count): (u64, u64),
    max_bytes: usize,
    tables: Option<&[u8]>,
) -> Result<GreyChunk, ImageIoError> {
    let corrupt =
        |what: String| ImageIoError::new(path, format!("{what}; the file is truncated or corrupt"));
    let count = usize::try_from(count)
        .ok()
        .filter(|&c| c <= max_bytes)
        .ok_or_else(|| {
            corrupt(format!(
                "a JPEG chunk of {count} bytes is larger than its pixels could need"
            ))
        })?;
    let mut chunk = vec![0u8; count];
    file.read_exact_at(&mut chunk, offset)
        .map_err(|e| corrupt(format!("cannot read a JPEG chunk at byte {offset} ({e})")))?;
    let data = stream(tables, chunk);
    let options = DecoderOptions::default()
        .set_max_width(MAX_SIDE_PX)
        .set_max_height(MAX_SIDE_PX);
    let mut decoder = JpegDecoder::new_with_options(ZCursor::new(&data[..]), options);
    let bad = |e: zune_jpeg::errors::DecodeErrors| {
        corrupt(format!(
            "a JPEG chunk at byte {offset} does not decode ({e:?})"
        ))
    };
    decoder.decode_headers().map_err(bad)?;
    let input = decoder.input_colorspace().unwrap_or(ColorSpace::Unknown);
    let luma = matches!(input, ColorSpace::YCbCr | ColorSpace::Luma);
    let out = if luma { ColorSpace::Luma } else { input };
    decoder.set_options(options.jpeg_set_out_colorspace(out));
    let (width, height) = decoder
        .dimensions()
        .ok_or_else(|| corrupt(format!("a JPEG chunk at byte {offset} has no frame header")))?;
    let decoded = decoder.decode().map_err(bad)?;
    let n = out.num_components().max(1);
    let samples = if n == 1 {
        decoded
    } else {
        decoded.chunks_exact(n).map(|p| p[0]).collect()
    };
    if samples.len() < width * height {
        return Err(corrupt(format!(
            "a JPEG chunk at byte {offset} holds {} of its {} pixels",
            samples.len(),
            width * height
        )));
    }
    Ok(GreyChunk {
        samples,
        width,
        height,
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn shared_tables_are_prepended_without_the_duplicate_markers() {
        let tables = [0xFF, 0xD8, 0xFF, 0xDB, 1, 2, 0xFF, 0xD9];
        let chunk = vec![0xFF, 0xD8, 0xFF, 0xC0, 9, 0xFF, 0xD9];
        assert_eq!(
            super::stream(Some(&tables), chunk.clone()),
            vec![0xFF, 0xD8, 0xFF, 0xDB, 1, 2, 0xFF, 0xC0, 9, 0xFF, 0xD9]
        );
        assert_eq!(super::stream(None, chunk.clone()), chunk);
    }
}

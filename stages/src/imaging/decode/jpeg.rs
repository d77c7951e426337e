//! JPEG files through `zune-jpeg`, decoding only the luma plane (no chroma upsampling, no colour
//! conversion): one byte per pixel in memory, the least a JPEG decoder can hold. Strict mode: a file that
//! ends before its end-of-image marker, or whose entropy-coded data is corrupt, is an error, not a grey
//! image with a missing bottom.

use super::limits::{reserve, MAX_SIDE_PX};
use super::{sink_error, GreyInfo, GreyRowSink, ImageFormat, ImageHeader};
use crate::imaging::io_error::ImageIoError;
use crate::imaging::pyramid::SampleDepth;
use std::path::Path;
use zune_jpeg::zune_core::bytestream::ZCursor;
use zune_jpeg::zune_core::colorspace::ColorSpace;
use zune_jpeg::zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;

/// Bytes per pixel the decoder holds beyond the output for a progressive JPEG: its coefficients (2 bytes
/// each) of up to three full-resolution components.
const PROGRESSIVE_EXTRA_BYTES_PER_PX: usize = 6;

fn options() -> DecoderOptions {
    DecoderOptions::default()
        .set_max_width(MAX_SIDE_PX)
        .set_max_height(MAX_SIDE_PX)
        .jpeg_set_out_colorspace(ColorSpace::Luma)
        .set_strict_mode(true)
}

/// Size and coding of the JPEG `path`, from its header only.
fn header(path: &Path) -> Result<(usize, usize, bool), ImageIoError> {
    let file = std::fs::File::open(path)
        .map_err(|e| ImageIoError::new(path, format!("cannot open ({e})")))?;
    let mut decoder = JpegDecoder::new_with_options(std::io::BufReader::new(file), options());
    decoder.decode_headers().map_err(|e| {
        ImageIoError::new(
            path,
            format!("has no readable JPEG header ({e:?}); is it truncated or corrupt?"),
        )
    })?;
    let info = decoder
        .info()
        .ok_or_else(|| ImageIoError::new(path, "has no readable JPEG header"))?;
    Ok((
        usize::from(info.width),
        usize::from(info.height),
        !info.sof.is_sequential_dct(),
    ))
}

/// Decodes the JPEG `path` (probed as `probed`) into `sink` as 8-bit grey (its Y plane).
pub fn decode(
    path: &Path,
    probed: &ImageHeader,
    sink: &mut dyn GreyRowSink,
) -> Result<GreyInfo, ImageIoError> {
    let file_len = probed.file_bytes;
    let (width, height, progressive) = header(path)?;
    let plane = width * height;
    let extra = if progressive {
        plane * PROGRESSIVE_EXTRA_BYTES_PER_PX
    } else {
        0
    };
    // The compressed bytes, the grey plane and (progressive) the coefficients are held at once.
    let reservation = reserve(
        path,
        "JPEG",
        width,
        height,
        file_len as usize + plane + extra,
        "its compressed data, grey plane and decoder buffers",
    )?;
    let data =
        std::fs::read(path).map_err(|e| ImageIoError::new(path, format!("cannot read ({e})")))?;
    let mut decoder = JpegDecoder::new_with_options(ZCursor::new(&data[..]), options());
    decoder
        .decode_headers()
        .map_err(|e| ImageIoError::new(path, format!("has no readable JPEG header ({e:?})")))?;
    if decoder.output_buffer_size() != Some(plane) {
        return Err(ImageIoError::new(
            path,
            format!(
                "its colour model ({:?}) cannot be decoded to grey; save it as RGB or greyscale JPEG",
                decoder.input_colorspace()
            ),
        ));
    }
    let mut grey = vec![0u8; plane];
    decoder.decode_into(&mut grey).map_err(|e| {
        ImageIoError::new(
            path,
            format!("does not decode as a JPEG ({e:?}); is it truncated or corrupt?"),
        )
    })?;
    drop(decoder);
    drop(data);
    let info = GreyInfo {
        width,
        height,
        depth: SampleDepth::U8,
        format: ImageFormat::Jpeg,
        geotiff: None,
    };
    sink.begin(&info).map_err(|e| sink_error(path, e))?;
    for row in grey.chunks_exact(width) {
        sink.row_u8(row).map_err(|e| sink_error(path, e))?;
    }
    drop(reservation);
    Ok(info)
}

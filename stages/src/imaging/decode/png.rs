//! PNG files through the `png` crate: non-interlaced images row by row (one row in memory), interlaced
//! (Adam7) images whole. Palettes and grey below 8 bits are expanded to 8 bits; 16-bit images stay 16-bit.

use super::grey::{grey_row16, grey_row8, Channels};
use super::limits::reserve;
use super::{sink_error, GreyInfo, GreyRowSink, ImageFormat};
use crate::imaging::io_error::ImageIoError;
use crate::imaging::pyramid::SampleDepth;
use png::{BitDepth, ColorType, Transformations};
use std::io::BufReader;
use std::path::Path;

fn channels(colour: ColorType) -> Channels {
    match colour {
        ColorType::Grayscale => Channels::Grey { extra: 0 },
        ColorType::GrayscaleAlpha => Channels::Grey { extra: 1 },
        ColorType::Rgb | ColorType::Indexed => Channels::Rgb { extra: 0 },
        ColorType::Rgba => Channels::Rgb { extra: 1 },
    }
}

/// Emits one decoded row (PNG's 16-bit samples are big-endian) as grey.
struct RowConverter {
    channels: Channels,
    sixteen: bool,
    wide: Vec<u16>,
    grey8: Vec<u8>,
    grey16: Vec<u16>,
}

impl RowConverter {
    fn emit(&mut self, data: &[u8], sink: &mut dyn GreyRowSink) -> std::io::Result<()> {
        if self.sixteen {
            self.wide.clear();
            self.wide.extend(
                data.chunks_exact(2)
                    .map(|b| u16::from_be_bytes([b[0], b[1]])),
            );
            grey_row16(&self.wide, self.channels, &mut self.grey16);
            sink.row_u16(&self.grey16)
        } else {
            grey_row8(data, self.channels, &mut self.grey8);
            sink.row_u8(&self.grey8)
        }
    }
}

fn decoding_error(path: &Path, e: png::DecodingError) -> ImageIoError {
    ImageIoError::new(
        path,
        format!("does not decode as a PNG ({e}); is it truncated or corrupt?"),
    )
}

/// Decodes the PNG `path` (probed before) into `sink` as grey.
pub fn decode(path: &Path, sink: &mut dyn GreyRowSink) -> Result<GreyInfo, ImageIoError> {
    let file = std::fs::File::open(path)
        .map_err(|e| ImageIoError::new(path, format!("cannot open ({e})")))?;
    let mut decoder = png::Decoder::new(BufReader::new(file));
    decoder.set_transformations(Transformations::EXPAND);
    let header = decoder
        .read_header_info()
        .map_err(|e| decoding_error(path, e))?;
    let (width, height) = (header.width as usize, header.height as usize);
    let interlaced = header.interlaced;
    // Row buffers of the decoder: a few rows of at most 8 bytes per pixel.
    let row_bytes = width * 8;
    let whole = if interlaced { height * row_bytes } else { 0 };
    let _reservation = reserve(
        path,
        "PNG",
        width,
        height,
        4 * row_bytes + whole,
        if interlaced {
            "its interlaced (whole-image) decoding"
        } else {
            "its row buffers"
        },
    )?;
    decoder.set_limits(png::Limits {
        bytes: 8 * row_bytes + whole + (1 << 20),
    });
    let mut reader = decoder.read_info().map_err(|e| decoding_error(path, e))?;
    let (colour, depth) = reader.output_color_type();
    let sixteen = depth == BitDepth::Sixteen;
    let info = GreyInfo {
        width,
        height,
        depth: if sixteen {
            SampleDepth::U16
        } else {
            SampleDepth::U8
        },
        format: ImageFormat::Png,
        geotiff: None,
    };
    let mut conv = RowConverter {
        channels: channels(colour),
        sixteen,
        wide: Vec::new(),
        grey8: Vec::new(),
        grey16: Vec::new(),
    };
    sink.begin(&info).map_err(|e| sink_error(path, e))?;
    if interlaced {
        let mut buf = vec![0u8; reader.output_buffer_size().unwrap_or(0)];
        let frame = reader
            .next_frame(&mut buf)
            .map_err(|e| decoding_error(path, e))?;
        for row in buf.chunks_exact(frame.line_size).take(height) {
            conv.emit(row, sink).map_err(|e| sink_error(path, e))?;
        }
    } else {
        let mut rows = 0;
        while let Some(row) = reader.next_row().map_err(|e| decoding_error(path, e))? {
            conv.emit(row.data(), sink)
                .map_err(|e| sink_error(path, e))?;
            rows += 1;
        }
        if rows != height {
            return Err(ImageIoError::new(
                path,
                format!("ends after {rows} of {height} rows; is it truncated?"),
            ));
        }
    }
    Ok(info)
}

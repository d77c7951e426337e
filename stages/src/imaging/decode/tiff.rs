//! TIFF and BigTIFF files through the `tiff` crate, one row of strips or tiles at a time: 8- or 16-bit grey,
//! RGB(A) or YCbCr (JPEG-compressed TIFFs keep their Y plane), chunky or planar, with any compression the
//! crate reads (none, LZW, Deflate, PackBits, JPEG) and predictors. Only the first image of the file is read
//! (overviews of a pyramidal TIFF are not needed: skytie builds its own).

use super::geotiff::GeoTiffTags;
use super::grey::{grey_row16, grey_row8, Channels};
use super::limits::reserve;
use super::tiff_jpeg::read_jpeg_chunk;
use super::tiff_lzw::{read_lzw_chunk, ChunkCoding};
use super::{sink_error, GreyInfo, GreyRowSink, ImageHeader};
use crate::imaging::io_error::ImageIoError;
use crate::imaging::pyramid::SampleDepth;
use std::io::BufReader;
use std::path::Path;
use tiff::decoder::{ChunkType, Decoder, DecodingResult, Limits};
use tiff::tags::{ByteOrder, CompressionMethod, PlanarConfiguration, Predictor, Tag};
use tiff::ColorType;

type TiffDecoder = Decoder<BufReader<std::fs::File>>;

fn tiff_error(path: &Path, e: tiff::TiffError) -> ImageIoError {
    ImageIoError::new(
        path,
        format!("does not decode as a TIFF ({e}); is it truncated or corrupt?"),
    )
}

/// How the first image's pixels are stored.
struct Structure {
    width: usize,
    height: usize,
    channels: Channels,
    depth: SampleDepth,
    planar: bool,
    /// Chunk (strip or tile) size, pixels.
    chunk_w: usize,
    chunk_h: usize,
    /// LZW chunks are decompressed by [`read_lzw_chunk`], JPEG chunks of grey or YCbCr images decoded by
    /// [`read_jpeg_chunk`]: their offsets, byte counts and coding. `None`: the `tiff` crate reads them.
    raw: Option<RawChunks>,
}

/// How chunks read without the `tiff` crate are coded.
enum RawCoding {
    Lzw(ChunkCoding),
    /// JPEG (TIFF compression 7), with the file's shared `JPEGTables`, if any.
    Jpeg(Option<Vec<u8>>),
}

struct RawChunks {
    /// Tiles hold `chunk_h` rows even at the bottom edge; the last strip holds only the rows left.
    tiled: bool,
    offsets: Vec<u64>,
    counts: Vec<u64>,
    coding: RawCoding,
}

impl Structure {
    fn chunks_across(&self) -> usize {
        self.width.div_ceil(self.chunk_w)
    }

    fn chunks_down(&self) -> usize {
        self.height.div_ceil(self.chunk_h)
    }
}

fn structure(path: &Path, dec: &mut TiffDecoder) -> Result<Structure, ImageIoError> {
    let (w, h) = dec.dimensions().map_err(|e| tiff_error(path, e))?;
    let colour = dec.colortype().map_err(|e| tiff_error(path, e))?;
    let unsupported = |what: String| {
        ImageIoError::new(
            path,
            format!("{what}; skytie reads 8- or 16-bit grey, RGB(A) or YCbCr TIFFs — convert it (e.g. gdal_translate -ot Byte)"),
        )
    };
    let (channels, bits) = match colour {
        ColorType::Gray(b) => (Channels::Grey { extra: 0 }, b),
        ColorType::GrayA(b) => (Channels::Grey { extra: 1 }, b),
        ColorType::RGB(b) => (Channels::Rgb { extra: 0 }, b),
        ColorType::RGBA(b) => (Channels::Rgb { extra: 1 }, b),
        ColorType::YCbCr(b) => (Channels::YCbCr, b),
        ColorType::Multiband {
            bit_depth,
            num_samples,
        } if num_samples >= 1 => (
            Channels::Grey {
                extra: usize::from(num_samples) - 1,
            },
            bit_depth,
        ),
        other => {
            return Err(unsupported(format!(
                "its colour type {other:?} is not supported"
            )))
        }
    };
    let depth = match bits {
        8 => SampleDepth::U8,
        16 => SampleDepth::U16,
        b => return Err(unsupported(format!("it has {b}-bit samples"))),
    };
    let planar = dec
        .find_tag_unsigned::<u16>(Tag::PlanarConfiguration)
        .ok()
        .flatten()
        == Some(PlanarConfiguration::Planar.to_u16())
        && channels.samples() > 1;
    let (cw, ch) = dec.chunk_dimensions();
    let (chunk_w, chunk_h) = match dec.get_chunk_type() {
        ChunkType::Tile => (cw as usize, ch as usize),
        ChunkType::Strip => (w as usize, (ch as usize).min(h as usize)),
    };
    if chunk_w == 0 || chunk_h == 0 {
        return Err(ImageIoError::new(
            path,
            "declares empty strips or tiles: the file is corrupt",
        ));
    }
    let compression = dec
        .find_tag_unsigned::<u16>(Tag::Compression)
        .ok()
        .flatten();
    let coding = if compression == Some(CompressionMethod::LZW.to_u16()) {
        let predictor = dec
            .find_tag_unsigned::<u16>(Tag::Predictor)
            .ok()
            .flatten()
            .unwrap_or(1);
        if predictor != 1 && predictor != Predictor::Horizontal.to_u16() {
            return Err(unsupported(format!(
                "its LZW predictor {predictor} is not supported"
            )));
        }
        Some(RawCoding::Lzw(ChunkCoding {
            row_px: chunk_w,
            samples: if planar { 1 } else { channels.samples() },
            bytes_per_sample: depth.bytes(),
            horizontal_predictor: predictor == Predictor::Horizontal.to_u16(),
            big_endian: dec.byte_order() == ByteOrder::BigEndian,
        }))
    } else if compression == Some(CompressionMethod::ModernJPEG.to_u16())
        && depth == SampleDepth::U8
        && !planar
        && matches!(channels, Channels::YCbCr | Channels::Grey { extra: 0 })
    {
        let tables = dec.get_tag_u8_vec(Tag::JPEGTables).ok();
        Some(RawCoding::Jpeg(tables))
    } else {
        None
    };
    let raw = match coding {
        Some(coding) => Some(raw_chunks(path, dec, coding)?),
        None => None,
    };
    Ok(Structure {
        width: w as usize,
        height: h as usize,
        channels,
        depth,
        planar,
        chunk_w,
        chunk_h,
        raw,
    })
}

/// The offsets and byte counts of the chunks of `dec`'s image, read without the `tiff` crate as `coding`.
fn raw_chunks(
    path: &Path,
    dec: &mut TiffDecoder,
    coding: RawCoding,
) -> Result<RawChunks, ImageIoError> {
    let tiled = matches!(dec.get_chunk_type(), ChunkType::Tile);
    let (offsets_tag, counts_tag) = if tiled {
        (Tag::TileOffsets, Tag::TileByteCounts)
    } else {
        (Tag::StripOffsets, Tag::StripByteCounts)
    };
    let offsets = dec
        .get_tag_u64_vec(offsets_tag)
        .map_err(|e| tiff_error(path, e))?;
    let counts = dec
        .get_tag_u64_vec(counts_tag)
        .map_err(|e| tiff_error(path, e))?;
    Ok(RawChunks {
        tiled,
        offsets,
        counts,
        coding,
    })
}

/// Samples of one decoded chunk (or plane of a chunk) as u16 or u8; `Err` for other sample types.
enum Samples {
    U8(Vec<u8>),
    U16(Vec<u16>),
}

impl Samples {
    fn u8(&self) -> Option<&[u8]> {
        match self {
            Samples::U8(v) => Some(v),
            Samples::U16(_) => None,
        }
    }

    fn u16(&self) -> Option<&[u16]> {
        match self {
            Samples::U16(v) => Some(v),
            Samples::U8(_) => None,
        }
    }
}

/// Gathers the samples of pixels `0..dw` of a planar chunk's row, which starts at `start` in every plane, into
/// `out`, pixel by pixel (one sample of each plane); `None` where a plane is of another depth (`plane` gives
/// its samples of the wanted depth) or holds too few samples.
fn interleave<T: Copy>(
    planes: &[Samples],
    plane: fn(&Samples) -> Option<&[T]>,
    start: usize,
    dw: usize,
    out: &mut Vec<T>,
) -> Option<()> {
    out.clear();
    for i in 0..dw {
        for p in planes {
            out.push(*plane(p)?.get(start + i)?);
        }
    }
    Some(())
}

fn samples(path: &Path, r: DecodingResult) -> Result<Samples, ImageIoError> {
    match r {
        DecodingResult::U8(v) => Ok(Samples::U8(v)),
        DecodingResult::U16(v) => Ok(Samples::U16(v)),
        _ => Err(ImageIoError::new(
            path,
            "has floating-point or signed samples; skytie reads unsigned 8- or 16-bit images — convert it",
        )),
    }
}

/// Where a decoded chunk goes in the band and how its samples are laid out: `dw × dh` pixels in rows of
/// `row_px` pixels, each pixel's samples as `channels` says (for planar images, per plane).
struct ChunkLayout {
    x0: usize,
    dw: usize,
    dh: usize,
    row_px: usize,
    channels: Channels,
}

/// One row of chunks decoded into full-width grey rows (`u8.rows` or `u16.rows`, `width × band_h`).
struct Band {
    u8: DepthBand<u8>,
    u16: DepthBand<u16>,
}

/// The grey rows of a band at one sample depth, and the pixels and grey of the chunk row being placed.
struct DepthBand<T> {
    rows: Vec<T>,
    pixel: Vec<T>,
    grey: Vec<T>,
}

/// Where row `r` of a decoded chunk goes: its samples start at `start` (in every plane), it has `dw` pixels of
/// `channels` (`n` samples each), and its first `w` grey values go to the band at `dst`.
struct ChunkRow {
    start: usize,
    dw: usize,
    n: usize,
    channels: Channels,
    dst: usize,
    w: usize,
}

impl<T: Copy + Default> DepthBand<T> {
    /// A band of `len` samples.
    fn new(len: usize) -> Self {
        Self {
            rows: vec![T::default(); len],
            pixel: Vec::new(),
            grey: Vec::new(),
        }
    }

    /// The grey of chunk row `at` of `decoded` (one sample vector, or one per plane, interleaved first) into
    /// the band; `plane` gives a vector's samples of this depth, `grey_row` the grey of a row of pixels.
    /// `None` where the chunk holds too few samples (or samples of another depth).
    fn place_row(
        &mut self,
        decoded: &[Samples],
        plane: fn(&Samples) -> Option<&[T]>,
        grey_row: fn(&[T], Channels, &mut Vec<T>),
        at: &ChunkRow,
    ) -> Option<()> {
        match decoded {
            [one] if plane(one).is_some() => {
                let src = plane(one)?.get(at.start..at.start + at.dw * at.n)?;
                grey_row(src, at.channels, &mut self.grey);
            }
            planes => {
                interleave(planes, plane, at.start, at.dw, &mut self.pixel)?;
                grey_row(&self.pixel, at.channels, &mut self.grey);
            }
        }
        self.rows[at.dst..at.dst + at.w].copy_from_slice(&self.grey[..at.w]);
        Some(())
    }
}

/// The decoded samples of chunk `index` (as the `tiff` crate returns them: `dw` pixels per row), or as
/// [`read_lzw_chunk`] returns them (the chunk's full stored width per row), or the grey plane of a JPEG chunk
/// from [`read_jpeg_chunk`]; returns them, that row width and how a pixel's samples are laid out.
fn read_chunk(
    path: &Path,
    dec: &mut TiffDecoder,
    file: &std::fs::File,
    s: &Structure,
    index: usize,
    (dw, dh): (usize, usize),
) -> Result<(Samples, usize, Channels), ImageIoError> {
    let Some(raw) = &s.raw else {
        let r = dec
            .read_chunk(index as u32)
            .map_err(|e| tiff_error(path, e))?;
        return Ok((samples(path, r)?, dw, s.channels));
    };
    let (Some(&offset), Some(&count)) = (raw.offsets.get(index), raw.counts.get(index)) else {
        return Err(ImageIoError::new(
            path,
            format!("has no offset for strip or tile {index}: the file is corrupt"),
        ));
    };
    let rows = if raw.tiled { s.chunk_h } else { dh };
    let c = match &raw.coding {
        RawCoding::Lzw(c) => c,
        RawCoding::Jpeg(tables) => {
            // A JPEG stream is never larger than a few times its raw samples plus its tables.
            let max_bytes = 4 * s.chunk_w * rows * s.channels.samples() + (1 << 20);
            let chunk = read_jpeg_chunk(path, file, (offset, count), max_bytes, tables.as_deref())?;
            if chunk.width < dw || chunk.height < dh {
                return Err(ImageIoError::new(
                    path,
                    format!(
                        "strip or tile {index} holds {} × {} px where {dw} × {dh} are needed: the file is corrupt",
                        chunk.width, chunk.height
                    ),
                ));
            }
            return Ok((
                Samples::U8(chunk.samples),
                chunk.width,
                Channels::Grey { extra: 0 },
            ));
        }
    };
    let expected = c.row_px * rows * c.samples * c.bytes_per_sample;
    let bytes = read_lzw_chunk(path, file, offset, count, expected, c)?;
    let samples = match s.depth {
        SampleDepth::U8 => Samples::U8(bytes),
        SampleDepth::U16 => Samples::U16(
            bytes
                .chunks_exact(2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]))
                .collect(),
        ),
    };
    Ok((samples, c.row_px, s.channels))
}

impl Band {
    /// Reads chunk row `row` of `s` into the band; returns its height.
    fn read(
        &mut self,
        path: &Path,
        dec: &mut TiffDecoder,
        raw: &std::fs::File,
        s: &Structure,
        row: usize,
    ) -> Result<usize, ImageIoError> {
        let band_h = s.chunk_h.min(s.height - row * s.chunk_h);
        let per_plane = s.chunks_across() * s.chunks_down();
        for c in 0..s.chunks_across() {
            let index = row * s.chunks_across() + c;
            let (dw, dh) = dec.chunk_data_dimensions(index as u32);
            let (dw, dh) = (dw as usize, (dh as usize).min(band_h));
            let planes = if s.planar { s.channels.samples() } else { 1 };
            let mut decoded = Vec::with_capacity(planes);
            let (mut row_px, mut channels) = (dw, s.channels);
            for p in 0..planes {
                let (samples, px, ch) =
                    read_chunk(path, dec, raw, s, p * per_plane + index, (dw, dh))?;
                decoded.push(samples);
                (row_px, channels) = (px, ch);
            }
            let layout = ChunkLayout {
                x0: c * s.chunk_w,
                dw,
                dh,
                row_px,
                channels,
            };
            self.place(path, s, &decoded, layout)?;
        }
        Ok(band_h)
    }

    /// Converts the decoded chunk (one sample vector, or one per plane, laid out as `layout` says) to grey and
    /// copies it into the band at column `layout.x0`.
    fn place(
        &mut self,
        path: &Path,
        s: &Structure,
        decoded: &[Samples],
        layout: ChunkLayout,
    ) -> Result<(), ImageIoError> {
        let ChunkLayout {
            x0,
            dw,
            dh,
            row_px,
            channels,
        } = layout;
        let n = channels.samples();
        let stride = if s.planar { row_px } else { row_px * n };
        let short = || {
            ImageIoError::new(
                path,
                "a strip or tile holds fewer samples than its size needs: the file is corrupt",
            )
        };
        for r in 0..dh {
            let at = ChunkRow {
                start: r * stride,
                dw,
                n,
                channels,
                dst: r * s.width + x0,
                w: dw.min(s.width - x0),
            };
            let placed = match (s.depth, decoded, channels) {
                // Grey samples go straight into the band.
                (SampleDepth::U8, [Samples::U8(v)], Channels::Grey { extra: 0 }) => v
                    .get(at.start..at.start + at.w)
                    .map(|src| self.u8.rows[at.dst..at.dst + at.w].copy_from_slice(src)),
                (SampleDepth::U8, ..) => self.u8.place_row(decoded, Samples::u8, grey_row8, &at),
                (SampleDepth::U16, ..) => {
                    self.u16.place_row(decoded, Samples::u16, grey_row16, &at)
                }
            };
            placed.ok_or_else(short)?;
        }
        Ok(())
    }
}

/// Decodes the TIFF or BigTIFF `path` (probed as `probed`) into `sink` as grey, one row of strips or tiles at
/// a time.
pub fn decode(
    path: &Path,
    probed: &ImageHeader,
    sink: &mut dyn GreyRowSink,
) -> Result<GreyInfo, ImageIoError> {
    let file = std::fs::File::open(path)
        .map_err(|e| ImageIoError::new(path, format!("cannot open ({e})")))?;
    let raw = file
        .try_clone()
        .map_err(|e| ImageIoError::new(path, format!("cannot read ({e})")))?;
    let mut dec = Decoder::new(BufReader::new(file)).map_err(|e| tiff_error(path, e))?;
    let s = structure(path, &mut dec)?;
    let bytes = s.depth.bytes();
    let chunk_bytes = s.chunk_w * s.chunk_h * s.channels.samples() * bytes;
    let band_bytes = s.width * s.chunk_h * bytes;
    // A decoded chunk, its compressed bytes (at most its decoded size for the formats read) and the band.
    let _reservation = reserve(
        path,
        "TIFF",
        s.width,
        s.height,
        2 * chunk_bytes + band_bytes,
        "one row of its strips or tiles",
    )?;
    dec = dec.with_limits({
        let mut l = Limits::default();
        l.decoding_buffer_size = chunk_bytes + (1 << 20);
        l.intermediate_buffer_size = 2 * chunk_bytes + (1 << 20);
        l.ifd_value_size = l.ifd_value_size.max(64 << 20);
        l
    });
    let info = GreyInfo {
        width: s.width,
        height: s.height,
        depth: s.depth,
        format: probed.format,
        geotiff: GeoTiffTags::read(&mut dec),
    };
    sink.begin(&info).map_err(|e| sink_error(path, e))?;
    let band_len = |depth: SampleDepth| {
        if s.depth == depth {
            s.width * s.chunk_h
        } else {
            0
        }
    };
    let mut band = Band {
        u8: DepthBand::new(band_len(SampleDepth::U8)),
        u16: DepthBand::new(band_len(SampleDepth::U16)),
    };
    for row in 0..s.chunks_down() {
        let band_h = band.read(path, &mut dec, &raw, &s, row)?;
        for r in 0..band_h {
            let result = match s.depth {
                SampleDepth::U8 => sink.row_u8(&band.u8.rows[r * s.width..(r + 1) * s.width]),
                SampleDepth::U16 => sink.row_u16(&band.u16.rows[r * s.width..(r + 1) * s.width]),
            };
            result.map_err(|e| sink_error(path, e))?;
        }
    }
    Ok(info)
}

//! The PNG part of [`probe`](super::probe::probe): the `IHDR` chunk (size, colour type, bit depth) checked
//! against the file size first, then every chunk walked to `IEND` with its CRC-32 verified (PNG specification,
//! 3rd edition, section 5). A file cut off ends before `IEND`; flipped bits fail a CRC.

use super::header::{check_size, ImageFormat, ImageHeader, Layout, ProbeError, Source};
use std::io::{Read, Seek};

const F: ImageFormat = ImageFormat::Png;

fn corrupt(detail: String) -> ProbeError {
    ProbeError::Corrupt { format: F, detail }
}

fn ends_without_iend(len: u64) -> ProbeError {
    ProbeError::Truncated {
        format: F,
        detail: format!(
            "it ends at byte {len} before its IEND chunk, so part of the image is missing"
        ),
    }
}

/// Channels of a valid (colour type, bit depth) pair.
fn channels(colour_type: u8, bit_depth: u8) -> Option<u8> {
    let ok = |depths: &[u8]| depths.contains(&bit_depth);
    match colour_type {
        0 if ok(&[1, 2, 4, 8, 16]) => Some(1),
        2 if ok(&[8, 16]) => Some(3),
        3 if ok(&[1, 2, 4, 8]) => Some(1),
        4 if ok(&[8, 16]) => Some(2),
        6 if ok(&[8, 16]) => Some(4),
        _ => None,
    }
}

pub(crate) fn probe_png<R: Read + Seek>(
    src: &mut Source<'_, R>,
) -> Result<ImageHeader, ProbeError> {
    src.seek(8)?;
    let mut header: Option<ImageHeader> = None;
    let mut idat_chunks = 0usize;
    loop {
        let at = src.pos();
        let mut head = [0u8; 8];
        if src.read_exact(&mut head)?.is_none() {
            return Err(ends_without_iend(src.len));
        }
        let length = u64::from(u32::from_be_bytes([head[0], head[1], head[2], head[3]]));
        let kind = [head[4], head[5], head[6], head[7]];
        let name = String::from_utf8_lossy(&kind).into_owned();
        if length > 0x7FFF_FFFF || !kind.iter().all(u8::is_ascii_alphabetic) {
            return Err(corrupt(format!(
                "chunk at byte {at} has an invalid type or length"
            )));
        }
        if header.is_none() && &kind != b"IHDR" {
            return Err(corrupt(format!("the first chunk is {name}, not IHDR")));
        }
        let mut crc = crc32fast::Hasher::new();
        crc.update(&kind);
        let mut first = Vec::new();
        let complete = src.stream(length, |bytes| {
            crc.update(bytes);
            if first.len() < 13 {
                first.extend_from_slice(&bytes[..bytes.len().min(13 - first.len())]);
            }
        })?;
        let mut stored = [0u8; 4];
        if complete.is_none() || src.read_exact(&mut stored)?.is_none() {
            return Err(ends_without_iend(src.len));
        }
        if &kind == b"IHDR" && header.is_none() {
            // Checked before the CRC so that an absurd size is named as such.
            header = Some(read_ihdr(&first, length, src.len)?);
        }
        if crc.finalize() != u32::from_be_bytes(stored) {
            return Err(corrupt(format!(
                "chunk {name} at byte {at} fails its CRC check"
            )));
        }
        match &kind {
            b"IDAT" => idat_chunks += 1,
            b"IEND" => break,
            _ => {}
        }
    }
    if idat_chunks == 0 {
        return Err(corrupt("no image data (no IDAT chunk)".into()));
    }
    header.ok_or_else(|| corrupt("no IHDR chunk".into()))
}

fn read_ihdr(data: &[u8], length: u64, file_bytes: u64) -> Result<ImageHeader, ProbeError> {
    if length != 13 || data.len() < 13 {
        return Err(corrupt(format!("IHDR has {length} bytes, not 13")));
    }
    let be = |i: usize| {
        u64::from(u32::from_be_bytes([
            data[i],
            data[i + 1],
            data[i + 2],
            data[i + 3],
        ]))
    };
    let (width, height) = check_size(F, be(0), be(4), file_bytes)?;
    let (bit_depth, colour_type, interlace) = (data[8], data[9], data[12]);
    let channels = channels(colour_type, bit_depth).ok_or_else(|| {
        corrupt(format!(
            "colour type {colour_type} with bit depth {bit_depth} is not a PNG combination"
        ))
    })?;
    if data[10] != 0 || data[11] != 0 || interlace > 1 {
        return Err(corrupt(
            "IHDR names an unknown compression, filter or interlace method".into(),
        ));
    }
    Ok(ImageHeader {
        format: F,
        width,
        height,
        channels,
        bit_depth,
        layout: Layout::Stream {
            progressive_or_interlaced: interlace == 1,
        },
        file_bytes,
    })
}

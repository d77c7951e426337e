//! The JPEG part of [`probe`](super::probe::probe): walk the marker segments (ITU-T T.81, B.1) from the
//! start-of-image to the end-of-image marker, reading the frame header (size, components, precision) and
//! skipping each scan's entropy-coded data up to the next marker. A file cut off anywhere ends before its
//! end-of-image marker; a decoder would fill the missing part with grey, so this is where it is caught.

use super::header::{check_size, ImageFormat, ImageHeader, Layout, ProbeError, Source};
use std::io::{Read, Seek};

const F: ImageFormat = ImageFormat::Jpeg;

fn truncated(detail: String) -> ProbeError {
    ProbeError::Truncated { format: F, detail }
}

fn corrupt(detail: String) -> ProbeError {
    ProbeError::Corrupt { format: F, detail }
}

/// The frame header's facts.
struct Frame {
    width: u32,
    height: u32,
    channels: u8,
    precision: u8,
    progressive: bool,
}

pub(crate) fn probe_jpeg<R: Read + Seek>(
    src: &mut Source<'_, R>,
) -> Result<ImageHeader, ProbeError> {
    src.seek(2)?;
    let mut frame: Option<Frame> = None;
    let mut scans = 0usize;
    let mut pending: Option<u8> = None;
    loop {
        let marker = match pending.take() {
            Some(m) => m,
            None => read_marker(src)?,
        };
        let at = src.pos().saturating_sub(2);
        match marker {
            0xD9 => break,
            0xD0..=0xD7 | 0x01 => continue,
            0xD8 => {
                return Err(corrupt(format!(
                    "a second start-of-image marker at byte {at}"
                )))
            }
            _ => {}
        }
        let mut lb = [0u8; 2];
        if src.read_exact(&mut lb)?.is_none() {
            return Err(ends_without_eoi(src.len));
        }
        let length = u64::from(u16::from_be_bytes(lb));
        if length < 2 {
            return Err(corrupt(format!(
                "segment FF{marker:02X} at byte {at} has length {length}"
            )));
        }
        let body = src.pos();
        let end = body + length - 2;
        if end > src.len {
            return Err(truncated(format!(
                "segment FF{marker:02X} at byte {at} needs {length} bytes but the file ends at byte {}",
                src.len
            )));
        }
        match marker {
            0xC0..=0xCF if !matches!(marker, 0xC4 | 0xC8 | 0xCC) => {
                if frame.is_some() {
                    return Err(corrupt(format!("a second frame header at byte {at}")));
                }
                frame = Some(read_frame(src, marker, length, at)?);
            }
            0xDA => {
                if frame.is_none() {
                    return Err(corrupt(format!(
                        "scan at byte {at} before any frame header"
                    )));
                }
                src.seek(end)?;
                pending = Some(skip_entropy_data(src)?);
                scans += 1;
                continue;
            }
            _ => {}
        }
        src.seek(end)?;
    }
    let Some(fr) = frame else {
        return Err(corrupt(
            "no frame header (no image size) before the end-of-image marker".into(),
        ));
    };
    if scans == 0 {
        return Err(corrupt(
            "no image data (no scan) before the end-of-image marker".into(),
        ));
    }
    Ok(ImageHeader {
        format: F,
        width: fr.width,
        height: fr.height,
        channels: fr.channels,
        bit_depth: fr.precision,
        layout: Layout::Stream {
            progressive_or_interlaced: fr.progressive,
        },
        file_bytes: src.len,
    })
}

fn ends_without_eoi(len: u64) -> ProbeError {
    truncated(format!(
        "it ends at byte {len} without its end-of-image marker, so part of the image is missing"
    ))
}

/// The next marker byte: one 0xFF (plus any fill 0xFF bytes), then the marker.
fn read_marker<R: Read + Seek>(src: &mut Source<'_, R>) -> Result<u8, ProbeError> {
    let mut b = [0u8; 1];
    let at = src.pos();
    if src.read_exact(&mut b)?.is_none() {
        return Err(ends_without_eoi(src.len));
    }
    if b[0] != 0xFF {
        return Err(corrupt(format!(
            "expected a marker at byte {at}, found byte {:02X}",
            b[0]
        )));
    }
    loop {
        if src.read_exact(&mut b)?.is_none() {
            return Err(ends_without_eoi(src.len));
        }
        if b[0] != 0xFF {
            return Ok(b[0]);
        }
    }
}

/// SOFn: precision, height, width, components; only the processes the decoder implements are accepted.
fn read_frame<R: Read + Seek>(
    src: &mut Source<'_, R>,
    marker: u8,
    length: u64,
    at: u64,
) -> Result<Frame, ProbeError> {
    let mut h = [0u8; 6];
    if length < 8 || src.read_exact(&mut h)?.is_none() {
        return Err(corrupt(format!(
            "frame header at byte {at} is too short ({length} bytes)"
        )));
    }
    let precision = h[0];
    let height = u64::from(u16::from_be_bytes([h[1], h[2]]));
    let width = u64::from(u16::from_be_bytes([h[3], h[4]]));
    let components = h[5];
    if length != 8 + 3 * u64::from(components) {
        return Err(corrupt(format!(
            "frame header at byte {at}: {components} components need {} bytes, the segment has {length}",
            8 + 3 * u64::from(components)
        )));
    }
    let process = match marker {
        0xC0 => "baseline",
        0xC1 => "extended sequential",
        0xC2 => "progressive",
        0xC3 | 0xC7 | 0xCB | 0xCF => "lossless",
        _ => "arithmetic-coded or hierarchical",
    };
    if !matches!(marker, 0xC0..=0xC2) {
        return Err(ProbeError::Unsupported {
            format: F,
            detail: format!("{process} JPEG"),
        });
    }
    if precision != 8 {
        return Err(ProbeError::Unsupported {
            format: F,
            detail: format!("{precision}-bit samples"),
        });
    }
    if !matches!(components, 1 | 3 | 4) {
        return Err(ProbeError::Unsupported {
            format: F,
            detail: format!("{components} colour components"),
        });
    }
    if height == 0 {
        return Err(ProbeError::Unsupported {
            format: F,
            detail: "height given after the first scan (DNL marker)".into(),
        });
    }
    let (width, height) = check_size(F, width, height, src.len)?;
    Ok(Frame {
        width,
        height,
        channels: components,
        precision,
        progressive: marker == 0xC2,
    })
}

/// Skip a scan's entropy-coded data: stuffed bytes (FF 00), fill bytes and restart markers belong to it; the
/// first other marker ends it. Returns that marker; the position is just after it.
fn skip_entropy_data<R: Read + Seek>(src: &mut Source<'_, R>) -> Result<u8, ProbeError> {
    let mut prev_ff = false;
    let mut found = 0u8;
    let hit = src.scan(|chunk| {
        let mut i = 0;
        while i < chunk.len() {
            if prev_ff {
                let b = chunk[i];
                if b != 0x00 && b != 0xFF && !(0xD0..=0xD7).contains(&b) {
                    found = b;
                    return Some(i + 1);
                }
                prev_ff = b == 0xFF;
                i += 1;
            } else {
                match chunk[i..].iter().position(|&b| b == 0xFF) {
                    Some(p) => {
                        prev_ff = true;
                        i += p + 1;
                    }
                    None => break,
                }
            }
        }
        None
    })?;
    match hit {
        Some(()) => Ok(found),
        None => Err(truncated(format!(
            "its compressed data ends at byte {} without an end-of-image marker, so part of the image is missing",
            src.len
        ))),
    }
}

//! The TIFF part of [`probe`](super::probe::probe): header (classic or BigTIFF), the first image file
//! directory's size, samples, bit depth, compression and layout (TIFF 6.0 baseline and BigTIFF), then every
//! strip or tile must lie inside the file, and an uncompressed one must hold the bytes its rows need. A TIFF
//! cut off loses the strips or tiles at its end (or its directory, which writers often put last).

use super::header::{check_size, ImageFormat, ImageHeader, Layout, ProbeError, Source};
use std::collections::HashMap;
use std::io::{Read, Seek};

/// Largest number of directory entries accepted (real files have a few dozen).
const MAX_ENTRIES: u64 = 4096;

/// Byte order, classic or big, of the file.
struct Tiff {
    big_endian: bool,
    big: bool,
    format: ImageFormat,
}

/// One directory entry: field type, count and the raw value/offset bytes.
struct Entry {
    kind: u16,
    count: u64,
    value: [u8; 8],
}

impl Tiff {
    fn u16(&self, b: &[u8]) -> u16 {
        let a = [b[0], b[1]];
        if self.big_endian {
            u16::from_be_bytes(a)
        } else {
            u16::from_le_bytes(a)
        }
    }
    fn u32(&self, b: &[u8]) -> u32 {
        let a = [b[0], b[1], b[2], b[3]];
        if self.big_endian {
            u32::from_be_bytes(a)
        } else {
            u32::from_le_bytes(a)
        }
    }
    fn u64(&self, b: &[u8]) -> u64 {
        let a: [u8; 8] = b[..8].try_into().expect("8 bytes");
        if self.big_endian {
            u64::from_be_bytes(a)
        } else {
            u64::from_le_bytes(a)
        }
    }
    /// An offset field (4 or 8 bytes).
    fn offset(&self, b: &[u8]) -> u64 {
        if self.big {
            self.u64(b)
        } else {
            u64::from(self.u32(b))
        }
    }
    fn corrupt(&self, detail: String) -> ProbeError {
        ProbeError::Corrupt {
            format: self.format,
            detail,
        }
    }
    fn truncated(&self, detail: String) -> ProbeError {
        ProbeError::Truncated {
            format: self.format,
            detail,
        }
    }
}

/// Size in bytes of one value of a TIFF field type (0 = unknown type).
fn type_size(kind: u16) -> u64 {
    match kind {
        1 | 2 | 6 | 7 => 1,
        3 | 8 => 2,
        4 | 9 | 11 | 13 => 4,
        5 | 10 | 12 | 16 | 17 | 18 => 8,
        _ => 0,
    }
}

pub(crate) fn probe_tiff<R: Read + Seek>(
    src: &mut Source<'_, R>,
) -> Result<ImageHeader, ProbeError> {
    let mut head = [0u8; 16];
    let n = src.read_up_to(&mut head)?;
    let big_endian = head[0] == b'M';
    let mut t = Tiff {
        big_endian,
        big: false,
        format: ImageFormat::Tiff,
    };
    if n < 8 || head[0] != head[1] {
        return Err(t.truncated(format!("the {n}-byte file is shorter than a TIFF header")));
    }
    let ifd = match t.u16(&head[2..]) {
        42 => u64::from(t.u32(&head[4..])),
        43 => {
            t.big = true;
            t.format = ImageFormat::BigTiff;
            if n < 16 || t.u16(&head[4..]) != 8 {
                return Err(t.corrupt("BigTIFF header with an offset size other than 8".into()));
            }
            t.u64(&head[8..])
        }
        v => {
            return Err(ProbeError::UnknownFormat(format!(
                "a TIFF byte order but version {v}"
            )))
        }
    };
    let entries = read_directory(&t, src, ifd)?;
    image_header(&t, src, &entries)
}

/// The entries of the directory at `ifd`, by tag.
fn read_directory<R: Read + Seek>(
    t: &Tiff,
    src: &mut Source<'_, R>,
    ifd: u64,
) -> Result<HashMap<u16, Entry>, ProbeError> {
    let (count_size, entry_size) = if t.big { (8, 20) } else { (2, 12) };
    if ifd < 8 || ifd.saturating_add(count_size) > src.len {
        return Err(t.truncated(format!(
            "its image directory at byte {ifd} lies past the end of the {}-byte file",
            src.len
        )));
    }
    src.seek(ifd)?;
    let mut cb = [0u8; 8];
    src.read_exact(&mut cb[..count_size as usize])?;
    let count = if t.big {
        t.u64(&cb)
    } else {
        u64::from(t.u16(&cb))
    };
    if count == 0 || count > MAX_ENTRIES {
        return Err(t.corrupt(format!(
            "its image directory at byte {ifd} claims {count} entries"
        )));
    }
    // The entries and the next directory's offset after them.
    let offset_size = if t.big { 8 } else { 4 };
    if ifd + count_size + count * entry_size + offset_size > src.len {
        return Err(t.truncated(format!(
            "its image directory at byte {ifd} ends past the end of the {}-byte file",
            src.len
        )));
    }
    let mut raw = vec![0u8; (count * entry_size) as usize];
    src.read_exact(&mut raw)?;
    let mut entries = HashMap::new();
    for e in raw.chunks_exact(entry_size as usize) {
        let tag = t.u16(e);
        let kind = t.u16(&e[2..]);
        let (count, value) = if t.big {
            (t.u64(&e[4..]), &e[12..20])
        } else {
            (u64::from(t.u32(&e[4..])), &e[8..12])
        };
        let mut v = [0u8; 8];
        v[..value.len()].copy_from_slice(value);
        let bytes = count.saturating_mul(type_size(kind));
        if bytes > offset_size && t.offset(&v).saturating_add(bytes) > src.len {
            return Err(t.truncated(format!(
                "the values of tag {tag} lie past the end of the {}-byte file",
                src.len
            )));
        }
        entries.insert(
            tag,
            Entry {
                kind,
                count,
                value: v,
            },
        );
    }
    Ok(entries)
}

/// All values of an integer field, read inline or from its offset (bounded by the file size).
fn values<R: Read + Seek>(
    t: &Tiff,
    src: &mut Source<'_, R>,
    tag: u16,
    e: &Entry,
) -> Result<Vec<u64>, ProbeError> {
    let size = type_size(e.kind);
    if !matches!(e.kind, 1 | 3 | 4 | 16) {
        return Err(t.corrupt(format!(
            "tag {tag} has field type {} instead of an unsigned integer",
            e.kind
        )));
    }
    let inline = if t.big { 8 } else { 4 };
    let bytes = e.count.saturating_mul(size);
    let data = if bytes <= inline {
        e.value[..bytes as usize].to_vec()
    } else {
        let at = t.offset(&e.value);
        if at.saturating_add(bytes) > src.len {
            return Err(t.truncated(format!(
                "the {} values of tag {tag} at byte {at} lie past the end of the {}-byte file",
                e.count, src.len
            )));
        }
        src.seek(at)?;
        let mut d = vec![0u8; bytes as usize];
        src.read_exact(&mut d)?;
        d
    };
    Ok(data
        .chunks_exact(size as usize)
        .map(|c| match size {
            1 => u64::from(c[0]),
            2 => u64::from(t.u16(c)),
            4 => u64::from(t.u32(c)),
            _ => t.u64(c),
        })
        .collect())
}

/// The first value of `tag`, or `default` when absent.
fn first<R: Read + Seek>(
    t: &Tiff,
    src: &mut Source<'_, R>,
    entries: &HashMap<u16, Entry>,
    tag: u16,
    default: Option<u64>,
) -> Result<u64, ProbeError> {
    match entries.get(&tag) {
        Some(e) if e.count > 0 => Ok(values(t, src, tag, e)?[0]),
        _ => default
            .ok_or_else(|| t.corrupt(format!("required tag {tag} ({}) is missing", tag_name(tag)))),
    }
}

fn tag_name(tag: u16) -> &'static str {
    match tag {
        256 => "ImageWidth",
        257 => "ImageLength",
        273 => "StripOffsets",
        279 => "StripByteCounts",
        324 => "TileOffsets",
        325 => "TileByteCounts",
        _ => "",
    }
}

fn image_header<R: Read + Seek>(
    t: &Tiff,
    src: &mut Source<'_, R>,
    entries: &HashMap<u16, Entry>,
) -> Result<ImageHeader, ProbeError> {
    let width = first(t, src, entries, 256, None)?;
    let height = first(t, src, entries, 257, None)?;
    let (width, height) = check_size(t.format, width, height, src.len)?;
    let bits = first(t, src, entries, 258, Some(1))?;
    let samples = first(t, src, entries, 277, Some(1))?;
    let compression = first(t, src, entries, 259, Some(1))?;
    let planar = first(t, src, entries, 284, Some(1))?;
    let unsupported = |detail: String| ProbeError::Unsupported {
        format: t.format,
        detail,
    };
    if !matches!(bits, 8 | 16 | 32) {
        return Err(unsupported(format!("{bits} bits per sample")));
    }
    if !(1..=4).contains(&samples) {
        return Err(unsupported(format!("{samples} samples per pixel")));
    }
    if !matches!(compression, 1 | 5 | 7 | 8 | 32773 | 32946) {
        return Err(unsupported(format!("compression scheme {compression}")));
    }
    let planes = if planar == 2 { samples } else { 1 };
    let samples_per_plane = samples / planes;
    let (w, h) = (u64::from(width), u64::from(height));
    let tiled = entries.contains_key(&322);
    let (layout, piece_w, piece_h, across) = if tiled {
        let tw = first(t, src, entries, 322, None)?;
        let th = first(t, src, entries, 323, None)?;
        if tw == 0 || th == 0 || tw > u64::from(u32::MAX) || th > u64::from(u32::MAX) {
            return Err(t.corrupt(format!("tile size {tw}×{th}")));
        }
        let count = w.div_ceil(tw) * h.div_ceil(th) * planes;
        let layout = Layout::Tiles {
            tile_width: tw as u32,
            tile_height: th as u32,
            count,
        };
        (layout, tw, th, w.div_ceil(tw))
    } else {
        let rows = first(t, src, entries, 278, Some(h))?.clamp(1, h);
        let count = h.div_ceil(rows) * planes;
        let layout = Layout::Strips {
            rows_per_strip: rows as u32,
            count,
        };
        (layout, w, rows, 1)
    };
    let (offsets_tag, counts_tag) = if tiled { (324, 325) } else { (273, 279) };
    let expected = match layout {
        Layout::Tiles { count, .. } | Layout::Strips { count, .. } => count,
        Layout::Stream { .. } => 0,
    };
    let get = |src: &mut Source<'_, R>, tag: u16| -> Result<Vec<u64>, ProbeError> {
        match entries.get(&tag) {
            Some(e) => values(t, src, tag, e),
            None => Err(t.corrupt(format!("required tag {tag} ({}) is missing", tag_name(tag)))),
        }
    };
    let offsets = get(src, offsets_tag)?;
    let counts = get(src, counts_tag)?;
    if (offsets.len() as u64) < expected || counts.len() != offsets.len() {
        return Err(t.corrupt(format!(
            "{} {} offsets and {} byte counts for the {expected} pieces the image needs",
            offsets.len(),
            if tiled { "tile" } else { "strip" },
            counts.len()
        )));
    }
    let row_bytes = |px: u64| (px * samples_per_plane * bits).div_ceil(8);
    for (i, (&at, &n)) in offsets
        .iter()
        .zip(&counts)
        .take(expected as usize)
        .enumerate()
    {
        let what = if tiled { "tile" } else { "strip" };
        if at.saturating_add(n) > src.len {
            return Err(t.truncated(format!(
                "{what} {} of {expected} ({n} bytes at byte {at}) ends past the end of the {}-byte file",
                i + 1,
                src.len
            )));
        }
        if compression == 1 {
            let index = i as u64 % (expected / planes);
            let rows = if tiled {
                piece_h
            } else {
                piece_h.min(h - (index / across) * piece_h)
            };
            let need = rows * row_bytes(piece_w);
            if n < need {
                return Err(t.corrupt(format!(
                    "uncompressed {what} {} holds {n} bytes but its pixels need {need}",
                    i + 1
                )));
            }
        }
    }
    Ok(ImageHeader {
        format: t.format,
        width,
        height,
        channels: samples as u8,
        bit_depth: bits as u8,
        layout,
        file_bytes: src.len,
    })
}

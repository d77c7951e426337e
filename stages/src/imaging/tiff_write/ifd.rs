//! One TIFF image file directory (IFD) in classic TIFF or BigTIFF form (TIFF 6.0 section 2; BigTIFF: the
//! same with 8-byte counts and offsets, entries of 20 bytes): entries sorted by tag, values of more than 4
//! (BigTIFF: 8) bytes stored before the directory.

/// Field types used here (TIFF 6.0 / BigTIFF).
#[derive(Clone, Copy, Debug)]
pub enum FieldType {
    Ascii = 2,
    Short = 3,
    Long = 4,
    Double = 12,
    Long8 = 16,
}

/// A tag with its values (little-endian bytes) and type.
pub struct Entry {
    pub tag: u16,
    pub field_type: FieldType,
    pub count: u64,
    pub bytes: Vec<u8>,
}

impl Entry {
    pub fn shorts(tag: u16, values: &[u16]) -> Self {
        Self::numbers(tag, FieldType::Short, values, u16::to_le_bytes)
    }

    pub fn longs(tag: u16, values: &[u32]) -> Self {
        Self::numbers(tag, FieldType::Long, values, u32::to_le_bytes)
    }

    pub fn doubles(tag: u16, values: &[f64]) -> Self {
        Self::numbers(tag, FieldType::Double, values, f64::to_le_bytes)
    }

    /// `values` of `field_type`, each written as its little-endian bytes by `le_bytes`.
    fn numbers<T: Copy, const N: usize>(
        tag: u16,
        field_type: FieldType,
        values: &[T],
        le_bytes: fn(T) -> [u8; N],
    ) -> Self {
        Self {
            tag,
            field_type,
            count: values.len() as u64,
            bytes: values.iter().flat_map(|&v| le_bytes(v)).collect(),
        }
    }

    /// NUL-terminated ASCII text.
    pub fn ascii(tag: u16, text: &str) -> Self {
        let mut bytes = text.as_bytes().to_vec();
        bytes.push(0);
        Self {
            tag,
            field_type: FieldType::Ascii,
            count: bytes.len() as u64,
            bytes,
        }
    }

    /// Offsets or byte counts: LONG8 in BigTIFF, LONG in classic TIFF (`None` if a value exceeds 32 bits).
    pub fn offsets(tag: u16, values: &[u64], big: bool) -> Option<Self> {
        if big {
            return Some(Self {
                tag,
                field_type: FieldType::Long8,
                count: values.len() as u64,
                bytes: values.iter().flat_map(|v| v.to_le_bytes()).collect(),
            });
        }
        let longs: Option<Vec<u32>> = values.iter().map(|&v| u32::try_from(v).ok()).collect();
        Some(Self::longs(tag, &longs?))
    }
}

/// The bytes of the out-of-line values followed by the directory, to be written at file offset `at`
/// (word-aligned); returns them and the directory's offset.
pub fn encode(mut entries: Vec<Entry>, at: u64, big: bool) -> (Vec<u8>, u64) {
    entries.sort_by_key(|e| e.tag);
    let inline = if big { 8 } else { 4 };
    let mut out = Vec::new();
    let mut value_offsets = Vec::with_capacity(entries.len());
    for e in &entries {
        if e.bytes.len() > inline {
            if out.len() % 2 == 1 {
                out.push(0);
            }
            value_offsets.push(Some(at + out.len() as u64));
            out.extend_from_slice(&e.bytes);
        } else {
            value_offsets.push(None);
        }
    }
    if out.len() % 2 == 1 {
        out.push(0);
    }
    let ifd_offset = at + out.len() as u64;
    if big {
        out.extend_from_slice(&(entries.len() as u64).to_le_bytes());
    } else {
        out.extend_from_slice(&(entries.len() as u16).to_le_bytes());
    }
    for (e, off) in entries.iter().zip(&value_offsets) {
        out.extend_from_slice(&e.tag.to_le_bytes());
        out.extend_from_slice(&(e.field_type as u16).to_le_bytes());
        let mut field = vec![0u8; inline];
        match off {
            Some(o) if big => field.copy_from_slice(&o.to_le_bytes()),
            Some(o) => field.copy_from_slice(&(*o as u32).to_le_bytes()),
            None => field[..e.bytes.len()].copy_from_slice(&e.bytes),
        }
        if big {
            out.extend_from_slice(&e.count.to_le_bytes());
        } else {
            out.extend_from_slice(&(e.count as u32).to_le_bytes());
        }
        out.extend_from_slice(&field);
    }
    // No next directory.
    out.extend_from_slice(&vec![0u8; inline]);
    (out, ifd_offset)
}

/// The file header with the first directory at `ifd_offset`.
pub fn header(ifd_offset: u64, big: bool) -> Vec<u8> {
    let mut h = b"II".to_vec();
    if big {
        h.extend_from_slice(&43u16.to_le_bytes());
        h.extend_from_slice(&8u16.to_le_bytes());
        h.extend_from_slice(&0u16.to_le_bytes());
        h.extend_from_slice(&ifd_offset.to_le_bytes());
    } else {
        h.extend_from_slice(&42u16.to_le_bytes());
        h.extend_from_slice(&(ifd_offset as u32).to_le_bytes());
    }
    h
}

/// Length of [`header`].
pub fn header_len(big: bool) -> u64 {
    if big {
        16
    } else {
        8
    }
}

//! The vocabulary of image probing: formats, layouts, the header a probe returns, its errors, and the
//! bounded byte source the per-format scanners read through.

use std::fmt;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// Container formats the decoders read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum ImageFormat {
    Jpeg,
    Png,
    Tiff,
    BigTiff,
}

impl ImageFormat {
    /// The usual name (for messages).
    pub fn name(self) -> &'static str {
        match self {
            ImageFormat::Jpeg => "JPEG",
            ImageFormat::Png => "PNG",
            ImageFormat::Tiff => "TIFF",
            ImageFormat::BigTiff => "BigTIFF",
        }
    }

    /// Whether a file name's extension (case-insensitive) is one this format is usually saved under.
    pub fn matches_extension(self, path: &Path) -> bool {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        match self {
            ImageFormat::Jpeg => matches!(ext.as_str(), "jpg" | "jpeg" | "jpe" | "jfif"),
            ImageFormat::Png => ext == "png",
            ImageFormat::Tiff | ImageFormat::BigTiff => matches!(ext.as_str(), "tif" | "tiff"),
        }
    }
}

impl fmt::Display for ImageFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How the pixel data is laid out in the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Layout {
    /// One compressed stream (JPEG, PNG).
    Stream { progressive_or_interlaced: bool },
    /// TIFF strips of `rows_per_strip` full-width rows.
    Strips { rows_per_strip: u32, count: u64 },
    /// TIFF tiles.
    Tiles {
        tile_width: u32,
        tile_height: u32,
        count: u64,
    },
}

/// What [`probe`](super::probe) found out about an image file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ImageHeader {
    pub format: ImageFormat,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel as stored (a palette PNG has 1).
    pub channels: u8,
    /// Bits per sample.
    pub bit_depth: u8,
    pub layout: Layout,
    /// File size, bytes.
    pub file_bytes: u64,
}

/// Why a file is not a usable image. `Display` says what is wrong; [`ProbeError::hint`] what to do.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ProbeError {
    /// The file cannot be opened or read.
    Unreadable(String),
    /// Zero bytes.
    Empty,
    /// Not JPEG, PNG or TIFF (first bytes shown).
    UnknownFormat(String),
    /// The file ends before the format's structure does.
    Truncated { format: ImageFormat, detail: String },
    /// The structure is broken (bad length, CRC, marker, offset).
    Corrupt { format: ImageFormat, detail: String },
    /// The header's size cannot be stored in a file of this size, or is zero.
    AbsurdSize {
        format: ImageFormat,
        width: u64,
        height: u64,
        file_bytes: u64,
    },
    /// A valid file of a kind the decoders do not read (e.g. 12-bit or arithmetic-coded JPEG).
    Unsupported { format: ImageFormat, detail: String },
    /// Structurally sound, but the decoder rejects the pixel data (found only by decoding).
    Undecodable { format: ImageFormat, detail: String },
}

impl ProbeError {
    /// Short machine-readable kind, e.g. for counting in metrics.
    pub fn kind(&self) -> &'static str {
        match self {
            ProbeError::Unreadable(_) => "image_unreadable",
            ProbeError::Empty => "image_empty",
            ProbeError::UnknownFormat(_) => "image_format",
            ProbeError::Truncated { .. } => "image_truncated",
            ProbeError::Corrupt { .. } => "image_corrupt",
            ProbeError::AbsurdSize { .. } => "image_absurd_size",
            ProbeError::Unsupported { .. } => "image_unsupported",
            ProbeError::Undecodable { .. } => "image_undecodable",
        }
    }

    /// What the user should do about it.
    pub fn hint(&self) -> &'static str {
        match self {
            ProbeError::Unreadable(_) => "check that the file exists and is readable",
            ProbeError::Empty | ProbeError::Truncated { .. } => {
                "copy the complete file again (it was cut off, e.g. by an interrupted transfer)"
            }
            ProbeError::UnknownFormat(_) => "convert it to JPEG, PNG or TIFF",
            ProbeError::Corrupt { .. }
            | ProbeError::AbsurdSize { .. }
            | ProbeError::Undecodable { .. } => {
                "the file is damaged: copy it again from the original source"
            }
            ProbeError::Unsupported { .. } => {
                "convert it to 8-bit baseline JPEG, PNG or TIFF (8/16-bit)"
            }
        }
    }
}

impl fmt::Display for ProbeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ProbeError::Unreadable(e) => write!(f, "cannot be read ({e})"),
            ProbeError::Empty => write!(f, "is empty (0 bytes)"),
            ProbeError::UnknownFormat(start) => {
                write!(f, "is not a JPEG, PNG or TIFF file (it starts with {start})")
            }
            ProbeError::Truncated { format, detail } => {
                write!(f, "is a truncated {format} file ({detail})")
            }
            ProbeError::Corrupt { format, detail } => write!(f, "is a damaged {format} file ({detail})"),
            ProbeError::AbsurdSize {
                format,
                width,
                height,
                file_bytes,
            } => write!(
                f,
                "is a {format} file whose header claims {width}×{height} px, which cannot be stored in its {file_bytes} bytes"
            ),
            ProbeError::Unsupported { format, detail } => {
                write!(f, "is a {format} file of a kind skytie cannot decode ({detail})")
            }
            ProbeError::Undecodable { format, detail } => {
                write!(f, "is a {format} file whose image data does not decode ({detail})")
            }
        }
    }
}

impl std::error::Error for ProbeError {}

/// No supported compression stores more pixels per byte of file: deflate's ratio is at most 1032:1 per byte
/// (a 1-bit image: 8 px per byte), a Huffman-coded JPEG needs ≥ 1 bit per 8×8 block (512 px per byte), LZW
/// emits at most 4096 bytes per 9-bit code. A file above it is not an image of that size.
pub const MAX_PIXELS_PER_BYTE: u64 = 8 * 4096;

/// Read size of the structural scan.
const CHUNK: usize = 1 << 20;

/// `width × height` must be non-zero and storable in `file_bytes`.
pub(crate) fn check_size(
    format: ImageFormat,
    width: u64,
    height: u64,
    file_bytes: u64,
) -> Result<(u32, u32), ProbeError> {
    let absurd = || ProbeError::AbsurdSize {
        format,
        width,
        height,
        file_bytes,
    };
    if width == 0 || height == 0 || width > u64::from(u32::MAX) || height > u64::from(u32::MAX) {
        return Err(absurd());
    }
    let limit = file_bytes.saturating_mul(MAX_PIXELS_PER_BYTE);
    if width.saturating_mul(height) > limit {
        return Err(absurd());
    }
    Ok((width as u32, height as u32))
}

/// A bounded, seekable byte source with the file length known (reads past the end are reported as such).
pub(crate) struct Source<'a, R: Read + Seek> {
    r: &'a mut R,
    pub len: u64,
    pos: u64,
}

impl<'a, R: Read + Seek> Source<'a, R> {
    pub(super) fn new(r: &'a mut R, len: u64) -> Self {
        Source { r, len, pos: 0 }
    }

    pub fn pos(&self) -> u64 {
        self.pos
    }

    pub fn seek(&mut self, pos: u64) -> Result<(), ProbeError> {
        self.r
            .seek(SeekFrom::Start(pos))
            .map_err(|e| ProbeError::Unreadable(e.to_string()))?;
        self.pos = pos;
        Ok(())
    }

    /// Fill as much of `buf` as the file holds from the current position; the count read.
    pub fn read_up_to(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        let want = (buf.len() as u64).min(self.len.saturating_sub(self.pos)) as usize;
        let mut got = 0;
        while got < want {
            match self.r.read(&mut buf[got..want]) {
                Ok(0) => break,
                Ok(n) => got += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(ProbeError::Unreadable(e.to_string())),
            }
        }
        self.pos += got as u64;
        Ok(got)
    }

    /// Exactly `buf.len()` bytes, or `None` when the file ends first.
    pub fn read_exact(&mut self, buf: &mut [u8]) -> Result<Option<()>, ProbeError> {
        Ok((self.read_up_to(buf)? == buf.len()).then_some(()))
    }

    /// Feed the next `n` bytes to `f` in chunks; `None` when the file ends first.
    pub fn stream(&mut self, n: u64, mut f: impl FnMut(&[u8])) -> Result<Option<()>, ProbeError> {
        let mut buf = vec![0u8; CHUNK.min(n as usize).max(1)];
        let mut left = n;
        while left > 0 {
            let take = (buf.len() as u64).min(left) as usize;
            let got = self.read_up_to(&mut buf[..take])?;
            f(&buf[..got]);
            if got < take {
                return Ok(None);
            }
            left -= got as u64;
        }
        Ok(Some(()))
    }

    /// Read chunks from the current position until `f` returns `Some(consumed)` (the bytes of the last chunk it
    /// used; the position is left just after them) or the file ends (`None`).
    pub fn scan(
        &mut self,
        mut f: impl FnMut(&[u8]) -> Option<usize>,
    ) -> Result<Option<()>, ProbeError> {
        let mut buf = vec![0u8; CHUNK];
        loop {
            let start = self.pos;
            let got = self.read_up_to(&mut buf)?;
            if got == 0 {
                return Ok(None);
            }
            if let Some(used) = f(&buf[..got]) {
                self.seek(start + used as u64)?;
                return Ok(Some(()));
            }
        }
    }
}

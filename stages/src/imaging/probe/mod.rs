//! What an image file is, read from its content (never from its name): format, size, channels, bit depth and
//! layout from the header, plus a structural scan that finds truncated and damaged files without decoding a
//! pixel — a JPEG must reach its end-of-image marker through well-formed segments, a PNG its `IEND` chunk with
//! every chunk's CRC intact, a TIFF's strips or tiles must lie inside the file.
//!
//! A header whose size cannot be stored in the file at all (100000 × 100000 px in 1 KB) is rejected right after
//! the header is read, before anything is allocated for the pixels: no compression any decoder supports packs
//! more than [`MAX_PIXELS_PER_BYTE`] pixels into one byte.
//!
//! Cost: one sequential read of the file in fixed-size chunks (memory independent of the image size); no
//! decoding. Decoders used after a successful probe meet the same file.

mod header;
mod jpeg;
mod png;
mod tiff;

use header::Source;
pub use header::{ImageFormat, ImageHeader, Layout, ProbeError, MAX_PIXELS_PER_BYTE};

use std::io::{Read, Seek};
use std::path::Path;

/// Probe the image file at `path` (see the module documentation).
pub fn probe(path: &Path) -> Result<ImageHeader, ProbeError> {
    let mut f = std::fs::File::open(path).map_err(|e| ProbeError::Unreadable(e.to_string()))?;
    let len = f
        .metadata()
        .map_err(|e| ProbeError::Unreadable(e.to_string()))?
        .len();
    probe_reader(&mut f, len)
}

/// Probe an image held in memory.
pub fn probe_bytes(bytes: &[u8]) -> Result<ImageHeader, ProbeError> {
    probe_reader(&mut std::io::Cursor::new(bytes), bytes.len() as u64)
}

/// Probe `len` bytes readable from `r` (positioned anywhere; it is rewound).
pub fn probe_reader<R: Read + Seek>(r: &mut R, len: u64) -> Result<ImageHeader, ProbeError> {
    if len == 0 {
        return Err(ProbeError::Empty);
    }
    let mut src = Source::new(r, len);
    let mut magic = [0u8; 8];
    let n = src.read_up_to(&mut magic)?;
    let magic = &magic[..n];
    src.seek(0)?;
    if magic.starts_with(&[0xFF, 0xD8]) {
        jpeg::probe_jpeg(&mut src)
    } else if magic.starts_with(b"\x89PNG\r\n\x1a\n") {
        png::probe_png(&mut src)
    } else if magic.starts_with(b"II") || magic.starts_with(b"MM") {
        tiff::probe_tiff(&mut src)
    } else {
        let shown: Vec<String> = magic.iter().take(4).map(|b| format!("{b:02X}")).collect();
        Err(ProbeError::UnknownFormat(format!(
            "bytes {}",
            shown.join(" ")
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::header::check_size;
    use super::*;

    #[test]
    fn unknown_and_empty_inputs_are_named() {
        assert_eq!(probe_bytes(&[]), Err(ProbeError::Empty));
        let e = probe_bytes(b"GIF89a......").unwrap_err();
        assert_eq!(
            e.to_string(),
            "is not a JPEG, PNG or TIFF file (it starts with bytes 47 49 46 38)"
        );
        assert_eq!(e.kind(), "image_format");
    }

    #[test]
    fn size_bound_rejects_what_no_compression_can_store() {
        assert!(check_size(ImageFormat::Png, 100_000, 100_000, 1024).is_err());
        assert!(check_size(ImageFormat::Png, 0, 10, 1024).is_err());
        assert_eq!(
            check_size(ImageFormat::Jpeg, 26_460, 17_004, 20_000_000).unwrap(),
            (26_460, 17_004)
        );
    }

    #[test]
    fn extensions() {
        assert!(ImageFormat::Jpeg.matches_extension(Path::new("a/b.JPG")));
        assert!(!ImageFormat::Png.matches_extension(Path::new("a/b.jpg")));
        assert!(ImageFormat::BigTiff.matches_extension(Path::new("b.tiff")));
    }
}

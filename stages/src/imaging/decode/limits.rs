//! Checks made on an image's header before anything is allocated: the claimed size must be possible at all,
//! must fit the bytes the file has (no compression squeezes more than a known number of pixels into a byte),
//! and the decoding buffers must fit the memory budget.

use crate::imaging::budget::{self, human_bytes, Reservation, RAISE_HINT};
use crate::imaging::io::ImageIoError;
use std::path::Path;

/// Largest side accepted, pixels (TIFF allows 2^32; no camera comes near this).
pub const MAX_SIDE_PX: usize = 1 << 20;

/// Most pixels per byte of file each format can describe:
/// - JPEG: every 8 × 8 block of the first component costs at least one bit (its DC code), so ≤ 512 px/byte;
/// - PNG: deflate expands at most ≈ 1032× and each pixel is at least 1/8 byte of filtered data (1-bit), so
///   ≤ 8256 px/byte;
/// - TIFF: LZW expands ≤ ≈ 1370× (a 12-bit code yields at most 4096 bytes), deflate ≈ 1032×, so with 1 byte
///   per pixel and sample ≤ 1400 px/byte (plus 512 for JPEG-compressed TIFF, which is below it).
pub mod px_per_byte {
    pub const JPEG: f64 = 512.0;
    pub const PNG: f64 = 8256.0;
    pub const TIFF: f64 = 1400.0;
}

/// Refuses a header whose size is impossible or more than `file_len` bytes could hold at `max_px_per_byte`.
pub fn check_claimed_size(
    path: &Path,
    format: &str,
    width: usize,
    height: usize,
    file_len: u64,
    max_px_per_byte: f64,
) -> Result<(), ImageIoError> {
    if width == 0 || height == 0 {
        return Err(ImageIoError::new(
            path,
            format!("its {format} header says {width} × {height} px: an image without pixels"),
        ));
    }
    if width > MAX_SIDE_PX || height > MAX_SIDE_PX {
        return Err(ImageIoError::new(
            path,
            format!(
                "its {format} header claims {width} × {height} px, more than {MAX_SIDE_PX} px on a side: the header is \
                 corrupt"
            ),
        ));
    }
    let pixels = width as f64 * height as f64;
    if pixels > file_len as f64 * max_px_per_byte {
        return Err(ImageIoError::new(
            path,
            format!(
                "its {format} header claims {width} × {height} px, which {file_len} bytes cannot hold: the file is \
                 truncated or its header is corrupt"
            ),
        ));
    }
    Ok(())
}

/// Reserves `bytes` of the global memory budget for decoding `path` (`width × height` px, `what` says what
/// the buffer is); the error names the file, its size and how to raise the budget.
pub fn reserve(
    path: &Path,
    format: &str,
    width: usize,
    height: usize,
    bytes: usize,
    what: &str,
) -> Result<Reservation<'static>, ImageIoError> {
    budget::global().reserve(bytes).map_err(|total| {
        ImageIoError::new(
            path,
            format!(
                "this {width} × {height} px {format} needs {} for {what}, more than the memory budget of {}; \
                 {RAISE_HINT}",
                human_bytes(bytes),
                human_bytes(total)
            ),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_headers_are_refused_with_the_file_named() {
        let p = Path::new("aerial/nadir/a.jpg");
        let e =
            check_claimed_size(p, "JPEG", 100_000, 100_000, 1024, px_per_byte::JPEG).unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("a.jpg") && m.contains("100000 × 100000") && m.contains("1024 bytes"),
            "{m}"
        );
        assert!(check_claimed_size(p, "JPEG", 26460, 17004, 40 << 20, px_per_byte::JPEG).is_ok());
        assert!(check_claimed_size(p, "TIFF", 0, 5, 100, px_per_byte::TIFF).is_err());
        assert!(check_claimed_size(p, "TIFF", 3 << 20, 5, u64::MAX, px_per_byte::TIFF).is_err());
    }

    #[test]
    fn an_oversized_reservation_names_the_option() {
        let e = reserve(
            Path::new("x.tif"),
            "TIFF",
            100,
            100,
            usize::MAX / 2,
            "its grey plane",
        )
        .err()
        .unwrap();
        let m = e.to_string();
        assert!(
            m.contains("x.tif") && m.contains("100 × 100") && m.contains("--memory-budget"),
            "{m}"
        );
    }
}

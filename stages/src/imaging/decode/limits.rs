//! Limits of the decoders: the largest side they accept, and the memory budget their buffers are reserved
//! from (the error names the file, its size and the option that raises the budget). Impossible or absurd
//! header sizes are refused earlier, by the probe every decode starts with ([`crate::imaging::probe`]).

use crate::imaging::budget::{self, human_bytes, Reservation, RAISE_HINT};
use crate::imaging::io_error::ImageIoError;
use std::path::Path;

/// Largest side accepted, pixels (TIFF allows 2^32; no camera comes near this).
pub const MAX_SIDE_PX: usize = 1 << 20;

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

//! A registration pair of the peer-comparison benches: written as 8-bit PNGs and re-loaded, so that skytie and
//! the peer see identical pixels.

use skytie_stages::imaging::io::{load_gray, save_gray};
use skytie_stages::imaging::GrayImage;
use std::path::Path;

/// A reference patch, a moving patch and the true shift of the moving one, pixels.
pub struct ShiftedPair {
    pub reference: GrayImage,
    pub moving: GrayImage,
    pub tx_px: f64,
    pub ty_px: f64,
}

impl ShiftedPair {
    /// Writes `reference` and `moving` into `dir` under `file_names` and returns them as re-loaded (8-bit
    /// quantised), with their true shift `(tx, ty)`.
    pub fn written(
        dir: &Path,
        file_names: [String; 2],
        reference: &GrayImage,
        moving: &GrayImage,
        (tx_px, ty_px): (f64, f64),
    ) -> Self {
        let [pa, pb] = file_names.map(|name| dir.join(name));
        save_gray(&pa, reference).expect("write PNG");
        save_gray(&pb, moving).expect("write PNG");
        Self {
            reference: load_gray(&pa).expect("re-load PNG"),
            moving: load_gray(&pb).expect("re-load PNG"),
            tx_px,
            ty_px,
        }
    }
}

//! The block's point unknowns as the adjustment stage records them: which kind of point each is (MM tie point,
//! aerial control point, single-aerial point) and its panorama and aerial observations by index.

use serde::{Deserialize, Serialize};

/// What a tie-point unknown is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum PointKind {
    /// MM tie point without aerial observations.
    Tie,
    /// Aerial control point seen in ≥ 2 aerial images.
    Control,
    /// Aerial control point seen in a single aerial image.
    SingleAerial,
}

/// One tie-point unknown and its observations (indices into the run's recordings and aerial images).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockPoint {
    /// `MmTiePoint::id` / `AerialControlPoint::tie_point_id`.
    pub id: String,
    pub kind: PointKind,
    /// (recording index, u, v) panorama pixels.
    pub pano: Vec<(usize, f64, f64)>,
    /// (aerial image index, u, v) aerial pixels (all aerial observations of the point, used or not).
    pub aerial: Vec<(usize, f64, f64)>,
}

impl BlockPoint {
    /// The recordings that observe the point in their panoramas, ascending, each once.
    pub fn recordings(&self) -> Vec<usize> {
        let mut recordings: Vec<usize> = self.pano.iter().map(|o| o.0).collect();
        recordings.sort_unstable();
        recordings.dedup();
        recordings
    }
}

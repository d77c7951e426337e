//! What one adjustment is given: the recordings (the recorded poses), the registration stages'
//! correspondences, the aerial images they refer to, and what is known of the panoramas and the ground.

use super::problem::HeightObservation;
use crate::campaign::{AerialImage, Recording};
use crate::correspondence::{AerialControlPoint, MmTiePoint};

/// The inputs of one adjustment.
#[derive(Clone, Copy, Debug)]
pub struct AdjustInputs<'a> {
    /// `mm/recordings.csv` rows, sorted by time (the recorded poses).
    pub recordings: &'a [Recording],
    /// Panorama (width, height) in pixels, one per recording.
    pub pano_size_px: &'a [(u32, u32)],
    /// The detail level of each recording's panorama (`PyramidLayout::detail_level`: 0 unless it was enlarged
    /// by pixel repetition), one per recording, or empty for 0 everywhere. `pano_sigma_px` is in pixels of
    /// that level, so a panorama enlarged 2^l times is weighted like the original.
    pub pano_detail_level: &'a [usize],
    /// MM–MM tie points (nadir matching and/or the oblique sparse cloud).
    pub tie_points: &'a [MmTiePoint],
    /// Aerial control points (nadir and/or oblique).
    pub control: &'a [AerialControlPoint],
    /// `aerial/nadir/cameras.csv` and `aerial/oblique/cameras.csv` rows (fixed orientations).
    pub nadir: &'a [AerialImage],
    pub oblique: &'a [AerialImage],
    /// Observed heights of the recordings (one per recording, `None` where there is none) from the campaign's
    /// terrain model ([`super::height_observation::terrain_heights`]), used with `dtm_height`; `None` when the
    /// campaign has no terrain model.
    pub heights: Option<&'a [Option<HeightObservation>]>,
    /// Observed heights of the tie points (one per entry of `tie_points`, `None` where there is none: no
    /// terrain there, or not a ground point) from the campaign's terrain model
    /// ([`super::tie_point_heights::terrain_under_tie_points`]), used with `dtm_tie_heights`; `None` when the
    /// campaign has no terrain model.
    pub tie_point_heights: Option<&'a [Option<HeightObservation>]>,
}

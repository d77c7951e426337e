//! Correspondence types that flow between the registration stages (nadir, oblique) and the adjustment.
//!
//! Every measurement goes back to the original image geometry (thesis 3.4.3, last paragraph): a panorama
//! observation is a continuous equirectangular pixel of the *original* panorama, an aerial observation a
//! continuous pixel of the original aerial image (campaign-format.md pixel convention: the first pixel's centre
//! is at (0.5, 0.5)). Object points are world frame, metres, f64.

use crate::campaign::AerialKind;
use serde::{Deserialize, Serialize};

mod ray_ground;
pub use ray_ground::AerialRayGround;

/// Where a point was measured in a panorama (original equirectangular pixel coordinates).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PanoObservation {
    /// `image_id` of the recording (`mm/recordings.csv`).
    pub image_id: String,
    pub u_px: f64,
    pub v_px: f64,
}

/// Where a point was measured in an aerial image (original pixel coordinates of the aerial image file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AerialObservation {
    /// `image_id` of the aerial image (`aerial/{nadir,oblique}/cameras.csv`).
    pub image_id: String,
    pub kind: AerialKind,
    pub u_px: f64,
    pub v_px: f64,
    /// Matching quality of this observation (phase-correlation peak or NCC/MI score; higher is better).
    pub score: f64,
    /// σ of this observation in full-resolution pixels when the stage that located it knows it better than
    /// the image's `sigma_px` (a point located at pyramid level l is `sigma_px · 2^l` full pixels precise);
    /// `None`: the image's `sigma_px`.
    #[serde(default)]
    pub sigma_px: Option<f64>,
}

/// A point matched across 2–3 adjacent panoramas (thesis 3.4.4) and triangulated from them (3.4.4.5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MmTiePoint {
    /// Stable identifier: `<image_id of the detecting recording>#<corner index>` (nadir) or
    /// `<triplet id>#<index>` (oblique sparse cloud).
    pub id: String,
    /// Observations, the detecting panorama first; at least two, all in different panoramas.
    pub observations: Vec<PanoObservation>,
    /// Triangulated object point, world frame, metres.
    pub point_world: [f64; 3],
    /// A-priori covariance of `point_world` (σ0 = 1) from the triangulation, m², row-major.
    pub covariance_m2: [[f64; 3]; 3],
    /// Largest intersection angle between the rays, degrees.
    pub max_angle_deg: f64,
}

/// An aerial control point (thesis 3.4.5.4): a point located in ≥ 1 aerial image(s) and linked to its MM
/// observations. With ≥ 2 aerial observations it is triangulated from the aerial images alone, so its object
/// coordinate is independent of the uncertain MM positions; with exactly one it can still enter a bundle that
/// holds the aerial orientation fixed but has no `point_world`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AerialControlPoint {
    /// The MM tie point it came from (`MmTiePoint::id`).
    pub tie_point_id: String,
    /// The MM observations of the point (copied from the tie point).
    pub mm: Vec<PanoObservation>,
    /// Observations in aerial images (each in a different image).
    pub aerial: Vec<AerialObservation>,
    /// Object point triangulated from the aerial observations (world, m); `None` with fewer than two.
    pub point_world: Option<[f64; 3]>,
    /// A-priori covariance of `point_world` (σ0 = 1, from the aerial images' `sigma_px`), m², row-major.
    pub covariance_m2: Option<[[f64; 3]; 3]>,
    /// Set when the point comes from an orthophoto instead of aerial frames (`aerial` is then empty): where it
    /// was measured and where its height came from. `point_world` and `covariance_m2` are then always set.
    #[serde(default)]
    pub map: Option<MapControl>,
    /// For a point seen in one aerial nadir image (`point_world` is then `None`): that image's ray where it
    /// crosses the MM tie point's height, so the point still has a horizontal position to verify against.
    #[serde(default)]
    pub ray_ground: Option<AerialRayGround>,
}

/// Where a height came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum HeightSource {
    /// Interpolated bilinearly in the campaign's DTM.
    Dtm,
    /// The mobile-mapping ground estimate (no DTM, or none at the point).
    MmGround,
}

/// The orthophoto measurement of a control point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapControl {
    /// The orthophoto tile, as named in `campaign.toml`.
    pub orthophoto: String,
    /// Continuous pixel in that tile (full resolution).
    pub u_px: f64,
    pub v_px: f64,
    /// Phase-correlation peak of the match.
    pub score: f64,
    pub height: HeightSource,
}

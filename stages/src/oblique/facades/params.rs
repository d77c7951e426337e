//! Parameters of the façade search (thesis 4.4.2–4.4.4) with units, defaults and range checks.
//!
//! Defaults follow the thesis where it gives a value (Table 4-1: max angle 5°, band 0.5 m, ≥ 10 points; 4.4.3:
//! θ, φ ≤ 70°, ≤ 8 cm theoretical resolution); the reasoning behind the others is in `docs/method.md`.

use serde::{Deserialize, Serialize};

/// How the non-uniform box grid (thesis 4.4.4, Pomerleau et al. 2013) splits a box that holds too many points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ThinningSplit {
    /// At the median point along the longest box dimension (libpointmatcher): every leaf keeps ⌈K/2⌉..K
    /// points, so dense and sparse areas are thinned at the same rate.
    Median,
    /// At the spatial midpoint of the longest box dimension (octree-like): isolated points end up alone in
    /// their box and are kept, clusters are thinned — the behaviour the thesis describes ("points with high
    /// proximity, rather than isolated points, will be removed"). Default.
    Midpoint,
}

crate::params! {
    /// Everything the façade search can be told.
    pub struct FacadeParams {
        /// Maximum angle between a plane normal and the reference vector (horizontal, perpendicular to the
        /// driving direction); a cone, so it bounds yaw and pitch together (thesis 4.4.2, Table 4-1).
        max_angle_deg: f64 = 5.0, unit "deg", above 0.0, max 90.0;
        /// Sparse points within this distance of a plane are its inliers (thesis 4.4.2). The MLESAC likelihood
        /// uses σ = band / 2.
        inlier_band_m: f64 = 0.5, unit "m", above 0.0, max 10.0;
        /// Fewest inliers for a plane (thesis Table 4-1; a plane needs 3).
        min_points: usize = 10, min 3;
        /// MLESAC: cap on the samples drawn per plane.
        mlesac_max_trials: usize = 10_000, min 1, max 1_000_000;
        /// MLESAC: confidence of the adaptive trial count.
        mlesac_confidence: f64 = 0.99, above 0.0, below 1.0;
        /// MLESAC: EM iterations per hypothesis.
        mlesac_em_iterations: usize = 3, min 1, max 100;
        /// Planes looked for per side: after a plane is found its inliers are removed and MLESAC runs again on
        /// the rest, up to this many planes (the thesis fits one plane per side).
        max_planes_per_side: usize = 1, min 1, max 10;
        /// Collinearity criterion (thesis 4.4.2): the centre recording must lie within this horizontal distance
        /// of the line through the outer two, else no plane is fitted.
        max_collinearity_deviation_m: f64 = 0.5, unit "m", above 0.0;
        /// The outer two recordings of the triplet must be at least this far apart horizontally.
        min_triplet_span_m: f64 = 1.0, unit "m", min 0.0;
        /// A plane is occluded (thesis 4.4.2, Fig. 4.5) when more than this many sparse points lie between it
        /// and the centre recording, on a sight line from the recording to the inliers' rectangle in the plane.
        occlusion_max_points: usize = 10;
        /// Visibility hypothesis (thesis 4.4.3): both view angles θ and φ at most this.
        max_view_angle_deg: f64 = 70.0, unit "deg", above 0.0, below 90.0;
        /// Visibility hypothesis (thesis 4.4.3): the theoretical resolution t = range / focal length at the
        /// centroid at most this.
        max_resolution_m: f64 = 0.08, unit "m", above 0.0;
        /// Patch centres: only inliers within this distance of the fitted plane (plane fitting still uses
        /// `inlier_band_m`).
        max_centre_offset_m: f64 = 0.15, unit "m", above 0.0;
        /// Box-grid thinning (thesis 4.4.4): a box with more points than this is split; one random point is
        /// kept per leaf box.
        thinning_max_points_per_box: usize = 8, min 1;
        /// Box-grid thinning: boxes longer than this are split whatever their count; `inf` splits by count
        /// only.
        thinning_max_box_m: f64 = 2.0, unit "m", above 0.0, max f64::INFINITY;
        /// Box-grid split rule (see [`ThinningSplit`]).
        thinning_split: ThinningSplit = ThinningSplit::Midpoint;
        /// Seed of MLESAC sampling and of the thinning's random choice (mixed with the triplet and side).
        seed: u64 = 0;
    }
}

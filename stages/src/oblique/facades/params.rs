//! Parameters of the façade search (thesis 4.4.2–4.4.4) with units, defaults and range checks.
//!
//! Defaults follow the thesis where it gives a value (Table 4-1: max angle 5°, band 0.5 m, ≥ 10 points; 4.4.3:
//! θ, φ ≤ 70°, ≤ 8 cm theoretical resolution) and are chosen and stated per field where it does not.

use serde::{Deserialize, Serialize};

/// How the non-uniform box grid (thesis 4.4.4, ALGORITHMS.md §9) splits a box that holds too many points.
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

/// Everything the façade search can be told.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FacadeParams {
    /// Maximum angle between a plane normal and the reference vector (horizontal, perpendicular to the
    /// driving direction), degrees (default 5°, thesis 4.4.2 / Table 4-1; a cone, so yaw and pitch together).
    pub max_angle_deg: f64,
    /// Sparse points within this distance of a plane are its inliers, metres (default 0.5 m, thesis 4.4.2).
    /// The MLESAC likelihood uses σ = band / 2 (ALGORITHMS.md §8).
    pub inlier_band_m: f64,
    /// Fewest inliers for a plane, (default 10, thesis Table 4-1).
    pub min_points: usize,
    /// MLESAC: cap on the samples drawn per plane (default 10 000).
    pub mlesac_max_trials: usize,
    /// MLESAC: confidence of the adaptive trial count (default 0.99).
    pub mlesac_confidence: f64,
    /// MLESAC: EM iterations per hypothesis (default 3).
    pub mlesac_em_iterations: usize,
    /// Planes looked for per side: after a plane is found its inliers are removed and MLESAC runs again on
    /// the rest, up to this many planes (default 1, the thesis' one plane per side; 2–3 can pick up a second
    /// building set back from the street in the same triplet).
    pub max_planes_per_side: usize,
    /// Collinearity criterion on the recording locations (thesis 4.4.2): the centre recording must lie within
    /// this horizontal distance of the line through the outer two, metres, else the driving direction — and
    /// with it the reference vector — is not well defined and no plane is fitted (default 0.5 m: ≈ 4× the
    /// random GNSS noise of the campaigns; on a 5 m spacing it admits curves of radius ≳ 25 m, while the 5°
    /// angle constraint is what limits the façade directions).
    pub max_collinearity_deviation_m: f64,
    /// The outer two recordings of the triplet must be at least this far apart horizontally, metres (default
    /// 1 m; a standing vehicle defines no driving direction).
    pub min_triplet_span_m: f64,
    /// A plane is occluded (thesis 4.4.2, Fig. 4.5) when more than this many sparse points lie between it
    /// and the centre recording: farther than the inlier band in front of the plane, nearer than the
    /// recording, on a sight line from the recording to the inliers' rectangle (horizontal × vertical) in the
    /// plane. The thesis
    /// gives no number; default 10 = `min_points`: an occluder that the sparse cloud sees as densely as a
    /// minimal façade (a tree crown, a truck) blocks it, a few stray mismatches do not.
    pub occlusion_max_points: usize,
    /// Visibility hypothesis (thesis 4.4.3): both view angles θ and φ at most this, degrees (default 70°).
    pub max_view_angle_deg: f64,
    /// Visibility hypothesis: theoretical resolution t = range / focal_px at the centroid at most this, metres
    /// (default 0.08 m, thesis 4.4.3). Note: the synthetic campaigns' obliques have 0.10 m at the image centre
    /// (450 m at 45°), which this default rejects; use ≈ 0.15 m for them.
    pub max_resolution_m: f64,
    /// Patch centres: only inliers within this distance of the fitted plane, metres (default 0.15 m). The patch
    /// grid lies in the plane through its centre point parallel to the façade; a centre d off the façade puts
    /// the façade texture at a wrong depth, and the MM and oblique views see it with a parallax of ≈ 1.5·d
    /// (horizontal MM rays vs 45° oblique rays). Plane fitting still uses `inlier_band_m`.
    pub max_centre_offset_m: f64,
    /// Box-grid thinning (thesis 4.4.4): a box with more points than this is split; one random point is kept
    /// per leaf box (default 8; the thesis gives no value, libpointmatcher uses 7, MATLAB requires ≥ 6).
    pub thinning_max_points_per_box: usize,
    /// Box-grid thinning: boxes longer than this are split whatever their count, metres (default 2 m: points
    /// farther apart give patch centres more than a quarter of the 8 m patch apart, which are kept; closer
    /// ones are thinned to one per ≤ K points). `inf` gives the count-only reference behaviour.
    pub thinning_max_box_m: f64,
    /// Box-grid split rule (default `Midpoint`, see [`ThinningSplit`]).
    pub thinning_split: ThinningSplit,
    /// Seed of MLESAC sampling and of the thinning's random choice (mixed with the triplet and side).
    pub seed: u64,
}

impl Default for FacadeParams {
    fn default() -> Self {
        Self {
            max_angle_deg: 5.0,
            inlier_band_m: 0.5,
            min_points: 10,
            mlesac_max_trials: 10_000,
            mlesac_confidence: 0.99,
            mlesac_em_iterations: 3,
            max_planes_per_side: 1,
            max_collinearity_deviation_m: 0.5,
            min_triplet_span_m: 1.0,
            occlusion_max_points: 10,
            max_view_angle_deg: 70.0,
            max_resolution_m: 0.08,
            max_centre_offset_m: 0.15,
            thinning_max_points_per_box: 8,
            thinning_max_box_m: 2.0,
            thinning_split: ThinningSplit::Midpoint,
            seed: 0,
        }
    }
}

impl FacadeParams {
    /// Range checks: (field, what is wrong and what to do) for every bad field.
    pub fn validate(&self) -> Result<(), Vec<(String, String)>> {
        let mut errs: Vec<(String, String)> = Vec::new();
        let mut check = |ok: bool, field: &str, msg: String| {
            if !ok {
                errs.push((field.to_string(), msg));
            }
        };
        let pos = |v: f64| v.is_finite() && v > 0.0;
        check(
            pos(self.max_angle_deg) && self.max_angle_deg <= 90.0,
            "max_angle_deg",
            format!("must be in (0, 90] degrees, got {}", self.max_angle_deg),
        );
        check(
            pos(self.inlier_band_m) && self.inlier_band_m <= 10.0,
            "inlier_band_m",
            format!("must be in (0, 10] m, got {}", self.inlier_band_m),
        );
        check(
            pos(self.max_centre_offset_m),
            "max_centre_offset_m",
            format!("must be finite and > 0 m, got {}", self.max_centre_offset_m),
        );
        check(
            self.min_points >= 3,
            "min_points",
            format!(
                "must be ≥ 3 (a plane needs 3 points), got {}",
                self.min_points
            ),
        );
        check(
            (1..=1_000_000).contains(&self.mlesac_max_trials),
            "mlesac_max_trials",
            format!("must be in [1, 1000000], got {}", self.mlesac_max_trials),
        );
        check(
            self.mlesac_confidence > 0.0 && self.mlesac_confidence < 1.0,
            "mlesac_confidence",
            format!(
                "must be in (0, 1), e.g. 0.99, got {}",
                self.mlesac_confidence
            ),
        );
        check(
            (1..=100).contains(&self.mlesac_em_iterations),
            "mlesac_em_iterations",
            format!("must be in [1, 100], got {}", self.mlesac_em_iterations),
        );
        check(
            (1..=10).contains(&self.max_planes_per_side),
            "max_planes_per_side",
            format!("must be in [1, 10], got {}", self.max_planes_per_side),
        );
        check(
            pos(self.max_collinearity_deviation_m),
            "max_collinearity_deviation_m",
            format!(
                "must be finite and > 0 m, got {}",
                self.max_collinearity_deviation_m
            ),
        );
        check(
            self.min_triplet_span_m.is_finite() && self.min_triplet_span_m >= 0.0,
            "min_triplet_span_m",
            format!("must be finite and ≥ 0 m, got {}", self.min_triplet_span_m),
        );
        check(
            pos(self.max_view_angle_deg) && self.max_view_angle_deg < 90.0,
            "max_view_angle_deg",
            format!(
                "must be in (0, 90) degrees, got {}",
                self.max_view_angle_deg
            ),
        );
        check(
            pos(self.max_resolution_m),
            "max_resolution_m",
            format!("must be finite and > 0 m, got {}", self.max_resolution_m),
        );
        check(
            self.thinning_max_points_per_box >= 1,
            "thinning_max_points_per_box",
            "must be ≥ 1 (1 keeps every distinct point)".to_string(),
        );
        check(
            self.thinning_max_box_m > 0.0,
            "thinning_max_box_m",
            format!(
                "must be > 0 m (inf for count-only boxes), got {}",
                self.thinning_max_box_m
            ),
        );
        if errs.is_empty() {
            Ok(())
        } else {
            Err(errs)
        }
    }
}

//! Parameters of the sparse-cloud stage (thesis 4.4.1) with units, defaults and range checks.

use crate::features::agast::AgastParams;
use crate::features::daisy::DaisyParams;
use crate::oblique::types::StreetSide;
use crate::params::Violation;

crate::params! {
    /// Everything the sparse cloud of a panorama triplet can be told.
    pub struct SparseCloudParams {
        /// Width = height of each perspective view.
        view_width_px: u32 = 512, unit "px", min 64, max 8192;
        /// Vertical field of view of the views (thesis eq. 4/1).
        vfov_deg: f64 = 90.0, unit "deg", above 1.0, below 170.0;
        /// Elevation of the views' optical axes above the horizon (thesis: 30°).
        pitch_deg: f64 = 30.0, unit "deg", above -90.0, below 90.0;
        /// Yaw deviations from the driving direction of views 1, 2, 3 on the left side (thesis fig. 4.3); the
        /// right side uses 360° minus these.
        left_yaw_deviations_deg: [f64; 3] = [300.0, 270.0, 240.0], unit "deg";
        /// AGAST corner detector (threshold on the 0..255 scale).
        agast: AgastParams = AgastParams::default(), section;
        /// DAISY descriptor.
        daisy: DaisyParams = DaisyParams::default(), section;
        /// Lowe ratio of nearest to second-nearest descriptor distance.
        match_ratio: f32 = 0.8, above 0.0, max 1.0;
        /// Keep only mutual nearest neighbours.
        mutual: bool = true;
        /// Guided matching: a feature of view 2 (3) is a candidate for a feature of view 1 (2) only within this
        /// distance of the epipolar segment holding the object points between `min_depth_m` and `max_range_m`
        /// along the first feature's ray. Absent = every feature is compared with every feature.
        epipolar_tolerance_px: Option<f64> = Some(8.0), unit "px", above 0.0;
        /// Nearest object distance considered by guided matching; below `max_range_m`.
        min_depth_m: f64 = 2.0, unit "m", above 0.0;
        /// Largest trifocal transfer error (1, 2 → 3) of a kept track.
        trifocal_tolerance_px: f64 = 2.0, unit "px", above 0.0;
        /// Measure the outer recordings' positions relative to the centre recording from the triplet's own
        /// tracks before matching for the cloud (`oblique::sparse_cloud::relative_pose`), instead of trusting
        /// the recorded relative positions: in a GNSS outage consecutive recordings can be off relative to each
        /// other by decimetres, and the trifocal check then rejects the right tracks.
        relative_pose: bool = true;
        /// Epipolar tolerance of the wide first matching whose tracks measure the relative positions (with
        /// the default 512-px, 90° views 32 px ≈ 5.6°: a relative error of 1 m for a point 10 m away). Without
        /// `epipolar_tolerance_px` that matching is unguided too.
        pose_epipolar_tolerance_px: f64 = 32.0, unit "px", above 0.0, max 512.0;
        /// σ per axis of the prior holding the outer positions at the recorded ones where the tracks say little
        /// (the triplet's scale; directions the façades leave weak).
        pose_prior_sigma_m: f64 = 0.5, unit "m", above 0.0;
        /// Fewest tracks (both sides) that must agree with the measured positions within
        /// `trifocal_tolerance_px` for them to be used.
        pose_min_tracks: usize = 12, min 3;
        /// A measured correction of an outer recording larger than this is not believed; the recorded
        /// positions are kept.
        pose_max_correction_m: f64 = 2.0, unit "m", above 0.0;
        /// Smallest maximum ray intersection angle of a kept point.
        min_intersection_angle_deg: f64 = 2.0, unit "deg", min 0.0, below 90.0;
        /// Points farther than this from the centre recording are dropped.
        max_range_m: f64 = 30.0, unit "m", above 0.0;
        /// Largest distance of a ray from its triangulated point.
        max_ray_residual_m: f64 = 0.30, unit "m", above 0.0;
        /// Standard deviation of a panorama observation (triangulation weights).
        pano_sigma_px: f64 = 0.5, unit "px", above 0.0;
        /// Seed for randomised steps (none at present; part of the cache key).
        seed: u64 = 0;
    }
    check(p, v) {
        crate::params::check_finite("left_yaw_deviations_deg", &p.left_yaw_deviations_deg, v);
        if p.max_range_m > 0.0 && p.min_depth_m >= p.max_range_m {
            v.push(Violation::new(
                "min_depth_m",
                format!(
                    "must be below max_range_m ({} m), got {}",
                    p.max_range_m, p.min_depth_m
                ),
            ));
        }
    }
}

impl SparseCloudParams {
    /// Yaw deviations of views 1, 2, 3 for a side, degrees.
    pub fn yaw_deviations_deg(&self, side: StreetSide) -> [f64; 3] {
        match side {
            StreetSide::Left => self.left_yaw_deviations_deg,
            StreetSide::Right => self.left_yaw_deviations_deg.map(|d| 360.0 - d),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_side_yaws_mirror_the_left_ones() {
        // Validity of the defaults, the TOML round trip and unknown keys: `assert_declaration_sound`.
        let p = SparseCloudParams::default();
        assert_eq!(p.yaw_deviations_deg(StreetSide::Right), [60.0, 90.0, 120.0]);
    }

    #[test]
    fn validate_names_every_bad_field() {
        let p = SparseCloudParams {
            view_width_px: 10,
            match_ratio: 1.5,
            max_range_m: f64::NAN,
            ..SparseCloudParams::default()
        };
        let fields = crate::params::violated_fields(&p);
        assert_eq!(fields, ["view_width_px", "match_ratio", "max_range_m"]);
    }
}

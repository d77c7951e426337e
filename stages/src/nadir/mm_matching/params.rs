//! Parameters of MM-to-MM matching (thesis 3.4.4) with units, defaults and range checks.
//!
//! Lengths in `px` are pixels of the ortho images (3 cm by default); lengths in `m` are metres on the ground.
//! Defaults follow the thesis where it gives a value (KAZE upright with one octave, RANSAC homography, 30 cm
//! centre check — 3.4.4.2); the reasoning behind the others is in `docs/method.md`.

crate::params! {
    /// Everything MM-to-MM matching can be told.
    pub struct MmMatchParams {
        /// KAZE detector threshold on the scale-normalised det(Hessian) of the 0..1 ortho image. KAZE runs
        /// upright with one octave (thesis 3.4.4.2).
        kaze_threshold: f32 = 3e-5, above 0.0;
        /// KAZE sub-levels of the single octave.
        kaze_sublevels: usize = 4, min 3, max 16;
        /// KAZE keypoints with a masked (vehicle) pixel within this distance are ignored.
        kaze_mask_margin_px: f32 = 16.0, unit "px", min 0.0, max 200.0;
        /// Lowe ratio of the nearest to the second-nearest descriptor distance.
        kaze_ratio: f32 = 0.9, above 0.0, max 1.0;
        /// KAZE matches whose displacement differs from the one the recorded poses predict by more than this are
        /// dropped before RANSAC; 0 disables the check.
        kaze_prior_window_m: f64 = 2.0, unit "m", min 0.0;
        /// RANSAC inlier threshold on the one-way transfer error, in ortho pixels.
        ransac_threshold_px: f64 = 3.0, unit "px", above 0.0, max 100.0;
        /// RANSAC maximum number of samples.
        ransac_max_iterations: usize = 2000, min 1, max 1_000_000;
        /// Fewest RANSAC inliers for a KAZE homography to be accepted (a homography needs 4).
        min_inliers: usize = 8, min 4;
        /// Centre check (thesis 3.4.4.2): the distance between the mapped detecting centre and the neighbour's
        /// centre may differ from the recorded horizontal distance of the two poses by at most this.
        verify_tolerance_m: f64 = 0.30, unit "m", above 0.0;
        /// Largest deviation of a KAZE homography from a pure translation (plus the poses' common rotation and
        /// scale), measured at `max_corner_distance_m` from the centre.
        max_homography_distortion_m: f64 = 0.5, unit "m", above 0.0;
        /// Förstner: σ of the derivative-of-Gaussian gradient, in ortho pixels.
        forstner_sigma_gradient_px: f32 = 0.7, unit "px", above 0.0, max 50.0;
        /// Förstner: σ of the tensor integration window, in ortho pixels.
        forstner_sigma_integration_px: f32 = 2.0, unit "px", above 0.0, max 50.0;
        /// Förstner: minimum roundness q.
        forstner_min_roundness: f32 = 0.5, min 0.0, max 1.0;
        /// Förstner: minimum weight as a multiple of the image's mean weight.
        forstner_min_weight_rel: f32 = 3.0, min 0.0;
        /// Förstner: non-maximum suppression radius, in ortho pixels.
        forstner_nms_radius_px: f32 = 4.0, unit "px", above 0.0, max 50.0;
        /// At most this many corners per detecting image, strongest first, after the mask and distance filters.
        max_corners: usize = 300, min 1, max 100_000;
        /// Corners farther than this from the detecting camera's foot point are not used.
        max_corner_distance_m: f64 = 9.0, unit "m", above 0.0;
        /// Half side h of the square NCC template: the template is (2·h + 1)² ortho pixels.
        template_half_px: usize = 10, unit "px", min 2, max 64;
        /// Search radius around the transferred corner when the pair transform is a verified KAZE homography.
        search_radius_px: usize = 6, unit "px", min 1, max 64;
        /// Search radius when the pair transform comes from the recorded poses (fallback).
        fallback_search_radius_px: usize = 16, unit "px", min 1, max 128;
        /// Lowest accepted NCC peak value.
        min_ncc: f32 = 0.8, above -1.0, max 1.0;
        /// Back-matching check: the neighbour's template at the located position, matched back into the
        /// detecting image, must land within this distance of the corner.
        max_backmatch_px: f64 = 1.0, unit "px", above 0.0, max 32.0;
        /// Second verification (thesis 3.4.4.4): the refined location must lie within this distance of the
        /// transferred one after removing the pair's median offset.
        corner_tolerance_px: f64 = 3.0, unit "px", above 0.0;
        /// Standard deviation of a panorama observation, for the triangulation weights.
        pano_sigma_px: f64 = 0.5, unit "px", above 0.0;
        /// Tie points with a ray farther than this from the triangulated point are rejected (of three rays the
        /// worst one is dropped first).
        max_ray_residual_m: f64 = 0.30, unit "m", above 0.0;
        /// Tie points whose rays intersect at a smaller angle are rejected.
        min_intersection_angle_deg: f64 = 2.0, unit "deg", min 0.0, below 90.0;
        /// Seed of the RANSAC sampling; each pair derives its own seed from it and the two image ids.
        seed: u64 = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    #[test]
    fn defaults_are_valid_and_round_trip_through_toml() {
        let p = MmMatchParams::default();
        assert_eq!(p.validate(), Ok(()));
        let text = toml::to_string(&p).unwrap();
        let back: MmMatchParams = toml::from_str(&text).unwrap();
        assert_eq!(back, p);
        let partial: MmMatchParams = toml::from_str("min_ncc = 0.7").unwrap();
        assert_eq!(partial.min_ncc, 0.7);
        assert_eq!(partial.search_radius_px, p.search_radius_px);
        assert!(toml::from_str::<MmMatchParams>("min_nc = 0.7").is_err());
    }

    #[test]
    fn validate_names_every_bad_field() {
        let p = MmMatchParams {
            min_inliers: 3,
            verify_tolerance_m: -1.0,
            template_half_px: 0,
            min_ncc: 2.0,
            max_ray_residual_m: f64::NAN,
            ..MmMatchParams::default()
        };
        let errs = p.validate().unwrap_err();
        let fields: Vec<&str> = errs.iter().map(|v| v.field.as_str()).collect();
        assert_eq!(
            fields,
            [
                "min_inliers",
                "verify_tolerance_m",
                "template_half_px",
                "min_ncc",
                "max_ray_residual_m"
            ]
        );
        assert!(errs[0].message.contains("got 3"));
    }
}

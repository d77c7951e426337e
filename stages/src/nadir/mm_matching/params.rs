//! Parameters of MM-to-MM matching (thesis 3.4.4) with units, defaults and range checks.
//!
//! Lengths in `_px` are pixels of the 3 cm ortho images (campaign-format.md pixel convention); lengths in
//! `_m` are metres on the ground. Defaults follow the thesis where it gives a value (KAZE upright with one
//! octave, RANSAC homography, 30 cm centre check — 3.4.4.2) and were chosen on the synthetic campaigns
//! elsewhere (stated per field).

use serde::{Deserialize, Serialize};

/// Everything MM-to-MM matching can be told.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MmMatchParams {
    /// KAZE detector threshold on the scale-normalised det(Hessian) of the 0..1 ortho image (default 3e-5:
    /// OpenCV's 0.001 finds no keypoints in 3 cm orthos of 1024-px panoramas, which are smooth because the
    /// ortho is finer than its source; on the demo campaign 3e-5 takes the KAZE path for 57 of 75 pairs,
    /// 1e-4 for 23). KAZE runs upright with one octave (thesis 3.4.4.2).
    pub kaze_threshold: f32,
    /// KAZE sub-levels of the single octave (default 4).
    pub kaze_sublevels: usize,
    /// KAZE keypoints with a masked (vehicle) pixel within this many ortho px are ignored (default 16 px;
    /// the M-SURF descriptor reaches ≈ 12 σ around the keypoint).
    pub kaze_mask_margin_px: f32,
    /// Lowe ratio of the nearest to the second-nearest descriptor distance (default 0.9; permissive because
    /// matches must also be mutual nearest neighbours, agree with the recorded poses and pass RANSAC and the
    /// centre check).
    pub kaze_ratio: f32,
    /// KAZE matches whose displacement disagrees with the one predicted by the recorded poses by more than
    /// this are dropped before RANSAC, metres (default 2.0 m — generous against GNSS errors, but it removes
    /// the repeated-pattern matches of zebra crossings and dashed lines one period away). 0 disables it.
    pub kaze_prior_window_m: f64,
    /// RANSAC inlier threshold on the one-way transfer error, ortho px (default 3 px = 9 cm at 3 cm GSD).
    pub ransac_threshold_px: f64,
    /// RANSAC maximum number of samples (default 2000).
    pub ransac_max_iterations: usize,
    /// Fewest RANSAC inliers for a KAZE homography to be accepted (default 8; the centre check guards
    /// against a weakly determined homography).
    pub min_inliers: usize,
    /// Centre check (thesis 3.4.4.2): |distance between the mapped detecting centre and the neighbour's
    /// centre − recorded horizontal inter-pose distance| must not exceed this, metres (default 0.30 m).
    pub verify_tolerance_m: f64,
    /// A KAZE homography must stay within this distance of a pure translation (plus the poses' common
    /// rotation and scale) at `max_corner_distance_m` from the centre, metres (default 0.5 m). Adjacent
    /// orthos share rotation and scale (thesis 3.4.4.2); a strongly projective homography is an extrapolation
    /// from keypoints in one part of the image. On the demo campaign 0.3 m keeps 20 of 75 pairs on the KAZE
    /// path (true-pose rays meet within 5 cm for 99.9 % of the tie points), no check keeps 57 (99.3 %).
    pub max_homography_distortion_m: f64,
    /// Förstner: σ of the derivative-of-Gaussian gradient, ortho px (default 0.7).
    pub forstner_sigma_gradient_px: f32,
    /// Förstner: σ of the tensor integration window, ortho px (default 2.0).
    pub forstner_sigma_integration_px: f32,
    /// Förstner: minimum roundness q in [0, 1] (default 0.5).
    pub forstner_min_roundness: f32,
    /// Förstner: minimum weight as a multiple of the image's mean weight (default 3.0: favours the contrasty
    /// corners of road markings, which the aerial stages can find as well, over asphalt texture).
    pub forstner_min_weight_rel: f32,
    /// Förstner: non-maximum suppression radius, ortho px (default 4).
    pub forstner_nms_radius_px: f32,
    /// At most this many corners per detecting image, strongest first, after the mask and distance filters
    /// (default 300).
    pub max_corners: usize,
    /// Corners farther than this from the detecting camera's foot point are not used, metres (default 9 m:
    /// beyond it the 3 cm ortho image is much finer than the panorama it was sampled from).
    pub max_corner_distance_m: f64,
    /// Half size of the square NCC template, ortho px: the template is (2·h + 1)² (default 10 ⇒ 21 × 21 px,
    /// 63 cm).
    pub template_half_px: usize,
    /// Search radius around the transferred corner when the pair transform is a verified KAZE homography,
    /// ortho px (default 6 px = 18 cm: covers the parallax of non-flat ground).
    pub search_radius_px: usize,
    /// Search radius when the pair transform comes from the recorded poses (fallback), ortho px (default
    /// 16 px = 48 cm: the relative pose error is not removed then).
    pub fallback_search_radius_px: usize,
    /// Lowest accepted NCC peak value (default 0.8).
    pub min_ncc: f32,
    /// Back-matching check: the neighbour's template at the located position, matched back into the detecting
    /// image, must land within this distance of the corner, ortho px (default 1.0 px). Rejects the
    /// asymmetric matches that blur differences between a near and a far panorama produce.
    pub max_backmatch_px: f64,
    /// Second verification (thesis 3.4.4.4): the refined location must lie within this distance of the
    /// transferred one after removing the pair's median offset, ortho px (default 3 px = 9 cm).
    pub corner_tolerance_px: f64,
    /// Standard deviation of a panorama observation, panorama px, for the triangulation weights (default 0.5).
    pub pano_sigma_px: f64,
    /// Tie points with a ray farther than this from the triangulated point are rejected (for three rays the
    /// worst ray is dropped first), metres (default 0.30 m: the recorded poses carry relative errors of
    /// decimetres, which this check must tolerate).
    pub max_ray_residual_m: f64,
    /// Tie points whose rays intersect at less than this angle are rejected, degrees (default 2°).
    pub min_intersection_angle_deg: f64,
    /// Seed of the RANSAC sampling; each pair derives its own seed from it and the two image ids.
    pub seed: u64,
}

impl Default for MmMatchParams {
    fn default() -> Self {
        Self {
            kaze_threshold: 3e-5,
            kaze_sublevels: 4,
            kaze_mask_margin_px: 16.0,
            kaze_ratio: 0.9,
            kaze_prior_window_m: 2.0,
            ransac_threshold_px: 3.0,
            ransac_max_iterations: 2000,
            min_inliers: 8,
            verify_tolerance_m: 0.30,
            max_homography_distortion_m: 0.5,
            forstner_sigma_gradient_px: 0.7,
            forstner_sigma_integration_px: 2.0,
            forstner_min_roundness: 0.5,
            forstner_min_weight_rel: 3.0,
            forstner_nms_radius_px: 4.0,
            max_corners: 300,
            max_corner_distance_m: 9.0,
            template_half_px: 10,
            search_radius_px: 6,
            fallback_search_radius_px: 16,
            min_ncc: 0.8,
            max_backmatch_px: 1.0,
            corner_tolerance_px: 3.0,
            pano_sigma_px: 0.5,
            max_ray_residual_m: 0.30,
            min_intersection_angle_deg: 2.0,
            seed: 0,
        }
    }
}

impl MmMatchParams {
    /// Check ranges; each error is (field, message with the allowed range).
    pub fn validate(&self) -> Result<(), Vec<(String, String)>> {
        let mut errs: Vec<(String, String)> = Vec::new();
        let mut check = |ok: bool, field: &str, msg: String| {
            if !ok {
                errs.push((field.to_string(), msg));
            }
        };
        let pos = |v: f64| v.is_finite() && v > 0.0;
        check(
            self.kaze_threshold.is_finite() && self.kaze_threshold > 0.0,
            "kaze_threshold",
            format!("must be finite and > 0, got {}", self.kaze_threshold),
        );
        check(
            (3..=16).contains(&self.kaze_sublevels),
            "kaze_sublevels",
            format!("must be in [3, 16], got {}", self.kaze_sublevels),
        );
        check(
            self.kaze_mask_margin_px.is_finite()
                && (0.0..=200.0).contains(&self.kaze_mask_margin_px),
            "kaze_mask_margin_px",
            format!("must be in [0, 200] px, got {}", self.kaze_mask_margin_px),
        );
        check(
            self.kaze_ratio.is_finite() && self.kaze_ratio > 0.0 && self.kaze_ratio <= 1.0,
            "kaze_ratio",
            format!("must be in (0, 1], got {}", self.kaze_ratio),
        );
        check(
            self.kaze_prior_window_m.is_finite() && self.kaze_prior_window_m >= 0.0,
            "kaze_prior_window_m",
            format!(
                "must be ≥ 0 m (0 disables), got {}",
                self.kaze_prior_window_m
            ),
        );
        check(
            pos(self.ransac_threshold_px) && self.ransac_threshold_px <= 100.0,
            "ransac_threshold_px",
            format!("must be in (0, 100] px, got {}", self.ransac_threshold_px),
        );
        check(
            (1..=1_000_000).contains(&self.ransac_max_iterations),
            "ransac_max_iterations",
            format!(
                "must be in [1, 1000000], got {}",
                self.ransac_max_iterations
            ),
        );
        check(
            self.min_inliers >= 4,
            "min_inliers",
            format!(
                "must be ≥ 4 (a homography needs 4 pairs), got {}",
                self.min_inliers
            ),
        );
        check(
            pos(self.verify_tolerance_m),
            "verify_tolerance_m",
            format!("must be finite and > 0 m, got {}", self.verify_tolerance_m),
        );
        check(
            pos(self.max_homography_distortion_m),
            "max_homography_distortion_m",
            format!(
                "must be finite and > 0 m, got {}",
                self.max_homography_distortion_m
            ),
        );
        for (field, v) in [
            (
                "forstner_sigma_gradient_px",
                self.forstner_sigma_gradient_px,
            ),
            (
                "forstner_sigma_integration_px",
                self.forstner_sigma_integration_px,
            ),
            ("forstner_nms_radius_px", self.forstner_nms_radius_px),
        ] {
            check(
                v.is_finite() && v > 0.0 && v <= 50.0,
                field,
                format!("must be in (0, 50] px, got {v}"),
            );
        }
        check(
            (0.0..=1.0).contains(&self.forstner_min_roundness),
            "forstner_min_roundness",
            format!("must be in [0, 1], got {}", self.forstner_min_roundness),
        );
        check(
            self.forstner_min_weight_rel.is_finite() && self.forstner_min_weight_rel >= 0.0,
            "forstner_min_weight_rel",
            format!("must be ≥ 0, got {}", self.forstner_min_weight_rel),
        );
        check(
            (1..=100_000).contains(&self.max_corners),
            "max_corners",
            format!("must be in [1, 100000], got {}", self.max_corners),
        );
        check(
            pos(self.max_corner_distance_m),
            "max_corner_distance_m",
            format!(
                "must be finite and > 0 m, got {}",
                self.max_corner_distance_m
            ),
        );
        check(
            (2..=64).contains(&self.template_half_px),
            "template_half_px",
            format!("must be in [2, 64] px, got {}", self.template_half_px),
        );
        check(
            (1..=64).contains(&self.search_radius_px),
            "search_radius_px",
            format!("must be in [1, 64] px, got {}", self.search_radius_px),
        );
        check(
            (1..=128).contains(&self.fallback_search_radius_px),
            "fallback_search_radius_px",
            format!(
                "must be in [1, 128] px, got {}",
                self.fallback_search_radius_px
            ),
        );
        check(
            self.min_ncc.is_finite() && self.min_ncc > -1.0 && self.min_ncc <= 1.0,
            "min_ncc",
            format!("must be in (-1, 1], got {}", self.min_ncc),
        );
        check(
            pos(self.max_backmatch_px) && self.max_backmatch_px <= 32.0,
            "max_backmatch_px",
            format!("must be in (0, 32] px, got {}", self.max_backmatch_px),
        );
        check(
            pos(self.corner_tolerance_px),
            "corner_tolerance_px",
            format!(
                "must be finite and > 0 px, got {}",
                self.corner_tolerance_px
            ),
        );
        check(
            pos(self.pano_sigma_px),
            "pano_sigma_px",
            format!("must be finite and > 0 px, got {}", self.pano_sigma_px),
        );
        check(
            pos(self.max_ray_residual_m),
            "max_ray_residual_m",
            format!("must be finite and > 0 m, got {}", self.max_ray_residual_m),
        );
        check(
            self.min_intersection_angle_deg.is_finite()
                && (0.0..90.0).contains(&self.min_intersection_angle_deg),
            "min_intersection_angle_deg",
            format!(
                "must be in [0, 90) degrees, got {}",
                self.min_intersection_angle_deg
            ),
        );
        if errs.is_empty() {
            Ok(())
        } else {
            Err(errs)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let fields: Vec<&str> = errs.iter().map(|(f, _)| f.as_str()).collect();
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
        assert!(errs[0].1.contains("got 3"));
    }
}

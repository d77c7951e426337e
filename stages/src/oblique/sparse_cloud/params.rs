//! Parameters of the sparse-cloud stage (thesis 4.4.1) with units, defaults and range checks.

use crate::features::agast::AgastParams;
use crate::features::daisy::DaisyParams;
use crate::oblique::types::StreetSide;
use serde::{Deserialize, Serialize};

/// Everything the sparse cloud of a panorama triplet can be told.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SparseCloudParams {
    /// Width = height of each perspective view, px (default 512: with `vfov_deg` 90° the view's centre pixel
    /// spans 0.18°, about the 0.225° of the 1600-px synthetic panoramas; the thesis' 4800-px panoramas would
    /// match ≈ 1530 px).
    pub view_width_px: u32,
    /// Vertical field of view of the views, degrees (eq. 4/1; default 90°).
    pub vfov_deg: f64,
    /// Elevation of the views' optical axes above the horizon, degrees (thesis: 30°).
    pub pitch_deg: f64,
    /// Yaw deviations from the driving direction (`heading`) of views 1, 2, 3 on the left side, degrees
    /// (thesis fig. 4.3: 300°, 270°, 240°); the right side uses 360° minus these (60°, 90°, 120°).
    pub left_yaw_deviations_deg: [f64; 3],
    /// AGAST corner detector (threshold on the 0..255 scale).
    pub agast: AgastParams,
    /// DAISY descriptor.
    pub daisy: DaisyParams,
    /// Lowe ratio of nearest to second-nearest descriptor distance (default 0.8).
    pub match_ratio: f32,
    /// Keep only mutual nearest neighbours (default true).
    pub mutual: bool,
    /// Guided matching: a feature of view 2 (3) is a candidate for a feature of view 1 (2) only if it lies
    /// within this distance of the segment of the epipolar line that holds the object points between
    /// `min_depth_m` and `max_range_m` along the first feature's ray, view px; computed from the recorded
    /// poses, so it must cover their relative error (≈ 0.14 m between neighbours at 10 m ≈ 4 px for the
    /// default views). `None` compares every feature with every feature (plain ratio matching).
    pub epipolar_tolerance_px: Option<f64>,
    /// Nearest object distance considered by guided matching, metres (default 2 m).
    pub min_depth_m: f64,
    /// Largest trifocal transfer error (1, 2 → 3) of a kept track, view px (default 2 px).
    pub trifocal_tolerance_px: f64,
    /// Smallest maximum ray intersection angle of a kept point, degrees (default 2°).
    pub min_intersection_angle_deg: f64,
    /// Points farther than this from the centre recording are dropped, metres (default 30 m: façades).
    pub max_range_m: f64,
    /// Largest distance of a ray from its triangulated point, metres (default 0.30 m, as the nadir MM
    /// matching: the recorded poses carry relative errors of decimetres).
    pub max_ray_residual_m: f64,
    /// Standard deviation of a panorama observation, panorama px (triangulation weights; default 0.5).
    pub pano_sigma_px: f64,
    /// Seed for randomised steps (none at present; part of the cache key).
    pub seed: u64,
}

impl Default for SparseCloudParams {
    fn default() -> Self {
        Self {
            view_width_px: 512,
            vfov_deg: 90.0,
            pitch_deg: 30.0,
            left_yaw_deviations_deg: [300.0, 270.0, 240.0],
            agast: AgastParams::default(),
            daisy: DaisyParams::default(),
            match_ratio: 0.8,
            mutual: true,
            epipolar_tolerance_px: Some(8.0),
            min_depth_m: 2.0,
            trifocal_tolerance_px: 2.0,
            min_intersection_angle_deg: 2.0,
            max_range_m: 30.0,
            max_ray_residual_m: 0.30,
            pano_sigma_px: 0.5,
            seed: 0,
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
            (64..=8192).contains(&self.view_width_px),
            "view_width_px",
            format!("must be in [64, 8192] px, got {}", self.view_width_px),
        );
        check(
            self.vfov_deg.is_finite() && self.vfov_deg > 1.0 && self.vfov_deg < 170.0,
            "vfov_deg",
            format!("must be in (1, 170) degrees, got {}", self.vfov_deg),
        );
        check(
            self.pitch_deg.is_finite() && self.pitch_deg.abs() < 90.0,
            "pitch_deg",
            format!("must be in (-90, 90) degrees, got {}", self.pitch_deg),
        );
        check(
            self.left_yaw_deviations_deg.iter().all(|d| d.is_finite()),
            "left_yaw_deviations_deg",
            format!(
                "must be finite degrees, got {:?}",
                self.left_yaw_deviations_deg
            ),
        );
        if let Err(e) = self.agast.validate() {
            errs.extend(e.into_iter().map(|(f, m)| (format!("agast.{f}"), m)));
        }
        if let Err(e) = self.daisy.validate() {
            errs.extend(e.into_iter().map(|(f, m)| (format!("daisy.{f}"), m)));
        }
        let mut check = |ok: bool, field: &str, msg: String| {
            if !ok {
                errs.push((field.to_string(), msg));
            }
        };
        check(
            self.match_ratio.is_finite() && self.match_ratio > 0.0 && self.match_ratio <= 1.0,
            "match_ratio",
            format!("must be in (0, 1], got {}", self.match_ratio),
        );
        check(
            self.epipolar_tolerance_px.is_none_or(pos),
            "epipolar_tolerance_px",
            format!(
                "must be finite and > 0 px (or left out for unguided matching), got {:?}",
                self.epipolar_tolerance_px
            ),
        );
        check(
            // (a bad max_range_m is reported on its own)
            pos(self.min_depth_m)
                && (self.min_depth_m < self.max_range_m || !pos(self.max_range_m)),
            "min_depth_m",
            format!(
                "must be > 0 m and below max_range_m ({} m), got {}",
                self.max_range_m, self.min_depth_m
            ),
        );
        check(
            pos(self.trifocal_tolerance_px),
            "trifocal_tolerance_px",
            format!(
                "must be finite and > 0 px, got {}",
                self.trifocal_tolerance_px
            ),
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
        check(
            pos(self.max_range_m),
            "max_range_m",
            format!("must be finite and > 0 m, got {}", self.max_range_m),
        );
        check(
            pos(self.max_ray_residual_m),
            "max_ray_residual_m",
            format!("must be finite and > 0 m, got {}", self.max_ray_residual_m),
        );
        check(
            pos(self.pano_sigma_px),
            "pano_sigma_px",
            format!("must be finite and > 0 px, got {}", self.pano_sigma_px),
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
        let p = SparseCloudParams::default();
        assert_eq!(p.validate(), Ok(()));
        let text = toml::to_string(&p).unwrap();
        let back: SparseCloudParams = toml::from_str(&text).unwrap();
        assert_eq!(back, p);
        assert!(toml::from_str::<SparseCloudParams>("match_ratoi = 0.7").is_err());
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
        let fields: Vec<String> = p.validate().unwrap_err().into_iter().map(|e| e.0).collect();
        assert_eq!(fields, ["view_width_px", "match_ratio", "max_range_m"]);
    }
}

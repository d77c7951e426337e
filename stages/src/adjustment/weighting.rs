//! Residual weighting of panorama observations, methods 1–4 of thesis 5.7 (Table 5-10).
//!
//! A panorama's ground sampling distance varies strongly with the distance d(c, X) between the camera and the
//! observed point, so the thesis scales the reprojection residual d(x, x̂) (pixels) by a factor:
//! 1. unweighted: `r = d(x, x̂)`;
//! 2. near-weighted: `r = (l − d(c,X)) / l · d(x, x̂)`;
//! 3. far-weighted: `r = (1 − (l − d(c,X)) / l) · d(x, x̂)`;
//! 4. GSD-weighted: `r = d(x, x̂) / (π · d(c,X) · α / 180)`;
//!
//! with d(c, X) and the maximum correspondence distance l in centimetres (l = 15 m in the thesis) and α the
//! angular resolution of the panorama in degrees (0.075° in the thesis). Method 2 gives weight 0 to points at
//! or beyond l (the thesis: "does not use these points"); we clamp it at 0 rather than letting it turn negative.
//! The factor multiplies the whitened residual (pixel residual / σ_px); it is evaluated once per solve from the
//! initial distances and then held fixed, so each solve is an ordinary weighted least-squares problem.

use super::error::AdjustError;
use std::f64::consts::PI;

/// Which of the thesis' four residual weightings (5.7) to apply.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WeightingMethod {
    /// Method 1: residuals are not weighted.
    #[default]
    Unweighted,
    /// Method 2: residuals closer to the camera are weighted higher.
    NearWeighted,
    /// Method 3: residuals further from the camera are weighted higher.
    FarWeighted,
    /// Method 4: residuals weighted by the ground sampling distance of the observation.
    GsdWeighted,
}

/// A weighting method with its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResidualWeighting {
    pub method: WeightingMethod,
    /// Maximum correspondence distance l, metres (thesis: 15 m).
    pub max_distance_m: f64,
    /// Angular resolution α of the panorama, degrees; `None` = from the image width (360°/W).
    pub angular_resolution_deg: Option<f64>,
}

impl Default for ResidualWeighting {
    fn default() -> Self {
        Self {
            method: WeightingMethod::Unweighted,
            max_distance_m: 15.0,
            angular_resolution_deg: None,
        }
    }
}

impl ResidualWeighting {
    /// A weighting with the thesis' l = 15 m and α from the image width.
    pub fn new(method: WeightingMethod) -> Self {
        Self {
            method,
            ..Self::default()
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), AdjustError> {
        if !(self.max_distance_m.is_finite() && self.max_distance_m > 0.0) {
            return Err(AdjustError::InvalidOption {
                field: "weighting.max_distance_m",
                value: self.max_distance_m,
                hint: "must be finite and > 0 (thesis: 15 m)",
            });
        }
        if let Some(a) = self.angular_resolution_deg {
            if !(a.is_finite() && a > 0.0) {
                return Err(AdjustError::InvalidOption {
                    field: "weighting.angular_resolution_deg",
                    value: a,
                    hint: "must be finite and > 0, or absent to use 360°/width",
                });
            }
        }
        Ok(())
    }

    /// The factor multiplying the residual of an observation at `distance_m` from the camera, for a
    /// panorama whose angular resolution is `image_resolution_deg` (used when no α is configured).
    pub fn factor(&self, distance_m: f64, image_resolution_deg: f64) -> f64 {
        let alpha_deg = self.angular_resolution_deg.unwrap_or(image_resolution_deg);
        residual_factor(self.method, distance_m, self.max_distance_m, alpha_deg)
    }
}

/// The thesis 5.7 factor for `method` at camera–point distance `distance_m`, maximum distance
/// `max_distance_m` (l) and angular resolution `alpha_deg` (distances converted to centimetres as in the
/// thesis; only method 4 depends on the unit).
pub fn residual_factor(
    method: WeightingMethod,
    distance_m: f64,
    max_distance_m: f64,
    alpha_deg: f64,
) -> f64 {
    let d_cm = distance_m * 100.0;
    let l_cm = max_distance_m * 100.0;
    match method {
        WeightingMethod::Unweighted => 1.0,
        WeightingMethod::NearWeighted => ((l_cm - d_cm) / l_cm).max(0.0),
        WeightingMethod::FarWeighted => 1.0 - (l_cm - d_cm) / l_cm,
        WeightingMethod::GsdWeighted => 1.0 / (PI * d_cm * alpha_deg / 180.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Thesis Table 5-10 (l = 15 m, α = 0.075°): distance, method 2, method 3, method 4. The table prints
    /// two decimals (method 2/3 truncated, e.g. 0.0667 → 0.06; method 4 rounded), hence the 0.01 tolerance.
    const TABLE_5_10: [(f64, f64, f64, f64); 5] = [
        (1.0, 0.93, 0.06, 7.64),
        (3.0, 0.8, 0.2, 2.55),
        (5.0, 0.66, 0.33, 1.53),
        (10.0, 0.33, 0.66, 0.76),
        (15.0, 0.0, 1.0, 0.51),
    ];

    #[test]
    fn reproduces_table_5_10() {
        for (d, m2, m3, m4) in TABLE_5_10 {
            let f = |m| residual_factor(m, d, 15.0, 0.075);
            assert_eq!(f(WeightingMethod::Unweighted), 1.0);
            assert!(
                (f(WeightingMethod::NearWeighted) - m2).abs() <= 0.01,
                "m2 at {d}"
            );
            assert!(
                (f(WeightingMethod::FarWeighted) - m3).abs() <= 0.01,
                "m3 at {d}"
            );
            assert!(
                (f(WeightingMethod::GsdWeighted) - m4).abs() <= 0.005 + 1e-12,
                "m4 at {d}"
            );
        }
        // Exact values behind the printed ones.
        assert!(
            (residual_factor(WeightingMethod::NearWeighted, 1.0, 15.0, 0.075) - 14.0 / 15.0).abs()
                < 1e-15
        );
        assert!(
            (residual_factor(WeightingMethod::FarWeighted, 1.0, 15.0, 0.075) - 1.0 / 15.0).abs()
                < 1e-15
        );
        let m4 = residual_factor(WeightingMethod::GsdWeighted, 1.0, 15.0, 0.075);
        assert!((m4 - 180.0 / (PI * 100.0 * 0.075)).abs() < 1e-12);
        // Beyond l the near weighting stays 0 (the thesis drops those points).
        assert_eq!(
            residual_factor(WeightingMethod::NearWeighted, 20.0, 15.0, 0.075),
            0.0
        );
    }
}

//! Grid north versus true north for a map projection: the grid azimuth of true north (meridian convergence)
//! and the point scale factor, both from the projection itself by central differences along the meridian
//! and the parallel, so they hold for every projection `proj4rs` implements.
//!
//! A direction with true azimuth `A_true` (clockwise from true north) has grid azimuth
//! `A_grid = A_true + true_north_grid_azimuth_deg`.

use super::definition::Crs;
use super::ellipsoid::Ellipsoid;
use super::transform::{HorizontalTransform, TransformError};

/// Step of the central differences, degrees of latitude/longitude (≈ 1 m; the truncation error is O(step²)).
const STEP_DEG: f64 = 1e-5;

/// Convergence and scale of one projected CRS.
#[derive(Clone)]
pub struct GridNorth {
    to_map: HorizontalTransform,
    ellipsoid: Ellipsoid,
}

impl GridNorth {
    /// `None` for a geographic CRS (no grid).
    pub fn new(crs: &Crs) -> Option<Self> {
        crs.is_projected().then(|| Self {
            to_map: HorizontalTransform::from_own_geographic(crs),
            ellipsoid: crs.ellipsoid,
        })
    }

    /// Grid azimuth of true north at (lat, lon) on the CRS's own datum, degrees clockwise from grid north
    /// (negative where true north points west of grid north).
    pub fn true_north_grid_azimuth_deg(
        &self,
        lat_deg: f64,
        lon_deg: f64,
    ) -> Result<f64, TransformError> {
        let (e1, n1) = self.to_map.apply(lat_deg - STEP_DEG, lon_deg)?;
        let (e2, n2) = self.to_map.apply(lat_deg + STEP_DEG, lon_deg)?;
        Ok((e2 - e1).atan2(n2 - n1).to_degrees())
    }

    /// Point scale factor k at (lat, lon): map distance / ellipsoid distance along the parallel (equal in all
    /// directions for the conformal projections used for mapping).
    pub fn scale_factor(&self, lat_deg: f64, lon_deg: f64) -> Result<f64, TransformError> {
        let (e1, n1) = self.to_map.apply(lat_deg, lon_deg - STEP_DEG)?;
        let (e2, n2) = self.to_map.apply(lat_deg, lon_deg + STEP_DEG)?;
        let map_m = (e2 - e1).hypot(n2 - n1);
        let ellipsoid_m = self.ellipsoid.prime_vertical_radius_m(lat_deg)
            * lat_deg.to_radians().cos()
            * (2.0 * STEP_DEG).to_radians();
        Ok(map_m / ellipsoid_m)
    }
}

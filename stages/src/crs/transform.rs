//! Horizontal transformations between CRSs (map projection, inverse projection, datum shift by the EPSG
//! definition's Helmert parameters or grids), on `proj4rs`.
//!
//! Coordinates are each CRS's "native" pair: easting, northing (m) for projected CRSs; latitude, longitude (°)
//! for geographic CRSs — always in that order, whatever axis order the EPSG register gives.

use super::definition::{Crs, HorizontalKind};
use proj4rs::Proj;

/// A latitude/longitude pair, degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geographic {
    pub lat_deg: f64,
    pub lon_deg: f64,
}

/// A point that could not be transformed (outside the projection's domain, NaN, ...).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("({a}, {b}) cannot be transformed from {from} to {to}: {reason} — check the coordinates' CRS and axis order (projected: easting, northing in m; geographic: latitude, longitude in degrees)")]
pub struct TransformError {
    pub a: f64,
    pub b: f64,
    pub from: String,
    pub to: String,
    pub reason: String,
}

/// A transformation from one CRS's native coordinates to another's.
#[derive(Clone)]
pub struct HorizontalTransform {
    from: Proj,
    to: Proj,
    from_geographic: bool,
    to_geographic: bool,
    from_name: String,
    to_name: String,
}

impl HorizontalTransform {
    /// From `from`'s native coordinates to `to`'s.
    pub fn new(from: &Crs, to: &Crs) -> Self {
        Self {
            from: from.proj.clone(),
            to: to.proj.clone(),
            from_geographic: from.kind == HorizontalKind::Geographic,
            to_geographic: to.kind == HorizontalKind::Geographic,
            from_name: format!("EPSG:{}", from.horizontal_code),
            to_name: format!("EPSG:{}", to.horizontal_code),
        }
    }

    /// From `crs`'s native coordinates to latitude/longitude on its own datum (map → geographic).
    pub fn to_own_geographic(crs: &Crs) -> Self {
        Self {
            from: crs.proj.clone(),
            to: crs.geographic.clone(),
            from_geographic: crs.kind == HorizontalKind::Geographic,
            to_geographic: true,
            from_name: format!("EPSG:{}", crs.horizontal_code),
            to_name: format!("EPSG:{} geographic", crs.horizontal_code),
        }
    }

    /// From latitude/longitude on `crs`'s own datum to its native coordinates (geographic → map).
    pub fn from_own_geographic(crs: &Crs) -> Self {
        Self {
            from: crs.geographic.clone(),
            to: crs.proj.clone(),
            from_geographic: true,
            to_geographic: crs.kind == HorizontalKind::Geographic,
            from_name: format!("EPSG:{} geographic", crs.horizontal_code),
            to_name: format!("EPSG:{}", crs.horizontal_code),
        }
    }

    /// Transform one native pair (see the module doc for the order).
    pub fn apply(&self, a: f64, b: f64) -> Result<(f64, f64), TransformError> {
        self.apply3(a, b, 0.0).map(|(x, y, _)| (x, y))
    }

    /// Transform a native pair with an ellipsoidal height (m); across datums the height follows the
    /// geocentric datum shift.
    pub fn apply3(&self, a: f64, b: f64, h_m: f64) -> Result<(f64, f64, f64), TransformError> {
        let fail = |reason: String| TransformError {
            a,
            b,
            from: self.from_name.clone(),
            to: self.to_name.clone(),
            reason,
        };
        if !a.is_finite() || !b.is_finite() {
            return Err(fail("not a finite number".into()));
        }
        let mut p = if self.from_geographic {
            if !(-90.0..=90.0).contains(&a) || !(-360.0..=360.0).contains(&b) {
                return Err(fail(
                    "latitude must lie in [−90°, 90°], longitude in [−360°, 360°]".into(),
                ));
            }
            (b.to_radians(), a.to_radians(), h_m)
        } else {
            (a, b, h_m)
        };
        proj4rs::transform::transform(&self.from, &self.to, &mut p)
            .map_err(|e| fail(e.to_string()))?;
        let out = if self.to_geographic {
            (p.1.to_degrees(), p.0.to_degrees(), p.2)
        } else {
            (p.0, p.1, p.2)
        };
        if out.0.is_finite() && out.1.is_finite() && out.2.is_finite() {
            Ok(out)
        } else {
            Err(fail("outside the domain of the projection".into()))
        }
    }
}

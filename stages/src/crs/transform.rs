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
    from: Side,
    to: Side,
}

/// One side of a transformation: the coordinates' definition, whether they are latitude/longitude, and the
/// name errors give them.
#[derive(Clone)]
struct Side {
    proj: Proj,
    geographic: bool,
    name: String,
}

impl Side {
    /// `crs`'s native coordinates.
    fn native(crs: &Crs) -> Self {
        Self {
            proj: crs.proj.clone(),
            geographic: crs.kind == HorizontalKind::Geographic,
            name: format!("EPSG:{}", crs.horizontal_code),
        }
    }

    /// Latitude/longitude on `crs`'s own datum.
    fn own_geographic(crs: &Crs) -> Self {
        Self {
            proj: crs.geographic.clone(),
            geographic: true,
            name: format!("EPSG:{} geographic", crs.horizontal_code),
        }
    }
}

impl HorizontalTransform {
    /// From `from`'s native coordinates to `to`'s.
    pub fn new(from: &Crs, to: &Crs) -> Self {
        Self {
            from: Side::native(from),
            to: Side::native(to),
        }
    }

    /// From `crs`'s native coordinates to latitude/longitude on its own datum (map → geographic).
    pub fn to_own_geographic(crs: &Crs) -> Self {
        Self {
            from: Side::native(crs),
            to: Side::own_geographic(crs),
        }
    }

    /// From latitude/longitude on `crs`'s own datum to its native coordinates (geographic → map).
    pub fn from_own_geographic(crs: &Crs) -> Self {
        Self {
            from: Side::own_geographic(crs),
            to: Side::native(crs),
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
            from: self.from.name.clone(),
            to: self.to.name.clone(),
            reason,
        };
        if !a.is_finite() || !b.is_finite() {
            return Err(fail("not a finite number".into()));
        }
        let mut p = if self.from.geographic {
            if !(-90.0..=90.0).contains(&a) || !(-360.0..=360.0).contains(&b) {
                return Err(fail(
                    "latitude must lie in [−90°, 90°], longitude in [−360°, 360°]".into(),
                ));
            }
            (b.to_radians(), a.to_radians(), h_m)
        } else {
            (a, b, h_m)
        };
        proj4rs::transform::transform(&self.from.proj, &self.to.proj, &mut p)
            .map_err(|e| fail(e.to_string()))?;
        let out = if self.to.geographic {
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

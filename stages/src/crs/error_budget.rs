//! How wrong a computation gets when it treats map coordinates (easting, northing, height) as a Cartesian
//! frame: the map projection scales horizontal distances by the point scale factor k but leaves heights
//! alone, and the earth's surface curves away from the flat map by about d²/(2R) over a distance d.
//!
//! [`map_frame_ray_error`] measures it for the ray of an aerial camera: a camera at flying height H above a
//! ground point G, a second ground point P at distance d east of G. The exact ray C→P is built in a local
//! tangent frame, expressed in the map frame with the camera's attitude turned by the meridian convergence
//! at C (what an exact import of the orientation gives), and intersected with P's map height. The
//! horizontal distance between that intersection and P's map position is the error a map-frame ray
//! intersection makes; it is ≈ (1 − k)·d (scale: the map stretches the ground by k but not the ray) −
//! d³/(2 R H) (curvature: the ground falls away below the flat map).

use super::definition::Crs;
use super::ellipsoid::LocalTangentFrame;
use super::grid_north::GridNorth;
use super::transform::{HorizontalTransform, TransformError};
use crate::geometry::rot_z;
use nalgebra::Vector3;

/// The error of one map-frame ray, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayErrorBudget {
    /// Horizontal distance between where the map-frame ray meets P's height and P, m (signed along the
    /// direction G→P: negative = falls short).
    pub along_m: f64,
    /// Across the direction G→P, m.
    pub across_m: f64,
    /// Point scale factor at G.
    pub scale_factor: f64,
    /// Closed-form estimate of the scale part, (1 − k)·d, m.
    pub scale_part_m: f64,
    /// Closed-form estimate of the curvature part, −d³/(2 R H), m.
    pub curvature_part_m: f64,
}

/// The error of a map-frame aerial ray at flying height `flying_height_m` above the ground point at
/// (lat, lon) (on `crs`'s datum, ellipsoidal height 0) to a ground point `offset_m` (true distance) east.
pub fn map_frame_ray_error(
    crs: &Crs,
    lat_deg: f64,
    lon_deg: f64,
    flying_height_m: f64,
    offset_m: f64,
) -> Result<RayErrorBudget, TransformError> {
    let ell = crs.ellipsoid;
    let frame = LocalTangentFrame::new(ell, lat_deg, lon_deg, 0.0);
    let to_map = HorizontalTransform::from_own_geographic(crs);
    let grid = GridNorth::new(crs).expect("a projected CRS");
    // P: on the ellipsoid, `offset_m` east of G along the tangent plane's east axis, dropped to h = 0.
    let (p_lat, p_lon, _) = frame.to_geodetic(&Vector3::new(offset_m, 0.0, 0.0));
    let p_local = frame.from_geodetic(p_lat, p_lon, 0.0);
    let c_local = Vector3::new(0.0, 0.0, flying_height_m);
    let ray_true = (p_local - c_local).normalize();
    // The attitude expressed in the map frame: ENU at C turned by the convergence at C.
    let gamma_deg = grid.true_north_grid_azimuth_deg(lat_deg, lon_deg)?;
    let ray_map = rot_z(-gamma_deg.to_radians()) * ray_true;
    let (ce, cn) = to_map.apply(lat_deg, lon_deg)?;
    let (pe, pn) = to_map.apply(p_lat, p_lon)?;
    let t = -flying_height_m / ray_map.z;
    let hit = Vector3::new(ce, cn, flying_height_m) + t * ray_map;
    let err = Vector3::new(hit.x - pe, hit.y - pn, 0.0);
    let along_dir = Vector3::new(pe - ce, pn - cn, 0.0).normalize();
    let across_dir = Vector3::new(-along_dir.y, along_dir.x, 0.0);
    let k = grid.scale_factor(lat_deg, lon_deg)?;
    let r = (ell.meridian_radius_m(lat_deg) * ell.prime_vertical_radius_m(lat_deg)).sqrt();
    Ok(RayErrorBudget {
        along_m: err.dot(&along_dir),
        across_m: err.dot(&across_dir),
        scale_factor: k,
        scale_part_m: (1.0 - k) * offset_m,
        curvature_part_m: -offset_m.powi(3) / (2.0 * r * flying_height_m),
    })
}

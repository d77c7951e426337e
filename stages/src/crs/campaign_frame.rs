//! A campaign's Cartesian frame: the local tangent (east-north-up) frame at an origin in the campaign area,
//! with conversions of points, attitudes and rays between it and the campaign's map coordinates (projected
//! easting/northing + the campaign's heights). Computations whose result depends on the frame being
//! Cartesian — intersecting aerial rays hundreds of metres long — done in this frame are free of the map
//! projection's scale error and of the earth curvature that a map-frame computation makes
//! ([`super::error_budget`]: 2–19 cm at 500–1000 m flying height).
//!
//! Map → local: easting/northing → latitude/longitude on the CRS's datum; height H → ellipsoidal height
//! h = H + N with the geoid separation N (h = H where no geoid model is given: heights are then off by N
//! everywhere alike, which shifts the frame by N vertically and scales it by N/R ≈ 7·10⁻⁶ — below 0.1 mm
//! on a 10 m ray, 3.5 mm on a 500 m one); geodetic → the tangent frame. Attitudes in the map frame are relative
//! to grid north: a vector of the map frame at a point is turned by the meridian convergence γ into the
//! east-north-up frame there (`v_enu = Rz(γ)·v_map`, Rz turning counter-clockwise, γ clockwise from grid
//! north to true north), then into the tangent frame at the origin.

use super::definition::Crs;
use super::ellipsoid::LocalTangentFrame;
use super::geoid::GeoidModel;
use super::grid_north::GridNorth;
use super::transform::HorizontalTransform;
use crate::geometry::{rot_z, Ray};
use nalgebra::{Matrix3, Vector3};

/// A point or attitude that could not be converted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    #[error("campaign frame: {0} is not a projected CRS")]
    NotProjected(String),
    #[error("campaign frame: {0}")]
    Transform(String),
}

/// The Cartesian frame of a campaign in a projected CRS.
#[derive(Clone)]
pub struct CampaignFrame {
    tangent: LocalTangentFrame,
    to_geo: HorizontalTransform,
    to_map: HorizontalTransform,
    grid: GridNorth,
    geoid: Option<GeoidModel>,
}

fn fail(e: impl ToString) -> FrameError {
    FrameError::Transform(e.to_string())
}

impl CampaignFrame {
    /// The tangent frame at map point `origin_map` (easting, northing, height) of `crs`.
    pub fn new(
        crs: &Crs,
        geoid: Option<GeoidModel>,
        origin_map: Vector3<f64>,
    ) -> Result<Self, FrameError> {
        let grid = GridNorth::new(crs).ok_or_else(|| FrameError::NotProjected(crs.text.clone()))?;
        let to_geo = HorizontalTransform::to_own_geographic(crs);
        let to_map = HorizontalTransform::from_own_geographic(crs);
        let mut frame = Self {
            tangent: LocalTangentFrame::new(crs.ellipsoid, 0.0, 0.0, 0.0),
            to_geo,
            to_map,
            grid,
            geoid,
        };
        let (lat, lon, h) = frame.geodetic(&origin_map)?;
        frame.tangent = LocalTangentFrame::new(crs.ellipsoid, lat, lon, h);
        Ok(frame)
    }

    fn separation_m(&self, lat_deg: f64, lon_deg: f64) -> Result<f64, FrameError> {
        match &self.geoid {
            Some(g) => g.separation_m(lat_deg, lon_deg).map_err(fail),
            None => Ok(0.0),
        }
    }

    /// Latitude, longitude (°) and ellipsoidal height (m) of a map point.
    fn geodetic(&self, p_map: &Vector3<f64>) -> Result<(f64, f64, f64), FrameError> {
        let (lat, lon) = self.to_geo.apply(p_map.x, p_map.y).map_err(fail)?;
        Ok((lat, lon, p_map.z + self.separation_m(lat, lon)?))
    }

    /// Map point → tangent frame, m.
    pub fn point_to_local(&self, p_map: &Vector3<f64>) -> Result<Vector3<f64>, FrameError> {
        let (lat, lon, h) = self.geodetic(p_map)?;
        Ok(self.tangent.from_geodetic(lat, lon, h))
    }

    /// Tangent-frame point → map point (easting, northing, height).
    pub fn point_to_map(&self, p_local: &Vector3<f64>) -> Result<Vector3<f64>, FrameError> {
        let (lat, lon, h) = self.tangent.to_geodetic(p_local);
        let (e, n) = self.to_map.apply(lat, lon).map_err(fail)?;
        Ok(Vector3::new(e, n, h - self.separation_m(lat, lon)?))
    }

    /// The rotation taking map-frame vectors at map point `at_map` into the tangent frame.
    pub fn map_to_local_rotation(&self, at_map: &Vector3<f64>) -> Result<Matrix3<f64>, FrameError> {
        let (lat, lon) = self.to_geo.apply(at_map.x, at_map.y).map_err(fail)?;
        let gamma_deg = self
            .grid
            .true_north_grid_azimuth_deg(lat, lon)
            .map_err(fail)?;
        Ok(self.tangent.enu_at(lat, lon) * rot_z(gamma_deg.to_radians()))
    }

    /// A camera→map rotation of a camera at `centre_map` as camera→tangent frame.
    pub fn attitude_to_local(
        &self,
        centre_map: &Vector3<f64>,
        camera_to_map: &Matrix3<f64>,
    ) -> Result<Matrix3<f64>, FrameError> {
        Ok(self.map_to_local_rotation(centre_map)? * camera_to_map)
    }

    /// A map-frame ray (origin and direction as a camera in the map frame sees it) in the tangent frame.
    pub fn ray_to_local(&self, ray_map: &Ray) -> Result<Ray, FrameError> {
        Ok(Ray::new(
            self.point_to_local(&ray_map.origin_world)?,
            self.map_to_local_rotation(&ray_map.origin_world)? * ray_map.dir_world,
        ))
    }
}

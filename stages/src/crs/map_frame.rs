//! Where a campaign's aerial rays are intersected: in its coordinates as they are (a Cartesian frame), or in
//! the local tangent frame of its projected CRS ([`CampaignFrame`]). A map projection scales horizontal
//! distances by its point scale factor and not heights, and the earth curves away from the flat map, so an
//! intersection of rays hundreds of metres long computed in map coordinates misses the true point by
//! millimetres to decimetres ([`super::error_budget`]). Intersected in the tangent frame and converted back,
//! it does not. Rays of a few tens of metres (the panoramas) need no such care: their error stays below 0.1 mm.
//!
//! [`MapFrameSpec`] is the serialisable description a pipeline passes between steps (the CRS, the frame's
//! origin and the kind); [`MapFrame`] is the frame built from it.

use super::campaign_frame::{CampaignFrame, FrameError};
use super::definition::Crs;
use crate::geometry::{FrameCamera, PanoramaCamera};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// How the coordinates of a campaign relate to a Cartesian frame (`campaign.toml` key `frame`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CoordinateFrame {
    /// Map coordinates of the projected `crs`: aerial rays are intersected in its tangent frame.
    #[default]
    Projected,
    /// The coordinates already are a Cartesian frame (a local engineering frame, a synthetic scene): used as
    /// they are.
    Cartesian,
}

/// The serialisable description of a campaign's intersection frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapFrameSpec {
    pub kind: CoordinateFrame,
    /// The campaign's CRS declaration (`EPSG:…`); unused for [`CoordinateFrame::Cartesian`].
    pub crs: String,
    /// Origin of the tangent frame, map coordinates (easting, northing, height), m.
    pub origin_map: [f64; 3],
}

impl MapFrameSpec {
    /// Coordinates used as they are.
    pub fn cartesian() -> Self {
        MapFrameSpec {
            kind: CoordinateFrame::Cartesian,
            crs: String::new(),
            origin_map: [0.0; 3],
        }
    }

    /// The frame a campaign declared as `kind` in `crs` needs, with its origin near `near_map` (rounded to
    /// whole kilometres horizontally and to sea level, so that the frame — and every key that depends on it —
    /// stays the same when recordings are added or edited). A `Projected` declaration whose CRS is not a
    /// projected CRS skytie knows becomes `Cartesian`, with the reason.
    pub fn for_campaign(
        kind: CoordinateFrame,
        crs: &str,
        near_map: Option<[f64; 3]>,
    ) -> (Self, Option<String>) {
        if kind == CoordinateFrame::Cartesian {
            return (Self::cartesian(), None);
        }
        let reason = match Crs::parse(crs) {
            Err(e) => Some(format!("crs '{crs}' cannot be used ({e})")),
            Ok(c) if super::GridNorth::new(&c).is_none() => {
                Some(format!("crs '{crs}' is not a projected CRS"))
            }
            Ok(_) => None,
        };
        if let Some(reason) = reason {
            return (
                Self::cartesian(),
                Some(format!(
                    "{reason}: aerial rays are intersected in the campaign's coordinates as they are \
                     (write frame = \"cartesian\" in campaign.toml to say that they are Cartesian)"
                )),
            );
        }
        let [x, y, _] = near_map.unwrap_or([0.0; 3]);
        let km = |v: f64| {
            if v.is_finite() {
                (v / 1000.0).round() * 1000.0
            } else {
                0.0
            }
        };
        let spec = MapFrameSpec {
            kind,
            crs: crs.to_string(),
            origin_map: [km(x), km(y), 0.0],
        };
        (spec, None)
    }
}

/// A campaign's intersection frame.
#[derive(Clone)]
pub enum MapFrame {
    /// The campaign's coordinates themselves.
    Cartesian,
    /// The tangent frame of the campaign's projected CRS.
    Tangent(Box<CampaignFrame>),
}

impl MapFrame {
    /// The frame `spec` describes. Without a geoid model heights are taken as ellipsoidal, which shifts the
    /// frame by the geoid separation and scales it by N/R ≈ 7·10⁻⁶ (below 4 mm on a 500 m ray).
    pub fn from_spec(spec: &MapFrameSpec) -> Result<Self, FrameError> {
        match spec.kind {
            CoordinateFrame::Cartesian => Ok(MapFrame::Cartesian),
            CoordinateFrame::Projected => {
                let crs =
                    Crs::parse(&spec.crs).map_err(|e| FrameError::Transform(e.to_string()))?;
                let frame = CampaignFrame::new(&crs, None, Vector3::from(spec.origin_map))?;
                Ok(MapFrame::Tangent(Box::new(frame)))
            }
        }
    }

    /// A camera oriented in map coordinates, in this frame.
    pub fn camera_to_local(&self, camera: &FrameCamera) -> Result<FrameCamera, FrameError> {
        match self {
            MapFrame::Cartesian => Ok(camera.clone()),
            MapFrame::Tangent(f) => Ok(FrameCamera {
                center_world: f.point_to_local(&camera.center_world)?,
                rotation_cam_to_world: f
                    .attitude_to_local(&camera.center_world, &camera.rotation_cam_to_world)?,
                ..camera.clone()
            }),
        }
    }

    /// A panorama oriented in map coordinates, in this frame.
    pub fn panorama_to_local(&self, camera: &PanoramaCamera) -> Result<PanoramaCamera, FrameError> {
        Ok(PanoramaCamera {
            center_world: self.point_to_local(&camera.center_world)?,
            rotation_pano_to_world: self.rotation_to_local(&camera.center_world)?
                * camera.rotation_pano_to_world,
            ..camera.clone()
        })
    }

    /// The rotation taking map-frame vectors at map point `at_map` into this frame (the identity for
    /// [`MapFrame::Cartesian`]).
    pub fn rotation_to_local(&self, at_map: &Vector3<f64>) -> Result<Matrix3<f64>, FrameError> {
        match self {
            MapFrame::Cartesian => Ok(Matrix3::identity()),
            MapFrame::Tangent(f) => f.map_to_local_rotation(at_map),
        }
    }

    /// A covariance (m²) of the map point `p_map` given in the map's axes, turned into this frame's axes.
    pub fn covariance_to_local(
        &self,
        p_map: &Vector3<f64>,
        covariance_map_m2: &Matrix3<f64>,
    ) -> Result<Matrix3<f64>, FrameError> {
        let r = self.rotation_to_local(p_map)?;
        Ok(r * covariance_map_m2 * r.transpose())
    }

    /// True for the tangent frame of a projected CRS (coordinates are converted), false when the campaign's
    /// coordinates are used as they are.
    pub fn is_tangent(&self) -> bool {
        matches!(self, MapFrame::Tangent(_))
    }

    /// A map point in this frame.
    pub fn point_to_local(&self, p_map: &Vector3<f64>) -> Result<Vector3<f64>, FrameError> {
        match self {
            MapFrame::Cartesian => Ok(*p_map),
            MapFrame::Tangent(f) => f.point_to_local(p_map),
        }
    }

    /// A point of this frame in map coordinates.
    pub fn point_to_map(&self, p_local: &Vector3<f64>) -> Result<Vector3<f64>, FrameError> {
        match self {
            MapFrame::Cartesian => Ok(*p_local),
            MapFrame::Tangent(f) => f.point_to_map(p_local),
        }
    }

    /// A covariance (m²) of the point `p_map` given in this frame, turned into the map's axes. The map's scale
    /// factor (within 10⁻³ of 1 in any sensible projected CRS) is not applied: it changes a σ by less than 0.1 %.
    pub fn covariance_to_map(
        &self,
        p_map: &Vector3<f64>,
        covariance_local_m2: &Matrix3<f64>,
    ) -> Result<Matrix3<f64>, FrameError> {
        match self {
            MapFrame::Cartesian => Ok(*covariance_local_m2),
            MapFrame::Tangent(f) => {
                let r = f.map_to_local_rotation(p_map)?;
                Ok(r.transpose() * covariance_local_m2 * r)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declarations_give_the_frame_or_say_why_not() {
        let (spec, note) = MapFrameSpec::for_campaign(
            CoordinateFrame::Projected,
            "EPSG:28992+5709",
            Some([136_412.3, 455_871.9, 4.2]),
        );
        assert!(note.is_none());
        assert_eq!(spec.kind, CoordinateFrame::Projected);
        assert_eq!(spec.origin_map, [136_000.0, 456_000.0, 0.0]);
        assert!(matches!(
            MapFrame::from_spec(&spec),
            Ok(MapFrame::Tangent(_))
        ));
        for crs in ["EPSG:4326", "EPSG:99999999", "LOCAL"] {
            let (spec, note) = MapFrameSpec::for_campaign(CoordinateFrame::Projected, crs, None);
            assert_eq!(spec, MapFrameSpec::cartesian(), "{crs}");
            assert!(note.unwrap().contains(crs));
        }
        let (spec, note) =
            MapFrameSpec::for_campaign(CoordinateFrame::Cartesian, "EPSG:28992", None);
        assert_eq!((spec, note), (MapFrameSpec::cartesian(), None));
    }

    #[test]
    fn the_tangent_frame_round_trips_cameras_points_and_covariances() {
        let (spec, _) = MapFrameSpec::for_campaign(
            CoordinateFrame::Projected,
            "EPSG:25832",
            Some([500_000.0, 5_650_000.0, 0.0]),
        );
        let frame = MapFrame::from_spec(&spec).unwrap();
        let p_map = Vector3::new(500_731.25, 5_649_512.5, 87.5);
        let local = frame.point_to_local(&p_map).unwrap();
        let back = frame.point_to_map(&local).unwrap();
        assert!((back - p_map).norm() < 1e-6, "{back:?}");
        let cov = Matrix3::from_diagonal(&Vector3::new(1e-4, 4e-4, 9e-4));
        let turned = frame.covariance_to_map(&p_map, &cov).unwrap();
        assert!((turned.trace() - cov.trace()).abs() < 1e-12);
        assert!((turned - turned.transpose()).norm() < 1e-15);
        let cam = FrameCamera::from_opk(
            p_map,
            1.0,
            -2.0,
            30.0,
            8000.0,
            4000.0,
            3000.0,
            8000,
            6000,
            Default::default(),
        );
        let l = frame.camera_to_local(&cam).unwrap();
        assert!((l.center_world - local).norm() < 1e-9);
        let r = l.rotation_cam_to_world;
        assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-12);
        assert_eq!(l.focal_px, cam.focal_px);
    }
}

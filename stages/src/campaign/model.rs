//! In-memory model of a campaign (docs/campaign-format.md): one struct per CSV row kind.
//!
//! Units: world coordinates in metres (f64, projected frame X = east, Y = north, Z = up), angles in degrees,
//! pixels in continuous pixel coordinates. Field names carry units where the CSV column name does not.

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// One panorama row of `mm/recordings.csv` (also the row type of `truth/recordings.csv`). The default is an
/// empty row with every number 0 (a base for struct update syntax, not a valid recording).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Recording {
    pub image_id: String,
    /// Path relative to `mm/panoramas/`.
    pub file: String,
    /// Acquisition time exactly as written (ISO 8601).
    pub time: String,
    /// Acquisition time in seconds since 1970-01-01T00:00:00Z (parsed from `time`); orders the trajectory.
    pub time_s: f64,
    /// Projection centre, world frame, metres.
    pub x: f64,
    pub y: f64,
    pub z: f64,
    /// Driving direction, degrees clockwise from grid north.
    pub heading_deg: f64,
    /// Height of the projection centre above the road surface below it, metres.
    pub camera_height_m: f64,
    /// A-priori standard deviation of x and of y each, metres (optional column `sigma_xy`).
    pub sigma_xy_m: Option<f64>,
    /// A-priori standard deviation of z, metres (optional column `sigma_z`).
    pub sigma_z_m: Option<f64>,
    /// Residual rotation of the panorama frame, degrees (optional columns, default 0).
    pub yaw_deg: f64,
    pub pitch_deg: f64,
    pub roll_deg: f64,
}

/// One row of `aerial/{nadir,oblique}/cameras.csv`. The default is an empty row with every number 0 (a base
/// for struct update syntax, not a valid camera).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AerialImage {
    pub image_id: String,
    /// Path relative to the folder of the CSV.
    pub file: String,
    /// Projection centre, world frame, metres.
    pub x: f64,
    pub y: f64,
    pub z: f64,
    /// Attitude, degrees, R = Rx(ω)·Ry(φ)·Rz(κ) maps camera-frame vectors to world-frame vectors.
    pub omega_deg: f64,
    pub phi_deg: f64,
    pub kappa_deg: f64,
    pub focal_px: f64,
    pub cx_px: f64,
    pub cy_px: f64,
    pub width_px: u32,
    pub height_px: u32,
    /// Brown distortion (optional columns, default 0); normalised image y points up.
    pub k1: f64,
    pub k2: f64,
    pub p1: f64,
    pub p2: f64,
    /// Higher radial terms r⁶, r⁸ (optional columns `k3`, `k4`, default 0).
    #[serde(default)]
    pub k3: f64,
    #[serde(default)]
    pub k4: f64,
    /// Affinity and non-orthogonality of the pixel axes, pixels (optional columns `b1`, `b2`, default 0):
    /// `u = cx + (focal_px + b1)·x_d + b2·y_d`, `v = cy − focal_px·y_d`.
    #[serde(default)]
    pub b1: f64,
    #[serde(default)]
    pub b2: f64,
    /// Image measurement precision, pixels (optional, default 0.5).
    pub sigma_px: f64,
}

impl Recording {
    /// A recording whose projection centre is `centre_world_m` (world frame, metres), with every optional
    /// column at its default (no a-priori σ, no residual rotation), file `<image_id>.jpg`, and `time` left
    /// empty: the campaign writer formats it from `time_s`.
    pub fn new(
        image_id: &str,
        time_s: f64,
        centre_world_m: [f64; 3],
        heading_deg: f64,
        camera_height_m: f64,
    ) -> Self {
        let [x, y, z] = centre_world_m;
        Self {
            image_id: image_id.into(),
            file: format!("{image_id}.jpg"),
            time_s,
            x,
            y,
            z,
            heading_deg,
            camera_height_m,
            ..Self::default()
        }
    }
}

impl AerialImage {
    /// A distortion-free frame camera at `centre_world_m` (world frame, metres) with attitude
    /// `opk_deg` = (ω, φ, κ) in degrees, focal length `focal_px` and an image of `size_px` = (width, height)
    /// pixels whose principal point is the image centre; σ 0.5 px (the column's default), file `<image_id>.jpg`.
    pub fn ideal(
        image_id: &str,
        centre_world_m: [f64; 3],
        opk_deg: [f64; 3],
        focal_px: f64,
        size_px: [u32; 2],
    ) -> Self {
        let [x, y, z] = centre_world_m;
        let [omega_deg, phi_deg, kappa_deg] = opk_deg;
        let [width_px, height_px] = size_px;
        Self {
            image_id: image_id.into(),
            file: format!("{image_id}.jpg"),
            x,
            y,
            z,
            omega_deg,
            phi_deg,
            kappa_deg,
            focal_px,
            cx_px: f64::from(width_px) / 2.0,
            cy_px: f64::from(height_px) / 2.0,
            width_px,
            height_px,
            sigma_px: 0.5,
            ..Self::default()
        }
    }
}

/// Which aerial folder an image came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum AerialKind {
    Nadir,
    Oblique,
}

/// One row of `control/checkpoints.csv`: a surveyed point used only for evaluation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckPoint {
    pub point_id: String,
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub sigma_xy_m: Option<f64>,
    pub sigma_z_m: Option<f64>,
}

/// One row of `control/observations.csv`: where a check point was measured in a panorama.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    pub point_id: String,
    pub image_id: String,
    /// Continuous pixel coordinates in the panorama.
    pub u_px: f64,
    pub v_px: f64,
}

/// A whole campaign as read from disk (only rows that passed validation).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Campaign {
    /// The campaign folder.
    pub root: PathBuf,
    /// `campaign.toml`: `name`.
    pub name: String,
    /// `campaign.toml`: `crs` (never reprojected; a projected CRS's tangent frame is where aerial rays are
    /// intersected, see `frame`).
    pub crs: String,
    /// `campaign.toml`: `frame` — whether the coordinates are map coordinates of `crs` (default) or already
    /// Cartesian.
    #[serde(default)]
    pub frame: crate::crs::CoordinateFrame,
    /// Recordings sorted by `time_s`.
    pub recordings: Vec<Recording>,
    pub nadir: Vec<AerialImage>,
    pub oblique: Vec<AerialImage>,
    pub checkpoints: Vec<CheckPoint>,
    pub observations: Vec<Observation>,
    /// `campaign.toml` `[orthophoto]`: the orthophoto tiles and their stated accuracy.
    #[serde(default)]
    pub orthophoto: Option<super::orthophoto::OrthophotoSource>,
    /// `campaign.toml` `[dtm]`: the terrain model tiles and their stated accuracy.
    #[serde(default)]
    pub dtm: Option<super::orthophoto::DtmSource>,
}

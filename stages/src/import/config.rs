//! The import configuration (a TOML file, `skytie import CONFIG.toml --out DIR`): the campaign's name and
//! CRS with the geoid model, the aerial orientation sources, the mobile-mapping trajectory with its event
//! file, boresight and lever arm, and the control points. Paths are relative to the configuration file.
//! Unknown keys are errors (a misspelt key must not silently fall back to a default).

use crate::formats::camera_model::CameraModel;
use crate::formats::events::EventFormat;
use crate::formats::opk_list::OpkListFormat;
use crate::formats::points::{MeasurementFormat, PointFormat};
use crate::formats::trajectory_csv::TrajectoryCsvFormat;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The whole configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImportConfig {
    pub campaign: CampaignSection,
    #[serde(default)]
    pub aerial: Vec<AerialSource>,
    #[serde(default)]
    pub mm: Option<MmSource>,
    /// Panoramas with their pose in EXIF GPS / GPano tags (instead of `[mm]`).
    #[serde(default)]
    pub panorama_tags: Option<PanoramaTagSource>,
    #[serde(default)]
    pub control: Option<ControlSource>,
}

/// `[panorama_tags]`: panoramas whose JPEG files carry their pose (EXIF GPS + GPano XMP).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PanoramaTagSource {
    /// Folder of the panorama images (every `.jpg`/`.jpeg` in it).
    pub panoramas: PathBuf,
    /// Geographic CRS of the GPS tags, e.g. `EPSG:4979` (WGS 84) or `EPSG:4937` (ETRS89).
    pub crs: String,
    /// What `GPSAltitude` is: `ellipsoidal`, `campaign` or `EPSG:<vertical>` (devices differ; no default).
    pub heights: String,
    /// Height of the panorama centre above the road, m.
    pub camera_height_m: f64,
    #[serde(default)]
    pub sigma_xy_m: Option<f64>,
    #[serde(default)]
    pub sigma_z_m: Option<f64>,
}

/// `[campaign]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignSection {
    pub name: String,
    /// Horizontal + vertical CRS of the campaign, e.g. `EPSG:28992+5709`.
    pub crs: String,
    /// GTX grid of the geoid (separation ellipsoid → the campaign's height surface, on ETRS89/WGS84
    /// latitude/longitude).
    #[serde(default)]
    pub geoid_grid: Option<PathBuf>,
    /// A constant separation instead of a grid, m.
    #[serde(default)]
    pub geoid_separation_m: Option<f64>,
    /// NTv2 grid (`.gsb`) of the campaign CRS's datum shift to ETRS89/WGS84 (e.g. `rdtrans2018.gsb` for RD
    /// New), used instead of the EPSG definition's Helmert parameters.
    #[serde(default)]
    pub datum_grid: Option<PathBuf>,
    /// `frame` of the campaign written (`projected`, the default, or `cartesian`; campaign-format.md).
    #[serde(default)]
    pub frame: crate::crs::CoordinateFrame,
}

/// Which aerial folder the images go to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AerialKindName {
    Nadir,
    Oblique,
}

/// The vendor format of an aerial source.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AerialFormat {
    /// `*_calibrated_external_camera_parameters.txt` + `*_pix4d_calibrated_internal_camera_parameters.cam`.
    Pix4d,
    /// Metashape camera XML export (sensors with calibration, cameras with transforms, chunk transform).
    MetashapeXml,
    /// Metashape Omega-Phi-Kappa text export + `[aerial.camera]`.
    MetashapeOpk,
    /// Any ω-φ-κ / yaw-pitch-roll list with `[aerial.layout]` + `[aerial.camera]`.
    OpkList,
}

/// `[[aerial]]`: one orientation source.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AerialSource {
    pub kind: AerialKindName,
    pub format: AerialFormat,
    /// The orientation file (list or XML).
    pub orientations: PathBuf,
    /// Pix4D: the internal camera parameters `.cam` file.
    #[serde(default)]
    pub internals: Option<PathBuf>,
    /// Folder of the image files.
    pub images: PathBuf,
    /// CRS of the orientation file (default: the campaign's; Metashape XML: ignored, the chunk's CRS is used
    /// and must be given here when the file has none).
    #[serde(default)]
    pub crs: Option<String>,
    /// `campaign` (default), `ellipsoidal` or `EPSG:<vertical>`.
    #[serde(default)]
    pub heights: Option<String>,
    /// Image size, pixels (Pix4D: needed when the image files cannot be read for it).
    #[serde(default)]
    pub image_width_px: Option<u32>,
    #[serde(default)]
    pub image_height_px: Option<u32>,
    /// Layout of an `opk-list`.
    #[serde(default)]
    pub layout: Option<OpkListFormat>,
    /// Interior orientation for list formats (campaign convention).
    #[serde(default)]
    pub camera: Option<CameraModel>,
    /// Image measurement precision, px (default 0.5).
    #[serde(default)]
    pub sigma_px: Option<f64>,
}

/// The trajectory file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TrajectoryFormat {
    Sbet,
    Csv,
}

/// Where a panorama's orientation comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PanoramaOrientation {
    /// The panorama is rigid on the vehicle: IMU attitude × boresight.
    Imu,
    /// The event file has the panorama's heading (true north), pitch and roll in `pano_columns`.
    EventColumns,
}

/// Which north a trajectory table's heading refers to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum North {
    True,
    Grid,
}

/// `[mm]`: the trajectory and the panoramas.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MmSource {
    pub trajectory: PathBuf,
    pub format: TrajectoryFormat,
    /// CRS of the trajectory positions, e.g. `EPSG:4937` (ETRS89 geographic 3D).
    pub crs: String,
    /// `ellipsoidal`, `campaign` or `EPSG:<vertical>`.
    pub heights: String,
    /// SBET: the GPS week of the seconds-of-week times.
    #[serde(default)]
    pub gps_week: Option<u32>,
    /// SBET: GPS − UTC in seconds (default: from the leap-second table).
    #[serde(default)]
    pub leap_seconds: Option<f64>,
    /// Trajectory table layout (`format = "csv"`).
    #[serde(default)]
    pub layout: Option<TrajectoryCsvFormat>,
    /// Trajectory table: whether its heading is to true or grid north (of its own CRS).
    #[serde(default)]
    pub heading_north: Option<North>,
    pub events: PathBuf,
    pub event_layout: EventFormat,
    pub orientation: PanoramaOrientation,
    /// Event-file columns of the panorama heading (true north), pitch, roll, degrees.
    #[serde(default)]
    pub pano_columns: Option<[String; 3]>,
    /// Folder of the panorama images.
    pub panoramas: PathBuf,
    /// Height of the panorama centre above the road, m.
    pub camera_height_m: f64,
    /// Rotation of the panorama frame relative to the IMU body frame: roll, pitch, yaw in degrees.
    #[serde(default)]
    pub boresight_deg: [f64; 3],
    /// IMU → panorama centre in the body frame (x forward, y right, z down), m.
    #[serde(default)]
    pub lever_arm_m: [f64; 3],
    /// Largest time gap between the two trajectory samples an event is interpolated between, s.
    #[serde(default = "default_max_gap")]
    pub max_gap_s: f64,
    #[serde(default)]
    pub sigma_xy_m: Option<f64>,
    #[serde(default)]
    pub sigma_z_m: Option<f64>,
}

fn default_max_gap() -> f64 {
    1.0
}

/// `[control]`: check points and their panorama measurements.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlSource {
    pub points: PathBuf,
    pub layout: PointFormat,
    #[serde(default)]
    pub crs: Option<String>,
    #[serde(default)]
    pub heights: Option<String>,
    #[serde(default)]
    pub measurements: Option<PathBuf>,
    #[serde(default)]
    pub measurement_layout: Option<MeasurementFormat>,
}

/// A configuration that cannot be read.
#[derive(Debug, thiserror::Error)]
#[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct ConfigError {
    pub path: PathBuf,
    pub line: Option<usize>,
    pub message: String,
}

impl ImportConfig {
    /// Read and parse `path`; paths inside are made relative to its folder.
    pub fn read(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|e| ConfigError {
            path: path.to_path_buf(),
            line: None,
            message: format!("cannot be read ({e})"),
        })?;
        let mut config = Self::parse(path, &text)?;
        config.resolve_paths(path.parent().unwrap_or(Path::new(".")));
        Ok(config)
    }

    /// Parse TOML text (paths left as written).
    pub fn parse(path: &Path, text: &str) -> Result<Self, ConfigError> {
        toml::from_str(text).map_err(|e| ConfigError {
            path: path.to_path_buf(),
            line: e
                .span()
                .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1),
            message: e.message().to_string(),
        })
    }

    fn resolve_paths(&mut self, base: &Path) {
        let fix = |p: &mut PathBuf| {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        };
        if let Some(g) = &mut self.campaign.geoid_grid {
            fix(g);
        }
        if let Some(g) = &mut self.campaign.datum_grid {
            fix(g);
        }
        for a in &mut self.aerial {
            fix(&mut a.orientations);
            fix(&mut a.images);
            if let Some(i) = &mut a.internals {
                fix(i);
            }
        }
        if let Some(mm) = &mut self.mm {
            fix(&mut mm.trajectory);
            fix(&mut mm.events);
            fix(&mut mm.panoramas);
        }
        if let Some(t) = &mut self.panorama_tags {
            fix(&mut t.panoramas);
        }
        if let Some(c) = &mut self.control {
            fix(&mut c.points);
            if let Some(m) = &mut c.measurements {
                fix(m);
            }
        }
    }
}

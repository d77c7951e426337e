//! `campaign.toml`'s `[source]` table: where an imported campaign's trajectory came from
//! (`[source.trajectory]`), so that a run can deliver the corrected trajectory in the same form (an SBET with
//! the same record layout and time base). The import copies the SBET (and the geoid grid, if one was used)
//! into `mm/trajectory/` of the campaign, so the folder stays self-contained; paths in the table are relative
//! to the campaign folder.
//!
//! ```toml
//! name = "Utrecht 2024"
//! crs = "EPSG:28992+5709"
//!
//! [source.trajectory]
//! format = "sbet"
//! file = "mm/trajectory/sbet_001.out"
//! crs = "EPSG:4937"
//! heights = "ellipsoidal"
//! gps_week = 2062
//! lever_arm_m = [0.41, 0.0, -1.92]
//! boresight_deg = [0.12, -0.35, 0.8]
//! geoid_grid = "mm/trajectory/nlgeo2018.gtx"     # or geoid_separation_m = 43.2, or neither
//! ```

use super::Problem;
use crate::crs::{CoordinateFrame, Crs, GeoidModel};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The file the table lives in.
const TOML: &str = "campaign.toml";

/// `[source]` of `campaign.toml`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SourceSection {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trajectory: Option<TrajectoryProvenance>,
}

/// The format of an imported trajectory file that a run can write back.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ProvenanceFormat {
    Sbet,
}

/// `[source.trajectory]`: the imported trajectory and everything needed to map campaign corrections back
/// into it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectoryProvenance {
    pub format: ProvenanceFormat,
    /// The trajectory file, relative to the campaign folder.
    pub file: PathBuf,
    /// Its geographic CRS, e.g. `EPSG:4937`.
    pub crs: String,
    /// Its height kind (`ellipsoidal`, `campaign` or `EPSG:<vertical>`).
    pub heights: String,
    /// GPS week of its seconds-of-week times.
    pub gps_week: u32,
    /// GPS − UTC used at import, s (absent: the leap-second table).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub leap_seconds: Option<f64>,
    /// IMU → panorama centre, body frame (x forward, y right, z down), m.
    pub lever_arm_m: [f64; 3],
    /// Panorama frame on the body: roll, pitch, yaw, degrees.
    pub boresight_deg: [f64; 3],
    /// Geoid grid (GTX) the import used, relative to the campaign folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub geoid_grid: Option<PathBuf>,
    /// Constant geoid separation the import used, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub geoid_separation_m: Option<f64>,
}

impl TrajectoryProvenance {
    /// The geoid model it names (`None` when the import used none).
    pub fn geoid(&self, root: &Path) -> Result<Option<GeoidModel>, String> {
        GeoidModel::from_keys(
            "source.trajectory",
            self.geoid_grid.as_deref(),
            self.geoid_separation_m,
            root,
        )
    }

    /// Check what a run needs: a geographic CRS skytie knows, a file that exists.
    pub fn validate(&self, root: &Path) -> Result<(), String> {
        let crs = Crs::parse(&self.crs).map_err(|e| format!("source.trajectory.crs: {e}"))?;
        if crs.is_projected() {
            return Err(format!(
                "source.trajectory.crs: {} is projected but an SBET holds latitude/longitude",
                self.crs
            ));
        }
        if !root.join(&self.file).is_file() {
            return Err(format!(
                "source.trajectory.file: {} does not exist",
                root.join(&self.file).display()
            ));
        }
        self.geoid(root).map(|_| ())
    }
}

/// `campaign.toml` with `name`, `crs`, `frame` (when not the default) and the `[source]` table.
pub fn write_campaign_toml_with_source(
    path: &Path,
    name: &str,
    crs: &str,
    frame: CoordinateFrame,
    source: &SourceSection,
) -> std::io::Result<()> {
    #[derive(Serialize)]
    struct Toml<'a> {
        name: &'a str,
        crs: &'a str,
        #[serde(skip_serializing_if = "Option::is_none")]
        frame: Option<CoordinateFrame>,
        #[serde(skip_serializing_if = "Option::is_none")]
        source: Option<&'a SourceSection>,
    }
    let frame = (frame != CoordinateFrame::default()).then_some(frame);
    let source = (source != &SourceSection::default()).then_some(source);
    let text = toml::to_string(&Toml {
        name,
        crs,
        frame,
        source,
    })
    .map_err(std::io::Error::other)?;
    crate::fsutil::atomic_write(path, text.as_bytes())
}

/// The `[source]` table of the campaign in `root` (the default when there is none); `Err` is a warning
/// naming `campaign.toml` and the key (the campaign is usable, only the corrected SBET cannot be written).
pub fn read_source(root: &Path) -> Result<SourceSection, Problem> {
    let Ok(text) = std::fs::read_to_string(root.join(TOML)) else {
        return Ok(SourceSection::default());
    };
    let Ok(table) = text.parse::<toml::Table>() else {
        // Not TOML at all: the campaign reader reports that.
        return Ok(SourceSection::default());
    };
    let Some(value) = table.get("source") else {
        return Ok(SourceSection::default());
    };
    let fail = |message: String| {
        Problem::warning(
            TOML,
            None,
            Some("source"),
            format!("{message}; the run will not write the corrected SBET"),
            "the [source] table is written by skytie import; see docs/campaign-format.md",
        )
    };
    let section: SourceSection = value.clone().try_into().map_err(|e: toml::de::Error| {
        fail(format!("is not a valid [source] table: {}", e.message()))
    })?;
    if let Some(t) = &section.trajectory {
        t.validate(root).map_err(fail)?;
    }
    Ok(section)
}

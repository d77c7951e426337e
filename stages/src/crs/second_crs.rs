//! A second output CRS (`campaign.toml` `[outputs]`): the campaign's map coordinates converted into another
//! CRS for delivery — positions with `proj4rs` (the EPSG definitions' Helmert datum shift, or a national NTv2
//! grid given as `datum_grid`), heights only when both height systems are known, and horizontal vectors
//! (corrections, σ) turned from the campaign's grid axes into the second CRS's axes (its grid east/north, or
//! true east/north for a geographic CRS).
//!
//! ```toml
//! crs = "EPSG:28992+5709"
//!
//! [outputs]
//! also_crs = "EPSG:4937"                # ETRS89 latitude, longitude, ellipsoidal height
//! geoid_grid = "geoid/nlgeo2018.gtx"    # or geoid_separation_m = 43.2: NAP → ellipsoidal heights
//! datum_grid = "grids/rdtrans2018.gsb"  # optional: RD's datum shift by the national NTv2 grid
//! ```
//!
//! Heights: the same height system on both sides, or no vertical part in `also_crs`, copies the campaign's
//! heights (named in the files' first line); ellipsoidal heights (a geographic 3D CRS) from the campaign's
//! orthometric heights need a geoid model (`h = H + N`); anything else is refused with what is missing.

use super::definition::{Crs, HorizontalKind, VerticalDatum};
use super::geoid::GeoidModel;
use super::grid_north::GridNorth;
use super::heights::{HeightConversion, HeightKind};
use super::transform::HorizontalTransform;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The file the table lives in.
pub const CAMPAIGN_TOML: &str = "campaign.toml";

/// `[outputs]` of `campaign.toml`.
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputsSection {
    /// The second CRS, `EPSG:<horizontal>[+<vertical>]`.
    #[serde(default)]
    pub also_crs: Option<String>,
    /// GTX geoid grid (separation ellipsoid → the campaign's height surface), relative to the campaign folder.
    #[serde(default)]
    pub geoid_grid: Option<PathBuf>,
    /// A constant geoid separation instead of a grid, m.
    #[serde(default)]
    pub geoid_separation_m: Option<f64>,
    /// NTv2 grid of the campaign CRS's datum shift, relative to the campaign folder.
    #[serde(default)]
    pub datum_grid: Option<PathBuf>,
}

impl OutputsSection {
    /// The `[outputs]` table of the campaign in `root` (the default when there is none). `Err` names the key.
    pub fn read(root: &Path) -> Result<Self, String> {
        let Ok(text) = std::fs::read_to_string(root.join(CAMPAIGN_TOML)) else {
            return Ok(Self::default());
        };
        let Ok(table) = text.parse::<toml::Table>() else {
            // Not TOML at all: the campaign reader reports that.
            return Ok(Self::default());
        };
        match table.get("outputs") {
            None => Ok(Self::default()),
            Some(v) => v.clone().try_into().map_err(|e: toml::de::Error| {
                format!("[outputs] is not a valid table: {}", e.message())
            }),
        }
    }

    fn geoid(&self, root: &Path) -> Result<Option<GeoidModel>, String> {
        GeoidModel::from_keys(
            "outputs",
            self.geoid_grid.as_deref(),
            self.geoid_separation_m,
            root,
        )
    }
}

/// How heights reach the second CRS.
#[derive(Debug, Clone, PartialEq)]
pub enum OutputHeights {
    /// Copied as they are, in the system named here (the campaign's).
    Copied(VerticalDatum),
    /// Ellipsoidal heights `h = H + N` with the geoid model.
    Ellipsoidal(HeightConversion),
}

/// The conversion from the campaign's map coordinates into the second CRS.
#[derive(Clone)]
pub struct SecondCrs {
    /// The second CRS as declared.
    pub crs: Crs,
    pub heights: OutputHeights,
    to_output: HorizontalTransform,
    to_campaign_geographic: HorizontalTransform,
    campaign_north: GridNorth,
    output_north: Option<GridNorth>,
}

impl SecondCrs {
    /// The second CRS of a campaign in `campaign_crs` (folder `root`), `None` without `also_crs`. `Err` says
    /// which key of `[outputs]` cannot be used and what to do.
    pub fn new(
        campaign_crs: &str,
        section: &OutputsSection,
        root: &Path,
    ) -> Result<Option<Self>, String> {
        let Some(also) = &section.also_crs else {
            return Ok(None);
        };
        let output = Crs::parse(also).map_err(|e| format!("outputs.also_crs: {e}"))?;
        let campaign = Crs::parse(campaign_crs).map_err(|e| format!("crs: {e}"))?;
        let campaign = match &section.datum_grid {
            Some(g) => campaign
                .with_datum_grid(&root.join(g))
                .map_err(|e| format!("outputs.datum_grid: {e}"))?,
            None => campaign,
        };
        let campaign_north = GridNorth::new(&campaign).ok_or_else(|| {
            format!("crs: {campaign_crs} is not a projected CRS, so its coordinates cannot be converted")
        })?;
        let heights = output_heights(&campaign, &output, section.geoid(root)?)?;
        Ok(Some(Self {
            to_output: HorizontalTransform::new(&campaign, &output),
            to_campaign_geographic: HorizontalTransform::to_own_geographic(&campaign),
            campaign_north,
            output_north: GridNorth::new(&output),
            crs: output,
            heights,
        }))
    }

    /// The folder name of the files in this CRS: `epsg_<h>[_<v>]`.
    pub fn folder_name(&self) -> String {
        match self.crs.vertical {
            VerticalDatum::Orthometric { code, .. } => {
                format!("epsg_{}_{code}", self.crs.horizontal_code)
            }
            _ => format!("epsg_{}", self.crs.horizontal_code),
        }
    }

    /// True when the second CRS gives latitude, longitude (degrees).
    pub fn is_geographic(&self) -> bool {
        self.crs.kind == HorizontalKind::Geographic
    }

    /// A campaign map point (easting, northing, height) in the second CRS: (easting, northing) or (latitude,
    /// longitude), and the height.
    pub fn point(&self, p_map: [f64; 3]) -> Result<[f64; 3], String> {
        let [x, y, z] = p_map;
        let (a, b) = self.to_output.apply(x, y).map_err(|e| e.to_string())?;
        let h = match &self.heights {
            OutputHeights::Copied(_) => z,
            // Only geographic 3D CRSs have ellipsoidal heights: (a, b) are latitude, longitude.
            OutputHeights::Ellipsoidal(c) => c.from_campaign(a, b, z).map_err(|e| e.to_string())?,
        };
        Ok([a, b, h])
    }

    /// The clockwise angle (degrees) that turns a horizontal vector at campaign map point (x, y) from the
    /// campaign's grid axes into the second CRS's axes (grid axes, or true east/north when geographic): the
    /// difference of the two projections' grid azimuths of true north.
    pub fn turn_deg(&self, x: f64, y: f64) -> Result<f64, String> {
        let (lat, lon) = self
            .to_campaign_geographic
            .apply(x, y)
            .map_err(|e| e.to_string())?;
        let gamma_campaign = self
            .campaign_north
            .true_north_grid_azimuth_deg(lat, lon)
            .map_err(|e| e.to_string())?;
        let gamma_output = match &self.output_north {
            // Latitude/longitude on the campaign's datum: datums differ by metres, convergence by < 10⁻⁴°.
            Some(g) => g
                .true_north_grid_azimuth_deg(lat, lon)
                .map_err(|e| e.to_string())?,
            None => 0.0,
        };
        Ok(gamma_output - gamma_campaign)
    }

    /// What the height column holds, for the files' first line.
    pub fn heights_label(&self) -> String {
        match &self.heights {
            OutputHeights::Copied(VerticalDatum::Unspecified) => {
                "heights as in the campaign (no height system declared)".to_string()
            }
            OutputHeights::Copied(v) => format!("heights in {v}"),
            OutputHeights::Ellipsoidal(c) => match c {
                HeightConversion::EllipsoidalToGeoid(g) => {
                    format!(
                        "ellipsoidal heights (campaign heights + geoid: {})",
                        g.describe()
                    )
                }
                HeightConversion::Identity => "ellipsoidal heights".to_string(),
            },
        }
    }
}

/// `(de, dn)` turned clockwise by `turn_deg`.
pub fn turn(de: f64, dn: f64, turn_deg: f64) -> (f64, f64) {
    let (s, c) = turn_deg.to_radians().sin_cos();
    (de * c + dn * s, dn * c - de * s)
}

/// σ of east and north turned clockwise by `turn_deg` (the diagonal of the turned covariance; the campaign's
/// σ carry no correlation).
pub fn turn_sigma(sigma_e: f64, sigma_n: f64, turn_deg: f64) -> (f64, f64) {
    let (s, c) = turn_deg.to_radians().sin_cos();
    let (ve, vn) = (sigma_e * sigma_e, sigma_n * sigma_n);
    (
        (ve * c * c + vn * s * s).sqrt(),
        (ve * s * s + vn * c * c).sqrt(),
    )
}

/// The height rule of the module doc.
fn output_heights(
    campaign: &Crs,
    output: &Crs,
    geoid: Option<GeoidModel>,
) -> Result<OutputHeights, String> {
    match (campaign.vertical, output.vertical) {
        (a, b) if a == b => Ok(OutputHeights::Copied(a)),
        (a, VerticalDatum::Unspecified) => Ok(OutputHeights::Copied(a)),
        (VerticalDatum::Unspecified, b) => Err(format!(
            "outputs.also_crs: {} has {b}, but the campaign's crs declares no height system, so its heights \
             cannot be converted — write the vertical part into crs (e.g. EPSG:28992+5709), or leave it out \
             of also_crs to copy the heights",
            output.text
        )),
        (a @ VerticalDatum::Orthometric { .. }, VerticalDatum::Ellipsoidal) => {
            let geoid = geoid.ok_or_else(|| {
                format!(
                    "outputs.also_crs: {} has ellipsoidal heights and the campaign's are {a}: give the geoid \
                     model in [outputs] (geoid_grid = \"file.gtx\" or geoid_separation_m = N)",
                    output.text
                )
            })?;
            HeightConversion::new(HeightKind::Ellipsoidal, a, Some(geoid))
                .map(OutputHeights::Ellipsoidal)
                .map_err(|e| format!("outputs: {e}"))
        }
        (a, b) => Err(format!(
            "outputs.also_crs: {} has {b} and the campaign {a}; skytie converts heights only between the \
             campaign's system and ellipsoidal heights — name the campaign's height system (or none) in \
             also_crs",
            output.text
        )),
    }
}

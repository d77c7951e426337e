//! What every importer needs: the campaign CRS and the geoid model, and converters from a source's
//! declared CRS and height system into the campaign's.

use super::config::CampaignSection;
use super::convert::Converter;
use crate::campaign::Problem;
use crate::crs::{Crs, GeoidModel, HeightKind};

/// The campaign side of an import.
#[derive(Clone)]
pub struct ImportContext {
    pub campaign_crs: Crs,
    pub geoid: Option<GeoidModel>,
}

const CONFIG: &str = "import configuration";

impl ImportContext {
    /// From `[campaign]`; `Err` when the CRS or the geoid cannot be used.
    pub fn new(section: &CampaignSection) -> Result<Self, Problem> {
        let campaign_crs = Crs::parse(&section.crs)
            .map_err(|e| Problem::error(CONFIG, None, Some("campaign.crs"), e.to_string(), ""))?;
        if !campaign_crs.is_projected() {
            return Err(Problem::error(CONFIG, None, Some("campaign.crs"), format!("{} is geographic; a campaign needs a projected CRS (metres east/north)", section.crs), "use the projected CRS of the project area, e.g. EPSG:28992+5709 or an ETRS89 / UTM zone with a vertical CRS"));
        }
        let campaign_crs = match &section.datum_grid {
            Some(grid) => campaign_crs.with_datum_grid(grid).map_err(|e| {
                Problem::error(CONFIG, None, Some("campaign.datum_grid"), e.to_string(), "")
            })?,
            None => campaign_crs,
        };
        let geoid = match (&section.geoid_grid, section.geoid_separation_m) {
            (Some(_), Some(_)) => {
                return Err(Problem::error(
                    CONFIG,
                    None,
                    Some("campaign.geoid_grid"),
                    "both a geoid grid and a constant separation are given",
                    "keep only one of geoid_grid and geoid_separation_m",
                ));
            }
            (Some(path), None) => Some(GeoidModel::read_gtx(path).map_err(|e| {
                Problem::error(CONFIG, None, Some("campaign.geoid_grid"), e.to_string(), "")
            })?),
            (None, Some(n)) if n.is_finite() => Some(GeoidModel::Constant { separation_m: n }),
            (None, Some(n)) => {
                return Err(Problem::error(
                    CONFIG,
                    None,
                    Some("campaign.geoid_separation_m"),
                    format!("{n} is not a separation"),
                    "give the geoid separation in metres",
                ));
            }
            (None, None) => None,
        };
        Ok(Self {
            campaign_crs,
            geoid,
        })
    }

    /// A converter from `source_crs` (default: the campaign's) with `heights` (default `campaign`).
    pub fn converter(
        &self,
        source_crs: Option<&str>,
        heights: Option<&str>,
    ) -> Result<Converter, Problem> {
        let parse = |text: &str| {
            Crs::parse(text)
                .map_err(|e| Problem::error(CONFIG, None, Some("crs"), e.to_string(), ""))
        };
        let source = match source_crs {
            Some(text) => match text.strip_prefix("geographic:") {
                Some(rest) => parse(rest)?.own_geographic(),
                None => parse(text)?,
            },
            None => self.campaign_crs.clone(),
        };
        let heights = HeightKind::parse(heights.unwrap_or("campaign"))
            .map_err(|m| Problem::error(CONFIG, None, Some("heights"), m, ""))?;
        Converter::new(&source, heights, &self.campaign_crs, self.geoid.clone())
            .map_err(|e| Problem::error(CONFIG, None, Some("heights"), e.to_string(), ""))
    }
}

//! Height conversion at import: heights of an input file (ellipsoidal, or in a named vertical CRS) into the
//! campaign's height system, with the geoid model the user gave. Heights are never silently mixed: every
//! combination that would need a model the user did not give is an error saying what is missing.

use super::definition::VerticalDatum;
use super::geoid::{GeoidError, GeoidModel};

/// What the heights of an input file are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeightKind {
    /// Heights above the ellipsoid of the input's geographic datum (GNSS/INS trajectories).
    Ellipsoidal,
    /// Heights already in the campaign's height system (declared by the user).
    Campaign,
    /// Heights in a named vertical CRS.
    Vertical(VerticalDatum),
}

impl HeightKind {
    /// `ellipsoidal`, `campaign` or `EPSG:<vertical code>`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let t = text.trim();
        if t.eq_ignore_ascii_case("ellipsoidal") {
            return Ok(Self::Ellipsoidal);
        }
        if t.eq_ignore_ascii_case("campaign") {
            return Ok(Self::Campaign);
        }
        let code = t
            .to_ascii_uppercase()
            .strip_prefix("EPSG:")
            .and_then(|c| c.parse::<u32>().ok())
            .ok_or_else(|| format!("'{t}' is not a height system — write \"ellipsoidal\", \"campaign\" or \"EPSG:<vertical code>\" (e.g. \"EPSG:5709\" for NAP)"))?;
        let name = super::vertical::vertical_name(code)
            .ok_or_else(|| format!("EPSG:{code} is not a supported vertical CRS"))?;
        Ok(Self::Vertical(VerticalDatum::Orthometric { code, name }))
    }
}

/// A conversion that cannot be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HeightError {
    #[error("the input heights are ellipsoidal but the campaign CRS declares {0}: give a geoid model (geoid_grid = \"file.gtx\" or geoid_separation_m = N) in the import configuration")]
    GeoidMissing(VerticalDatum),
    #[error("the input heights are ellipsoidal but the campaign CRS declares no height system: write the vertical part into the campaign CRS (e.g. crs = \"EPSG:28992+5709\") and give a geoid model")]
    CampaignVerticalMissing,
    #[error("the input heights are in {input} but the campaign uses {campaign}; skytie converts only between ellipsoidal heights and the campaign's system — convert the input heights first or declare heights = \"campaign\" if they already are")]
    Incompatible {
        input: VerticalDatum,
        campaign: VerticalDatum,
    },
    #[error(transparent)]
    Geoid(#[from] GeoidError),
}

/// Input heights → campaign heights.
#[derive(Debug, Clone, PartialEq)]
pub enum HeightConversion {
    /// Heights are taken as they are.
    Identity,
    /// `H = h − N(lat, lon)`.
    EllipsoidalToGeoid(GeoidModel),
}

impl HeightConversion {
    /// The conversion from `input` heights to the campaign's `campaign` heights.
    pub fn new(
        input: HeightKind,
        campaign: VerticalDatum,
        geoid: Option<GeoidModel>,
    ) -> Result<Self, HeightError> {
        match (input, campaign) {
            (HeightKind::Campaign, _) => Ok(Self::Identity),
            (HeightKind::Ellipsoidal, VerticalDatum::Ellipsoidal) => Ok(Self::Identity),
            (HeightKind::Ellipsoidal, VerticalDatum::Unspecified) => {
                Err(HeightError::CampaignVerticalMissing)
            }
            (HeightKind::Ellipsoidal, v @ VerticalDatum::Orthometric { .. }) => geoid
                .map(Self::EllipsoidalToGeoid)
                .ok_or(HeightError::GeoidMissing(v)),
            (HeightKind::Vertical(a), b) if a == b => Ok(Self::Identity),
            (HeightKind::Vertical(a), b) => Err(HeightError::Incompatible {
                input: a,
                campaign: b,
            }),
        }
    }

    /// Campaign height of an input height at (lat, lon) (degrees, on the input's datum).
    pub fn to_campaign(&self, lat_deg: f64, lon_deg: f64, h_m: f64) -> Result<f64, GeoidError> {
        match self {
            Self::Identity => Ok(h_m),
            Self::EllipsoidalToGeoid(g) => Ok(h_m - g.separation_m(lat_deg, lon_deg)?),
        }
    }

    /// Input height of a campaign height (the inverse, for exporters).
    pub fn from_campaign(&self, lat_deg: f64, lon_deg: f64, h_m: f64) -> Result<f64, GeoidError> {
        match self {
            Self::Identity => Ok(h_m),
            Self::EllipsoidalToGeoid(g) => Ok(h_m + g.separation_m(lat_deg, lon_deg)?),
        }
    }
}

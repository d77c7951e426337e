//! Parsing a CRS declaration such as `EPSG:28992+5709` (RD New + NAP height), `EPSG:25831` (ETRS89 / UTM 31N,
//! heights unspecified) or `EPSG:4937` (ETRS89 geographic 3D: latitude, longitude, ellipsoidal height) into
//! its horizontal part (a `proj4rs` projection built from the EPSG definition) and its height system.

use super::ellipsoid::Ellipsoid;
use super::vertical::{vertical_name, GEOGRAPHIC_3D};
use proj4rs::Proj;
use std::fmt;

/// A CRS declaration that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CrsError {
    #[error("'{0}' is not a CRS declaration — write it as EPSG:<horizontal code>[+<vertical code>], e.g. EPSG:28992+5709 (RD New + NAP height)")]
    Syntax(String),
    #[error("EPSG:{0} is not a horizontal CRS skytie knows (not in the EPSG definitions it carries, or a vertical/compound code) — give the code of the projected or geographic CRS, e.g. EPSG:28992, EPSG:25832, EPSG:4258")]
    UnknownHorizontal(u32),
    #[error("EPSG:{0} is not a supported vertical CRS — supported: {1}; or leave the vertical part out if heights are not converted")]
    UnknownVertical(u32, String),
    #[error("EPSG:{0} is a geographic 3D CRS with ellipsoidal heights; it takes no vertical part (+{1})")]
    VerticalOnGeographic3d(u32, u32),
    #[error("EPSG:{code}: the projection cannot be set up ({reason})")]
    Projection { code: u32, reason: String },
    #[error(transparent)]
    DatumGrid(#[from] super::datum_grid::DatumGridError),
}

/// Whether the horizontal coordinates are map coordinates or latitude/longitude.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HorizontalKind {
    /// Easting, northing in metres.
    Projected,
    /// Latitude, longitude in degrees.
    Geographic,
}

/// The height system of a CRS.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VerticalDatum {
    /// No vertical part declared: heights are taken as given and never converted.
    Unspecified,
    /// Heights above the ellipsoid of the horizontal datum (geographic 3D CRSs).
    Ellipsoidal,
    /// Heights in a vertical CRS (EPSG code and name), e.g. NAP height (EPSG:5709).
    Orthometric { code: u32, name: &'static str },
}

impl fmt::Display for VerticalDatum {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Unspecified => write!(f, "unspecified heights"),
            Self::Ellipsoidal => write!(f, "ellipsoidal heights"),
            Self::Orthometric { code, name } => write!(f, "{name} (EPSG:{code})"),
        }
    }
}

/// A parsed CRS: its declaration, horizontal projection and height system.
#[derive(Clone)]
pub struct Crs {
    /// The declaration as written (e.g. `EPSG:28992+5709`).
    pub text: String,
    /// EPSG code of the horizontal part.
    pub horizontal_code: u32,
    pub kind: HorizontalKind,
    pub vertical: VerticalDatum,
    /// The horizontal CRS (`proj4rs`; geographic CRSs in radians).
    pub(crate) proj: Proj,
    /// Latitude/longitude on the same datum as `proj`.
    pub(crate) geographic: Proj,
    /// The ellipsoid of the horizontal datum.
    pub ellipsoid: Ellipsoid,
    /// The proj4 definition of the horizontal part (with the datum shift it uses).
    pub(crate) definition: String,
}

impl fmt::Debug for Crs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Crs")
            .field("text", &self.text)
            .field("kind", &self.kind)
            .field("vertical", &self.vertical)
            .finish()
    }
}

impl PartialEq for Crs {
    fn eq(&self, other: &Self) -> bool {
        self.horizontal_code == other.horizontal_code && self.vertical == other.vertical
    }
}

impl Crs {
    /// Parse `EPSG:<h>[+<v>]` (case-insensitive, spaces ignored; `EPSG:<h>+EPSG:<v>` is accepted too).
    pub fn parse(text: &str) -> Result<Self, CrsError> {
        let compact: String = text.chars().filter(|c| !c.is_whitespace()).collect();
        let upper = compact.to_ascii_uppercase();
        let body = upper
            .strip_prefix("EPSG:")
            .ok_or_else(|| CrsError::Syntax(text.to_string()))?;
        let (h, v) = match body.split_once('+') {
            Some((h, v)) => (h, Some(v.strip_prefix("EPSG:").unwrap_or(v))),
            None => (body, None),
        };
        let code = |s: &str| {
            s.parse::<u32>()
                .map_err(|_| CrsError::Syntax(text.to_string()))
        };
        let horizontal_code = code(h)?;
        let vertical_code = v.map(code).transpose()?;
        let def = u16::try_from(horizontal_code)
            .ok()
            .and_then(crs_definitions::from_code)
            .ok_or(CrsError::UnknownHorizontal(horizontal_code))?;
        let proj = Proj::from_proj_string(def.proj4).map_err(|e| CrsError::Projection {
            code: horizontal_code,
            reason: e.to_string(),
        })?;
        let kind = if proj.is_latlong() {
            HorizontalKind::Geographic
        } else if proj.is_geocent() {
            return Err(CrsError::UnknownHorizontal(horizontal_code));
        } else {
            HorizontalKind::Projected
        };
        let geographic_3d = GEOGRAPHIC_3D.contains(&horizontal_code);
        let vertical = match (vertical_code, geographic_3d) {
            (Some(v), true) => return Err(CrsError::VerticalOnGeographic3d(horizontal_code, v)),
            (None, true) => VerticalDatum::Ellipsoidal,
            (None, false) => VerticalDatum::Unspecified,
            (Some(v), false) => VerticalDatum::Orthometric {
                code: v,
                name: vertical_name(v)
                    .ok_or_else(|| CrsError::UnknownVertical(v, supported_vertical_list()))?,
            },
        };
        let geographic = geographic_proj(horizontal_code, def.proj4)?;
        let (a, b) = proj.ellipse_parameters();
        Ok(Self {
            text: text.trim().to_string(),
            horizontal_code,
            kind,
            vertical,
            proj,
            geographic,
            ellipsoid: Ellipsoid::from_axes(a, b),
            definition: def.proj4.to_string(),
        })
    }

    /// This CRS with its datum shift (to ETRS89/WGS84) taken from the NTv2 grid `grid` instead of the EPSG
    /// definition's Helmert parameters ([`super::datum_grid`]): a national grid such as RDNAPTRANS's
    /// `rdtrans2018.gsb` for RD New gives millimetres where the Helmert parameters give decimetres.
    pub fn with_datum_grid(&self, grid: &std::path::Path) -> Result<Self, CrsError> {
        let key = super::datum_grid::load(grid)?;
        let mut definition: String = self
            .definition
            .split_whitespace()
            .filter(|t| !t.starts_with("+towgs84=") && !t.starts_with("+nadgrids="))
            .collect::<Vec<_>>()
            .join(" ");
        definition.push_str(&format!(" +nadgrids={key}"));
        let fail = |e: proj4rs::errors::Error| CrsError::Projection {
            code: self.horizontal_code,
            reason: e.to_string(),
        };
        let proj = Proj::from_proj_string(&definition).map_err(fail)?;
        Ok(Self {
            text: format!("{} with datum grid {}", self.text, grid.display()),
            proj,
            geographic: geographic_proj(self.horizontal_code, &definition)?,
            definition,
            ..self.clone()
        })
    }

    /// Latitude/longitude with ellipsoidal heights on this CRS's datum (e.g. for earth-centred coordinates
    /// of a Metashape chunk in this CRS).
    pub fn own_geographic(&self) -> Self {
        Self {
            text: format!("geographic 3D of {}", self.text),
            horizontal_code: self.horizontal_code,
            kind: HorizontalKind::Geographic,
            vertical: VerticalDatum::Ellipsoidal,
            proj: self.geographic.clone(),
            geographic: self.geographic.clone(),
            ellipsoid: self.ellipsoid,
            definition: geographic_definition(&self.definition),
        }
    }

    /// True for map coordinates (easting, northing).
    pub fn is_projected(&self) -> bool {
        self.kind == HorizontalKind::Projected
    }
}

/// Latitude/longitude on the datum of the proj4 definition `proj4` of EPSG:`code`.
fn geographic_proj(code: u32, proj4: &str) -> Result<Proj, CrsError> {
    Proj::from_proj_string(&geographic_definition(proj4)).map_err(|e| CrsError::Projection {
        code,
        reason: e.to_string(),
    })
}

/// `+proj=longlat` with the datum parameters (ellipsoid, datum, towgs84, nadgrids, prime meridian) of a
/// proj4 definition.
fn geographic_definition(proj4: &str) -> String {
    const DATUM_KEYS: &[&str] = &[
        "+ellps=",
        "+datum=",
        "+towgs84=",
        "+nadgrids=",
        "+a=",
        "+b=",
        "+rf=",
        "+f=",
        "+pm=",
        "+R=",
    ];
    let mut out = String::from("+proj=longlat");
    for token in proj4.split_whitespace() {
        if DATUM_KEYS.iter().any(|k| token.starts_with(k)) {
            out.push(' ');
            out.push_str(token);
        }
    }
    out.push_str(" +no_defs");
    out
}

fn supported_vertical_list() -> String {
    super::vertical::VERTICAL_CRS
        .iter()
        .map(|(c, n)| format!("EPSG:{c} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

//! Positions and attitudes from a source CRS (a vendor file's) into the campaign CRS: horizontal
//! transformation, height conversion with the user's geoid model, and the rotation of attitudes by the
//! angle between the source's north (grid north of a projected source, true north of a geographic one) and
//! the campaign's grid north at the point.

use crate::crs::heights::{HeightConversion, HeightError};
use crate::crs::transform::TransformError;
use crate::crs::{Crs, GeoidModel, HeightKind, HorizontalTransform};
use crate::geometry::rot_z;
use nalgebra::Matrix3;

/// Step for the north direction: 1 m in a projected source, 1e-5° in a geographic one.
const NORTH_STEP_M: f64 = 1.0;
const NORTH_STEP_DEG: f64 = 1e-5;
/// Fixed-point steps of an exact inverse (two reach 1e-12 m for datum shifts; a bound, not a tolerance).
const MAX_REFINEMENTS: usize = 8;

/// A conversion source → campaign.
#[derive(Clone)]
pub struct Converter {
    source: Crs,
    /// Source and campaign share the horizontal CRS: coordinates and attitudes pass unchanged (exactly).
    same_horizontal: bool,
    forward: HorizontalTransform,
    /// Source native → ETRS89 latitude/longitude (where geoid models are given).
    to_geoid_lookup: HorizontalTransform,
    heights: HeightConversion,
}

/// A point that could not be converted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConvertError {
    #[error(transparent)]
    Transform(#[from] TransformError),
    #[error(transparent)]
    Geoid(#[from] crate::crs::GeoidError),
}

impl Converter {
    /// From `source` (whose heights are `heights`) to `campaign`.
    pub fn new(
        source: &Crs,
        heights: HeightKind,
        campaign: &Crs,
        geoid: Option<GeoidModel>,
    ) -> Result<Self, HeightError> {
        let etrs89 = Crs::parse("EPSG:4258").expect("ETRS89 is a known CRS");
        Ok(Self {
            source: source.clone(),
            same_horizontal: source.horizontal_code == campaign.horizontal_code
                && source.kind == campaign.kind,
            forward: HorizontalTransform::new(source, campaign),
            to_geoid_lookup: HorizontalTransform::new(source, &etrs89),
            heights: HeightConversion::new(heights, campaign.vertical, geoid)?,
        })
    }

    /// Campaign (x, y, z) of a source native pair and height.
    ///
    /// Ellipsoidal heights are first taken to ETRS89 through the datum shift (a source on another datum has
    /// its own ellipsoid), then reduced by the geoid separation there.
    pub fn position(&self, a: f64, b: f64, h_m: f64) -> Result<(f64, f64, f64), ConvertError> {
        let (x, y) = self.across(&self.forward, a, b)?;
        let z = match self.heights {
            HeightConversion::Identity => h_m,
            _ => {
                let (lat, lon, h_etrs) = self.to_geoid_lookup.apply3(a, b, h_m)?;
                self.heights.to_campaign(lat, lon, h_etrs)?
            }
        };
        Ok((x, y, z))
    }

    /// A horizontal pair taken across `t` (one direction between source and campaign), or unchanged when both
    /// share the horizontal CRS.
    fn across(
        &self,
        t: &HorizontalTransform,
        a: f64,
        b: f64,
    ) -> Result<(f64, f64), TransformError> {
        if self.same_horizontal {
            Ok((a, b))
        } else {
            t.apply(a, b)
        }
    }

    /// Grid azimuth (campaign, degrees) of the source's north direction at a source native pair.
    pub fn north_azimuth_deg(&self, a: f64, b: f64) -> Result<f64, TransformError> {
        if self.same_horizontal {
            return Ok(0.0);
        }
        let (da, db) = if self.source.is_projected() {
            (0.0, NORTH_STEP_M)
        } else {
            (NORTH_STEP_DEG, 0.0)
        };
        let (x1, y1) = self.forward.apply(a - da, b - db)?;
        let (x2, y2) = self.forward.apply(a + da, b + db)?;
        Ok((x2 - x1).atan2(y2 - y1).to_degrees())
    }

    /// A camera→source-world rotation as camera→campaign-world: turned clockwise by the north azimuth.
    pub fn rotation(
        &self,
        a: f64,
        b: f64,
        r: &Matrix3<f64>,
    ) -> Result<Matrix3<f64>, TransformError> {
        Ok(rot_z(-self.north_azimuth_deg(a, b)?.to_radians()) * r)
    }

    /// The inverse direction (campaign → source), for exporters.
    pub fn inverse(
        &self,
        campaign: &Crs,
        source_heights: HeightKind,
        geoid: Option<GeoidModel>,
    ) -> Result<Inverse, HeightError> {
        let etrs89 = Crs::parse("EPSG:4258").expect("ETRS89 is a known CRS");
        Ok(Inverse {
            backward: HorizontalTransform::new(campaign, &self.source),
            forward: self.clone(),
            to_geoid_lookup: HorizontalTransform::new(campaign, &etrs89),
            from_etrs89: HorizontalTransform::new(&etrs89, &self.source),
            heights: HeightConversion::new(source_heights, campaign.vertical, geoid)?,
        })
    }
}

/// Campaign → source, the exact inverse of a [`Converter`] (positions by the inverse transformation,
/// rotations by the same north azimuth evaluated at the source point).
#[derive(Clone)]
pub struct Inverse {
    backward: HorizontalTransform,
    forward: Converter,
    to_geoid_lookup: HorizontalTransform,
    from_etrs89: HorizontalTransform,
    heights: HeightConversion,
}

impl Inverse {
    /// Source native pair and height of a campaign point: the point the importer's [`Converter`] takes to
    /// (x, y, z), to its rounding. The inverse transformation alone is not quite that: PROJ-style inverse
    /// Helmert shifts reuse the small-angle rotation matrix transposed, which is off by the square of the
    /// rotation (≈ 0.5 mm for the Amersfoort parameters), so the result is refined by fixed-point steps
    /// `s ← s + B(p) − B(F(s))` (F the importer's conversion, B the inverse transformation) until the step is
    /// below 1e-10 of a unit.
    pub fn position(&self, x: f64, y: f64, z: f64) -> Result<(f64, f64, f64), ConvertError> {
        let first = self.approximate(x, y, z)?;
        let mut s = first;
        for _ in 0..MAX_REFINEMENTS {
            let f = self.forward.position(s.0, s.1, s.2)?;
            let back = self.approximate(f.0, f.1, f.2)?;
            let step = (first.0 - back.0, first.1 - back.1, first.2 - back.2);
            s = (s.0 + step.0, s.1 + step.1, s.2 + step.2);
            if step.0.abs().max(step.1.abs()).max(step.2.abs()) < 1e-10 {
                break;
            }
        }
        Ok(s)
    }

    /// The inverse transformation of a campaign point (see [`Inverse::position`]).
    fn approximate(&self, x: f64, y: f64, z: f64) -> Result<(f64, f64, f64), ConvertError> {
        let (a, b) = self.forward.across(&self.backward, x, y)?;
        let h = match self.heights {
            HeightConversion::Identity => z,
            _ => {
                let (lat, lon) = self.to_geoid_lookup.apply(x, y)?;
                let h_etrs = self.heights.from_campaign(lat, lon, z)?;
                // Back onto the source datum's ellipsoid.
                self.from_etrs89.apply3(lat, lon, h_etrs)?.2
            }
        };
        Ok((a, b, h))
    }

    /// A camera→campaign rotation as camera→source at source point (a, b).
    pub fn rotation(
        &self,
        a: f64,
        b: f64,
        r: &Matrix3<f64>,
    ) -> Result<Matrix3<f64>, TransformError> {
        Ok(rot_z(self.forward.north_azimuth_deg(a, b)?.to_radians()) * r)
    }
}

//! Coordinate reference systems for importing vendor data into a campaign: the campaign's declared CRS
//! (horizontal + vertical, e.g. `EPSG:28992+5709`), horizontal transformations between CRSs (pure-Rust
//! `proj4rs` with the EPSG definitions of `crs-definitions`, or a national NTv2 grid: [`datum_grid`]),
//! geoid models for ellipsoidal ↔ orthometric heights, meridian convergence and point scale factor of a map
//! projection, geodetic ↔ earth-centred coordinates and a local tangent (east-north-up) frame for
//! computations that need a Cartesian frame ([`map_frame`]: where the pipeline intersects aerial rays and
//! adjusts aerial pixel observations), and the second CRS a run's outputs are also written in
//! ([`second_crs`]).
//!
//! Units: geographic coordinates in degrees (latitude, longitude), projected coordinates and heights in
//! metres, angles of convergence in degrees (`_deg`).

pub mod campaign_frame;
pub mod datum_grid;
pub mod definition;
pub mod ellipsoid;
pub mod error_budget;
pub mod geoid;
pub mod grid_north;
pub mod heights;
pub mod map_frame;
pub mod second_crs;
pub mod transform;
mod vertical;

#[cfg(test)]
mod tests;

pub use campaign_frame::{CampaignFrame, FrameError};
pub use datum_grid::DatumGridError;
pub use definition::{Crs, CrsError, HorizontalKind, VerticalDatum};
pub use ellipsoid::{Ellipsoid, LocalTangentFrame};
pub use geoid::{GeoidError, GeoidModel};
pub use grid_north::GridNorth;
pub use heights::{HeightConversion, HeightKind};
pub use map_frame::{CoordinateFrame, MapFrame, MapFrameSpec};
pub use second_crs::{OutputHeights, OutputsSection, SecondCrs};
pub use transform::{Geographic, HorizontalTransform};

//! Geoid models: the separation N between the ellipsoid and the height reference surface, so that an
//! orthometric (or normal) height is `H = h − N` for an ellipsoidal height `h`.
//!
//! Either a constant separation (for a small area, from the national geodetic agency's value at the site) or
//! a grid file in the GTX format (NOAA VDatum / PROJ vertical grids): a big-endian header of four f64 —
//! latitude and longitude of the south-west node, latitude and longitude spacing, all in degrees — and two
//! i32 (rows, columns), then rows × columns f32 separations in metres, row by row from the south, west to
//! east; −88.8888 marks a node without value. Values are interpolated bilinearly.

use std::path::{Path, PathBuf};

/// A separation that cannot be given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeoidError {
    #[error("{}: cannot be read as a GTX geoid grid ({reason}) — give a .gtx file (NOAA/PROJ vertical grid) or a constant separation", path.display())]
    Unreadable { path: PathBuf, reason: String },
    #[error("({lat_deg}°, {lon_deg}°) lies outside the geoid grid {} or on a node without value — use a grid that covers the campaign area", path.display())]
    Outside {
        path: PathBuf,
        lat_deg: f64,
        lon_deg: f64,
    },
}

/// The separation ellipsoid → height surface, metres.
#[derive(Debug, Clone, PartialEq)]
pub enum GeoidModel {
    /// The same separation everywhere, m.
    Constant { separation_m: f64 },
    /// A regular latitude/longitude grid.
    Grid(GeoidGrid),
}

/// A GTX grid in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct GeoidGrid {
    pub path: PathBuf,
    pub south_lat_deg: f64,
    pub west_lon_deg: f64,
    pub dlat_deg: f64,
    pub dlon_deg: f64,
    pub rows: usize,
    pub cols: usize,
    /// Row-major from the south-west node, metres (NaN where the file has no value).
    pub values_m: Vec<f32>,
}

const GTX_NO_VALUE: f32 = -88.8888;
const GTX_HEADER_BYTES: usize = 40;

impl GeoidModel {
    /// The model a table names by its keys `geoid_grid` (a GTX file relative to `root`) or
    /// `geoid_separation_m` (a constant): `None` when it names neither; `Err` (prefixed with the table's
    /// `table` name) when it names both or one cannot be used.
    pub fn from_keys(
        table: &str,
        grid: Option<&Path>,
        separation_m: Option<f64>,
        root: &Path,
    ) -> Result<Option<Self>, String> {
        match (grid, separation_m) {
            (Some(_), Some(_)) => Err(format!(
                "{table}: both geoid_grid and geoid_separation_m are given; keep one"
            )),
            (Some(g), None) => Self::read_gtx(&root.join(g))
                .map(Some)
                .map_err(|e| format!("{table}.geoid_grid: {e}")),
            (None, Some(n)) if n.is_finite() => Ok(Some(Self::Constant { separation_m: n })),
            (None, Some(n)) => Err(format!(
                "{table}.geoid_separation_m: {n} is not a separation"
            )),
            (None, None) => Ok(None),
        }
    }

    /// Separation N at (lat, lon), metres.
    pub fn separation_m(&self, lat_deg: f64, lon_deg: f64) -> Result<f64, GeoidError> {
        match self {
            Self::Constant { separation_m } => Ok(*separation_m),
            Self::Grid(grid) => grid.separation_m(lat_deg, lon_deg),
        }
    }

    /// Read a GTX grid file.
    pub fn read_gtx(path: &Path) -> Result<Self, GeoidError> {
        let bytes = std::fs::read(path).map_err(|e| GeoidError::Unreadable {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        GeoidGrid::parse_gtx(path, &bytes).map(Self::Grid)
    }

    /// A short description for reports.
    pub fn describe(&self) -> String {
        match self {
            Self::Constant { separation_m } => format!("constant separation {separation_m} m"),
            Self::Grid(g) => format!("grid {} ({} × {} nodes)", g.path.display(), g.rows, g.cols),
        }
    }
}

impl GeoidGrid {
    fn parse_gtx(path: &Path, bytes: &[u8]) -> Result<Self, GeoidError> {
        let bad = |reason: String| GeoidError::Unreadable {
            path: path.to_path_buf(),
            reason,
        };
        if bytes.len() < GTX_HEADER_BYTES {
            return Err(bad(format!(
                "{} bytes, shorter than the 40-byte header",
                bytes.len()
            )));
        }
        let f = |i: usize| f64::from_be_bytes(bytes[i..i + 8].try_into().expect("8 bytes"));
        let n = |i: usize| i32::from_be_bytes(bytes[i..i + 4].try_into().expect("4 bytes"));
        let (south, mut west, dlat, dlon) = (f(0), f(8), f(16), f(24));
        let (rows, cols) = (n(32), n(36));
        let header_ok =
            rows > 1 && cols > 1 && dlat > 0.0 && dlon > 0.0 && (-90.0..=90.0).contains(&south);
        if !header_ok {
            return Err(bad(format!(
                "header says {rows} rows × {cols} columns, spacing {dlat}° × {dlon}°, south {south}°"
            )));
        }
        let (rows, cols) = (rows as usize, cols as usize);
        let expected = GTX_HEADER_BYTES + rows * cols * 4;
        if bytes.len() != expected {
            return Err(bad(format!(
                "{} bytes, the header announces {expected}",
                bytes.len()
            )));
        }
        if west > 180.0 {
            west -= 360.0;
        }
        let values_m = bytes[GTX_HEADER_BYTES..]
            .chunks_exact(4)
            .map(|c| {
                let v = f32::from_be_bytes(c.try_into().expect("4 bytes"));
                if (v - GTX_NO_VALUE).abs() < 1e-3 {
                    f32::NAN
                } else {
                    v
                }
            })
            .collect();
        Ok(Self {
            path: path.to_path_buf(),
            south_lat_deg: south,
            west_lon_deg: west,
            dlat_deg: dlat,
            dlon_deg: dlon,
            rows,
            cols,
            values_m,
        })
    }

    /// Write a grid as GTX (for tests and exports of synthetic campaigns).
    pub fn to_gtx_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(GTX_HEADER_BYTES + self.values_m.len() * 4);
        for v in [
            self.south_lat_deg,
            self.west_lon_deg,
            self.dlat_deg,
            self.dlon_deg,
        ] {
            out.extend_from_slice(&v.to_be_bytes());
        }
        out.extend_from_slice(&(self.rows as i32).to_be_bytes());
        out.extend_from_slice(&(self.cols as i32).to_be_bytes());
        for v in &self.values_m {
            let v = if v.is_nan() { GTX_NO_VALUE } else { *v };
            out.extend_from_slice(&v.to_be_bytes());
        }
        out
    }

    /// Bilinear interpolation of the four surrounding nodes.
    pub fn separation_m(&self, lat_deg: f64, lon_deg: f64) -> Result<f64, GeoidError> {
        let outside = || GeoidError::Outside {
            path: self.path.clone(),
            lat_deg,
            lon_deg,
        };
        let mut lon = lon_deg;
        if lon < self.west_lon_deg {
            lon += 360.0;
        }
        let r = (lat_deg - self.south_lat_deg) / self.dlat_deg;
        let c = (lon - self.west_lon_deg) / self.dlon_deg;
        let (max_r, max_c) = ((self.rows - 1) as f64, (self.cols - 1) as f64);
        if !(r >= 0.0 && r <= max_r && c >= 0.0 && c <= max_c) {
            return Err(outside());
        }
        let (r0, c0) = (
            (r.floor() as usize).min(self.rows - 2),
            (c.floor() as usize).min(self.cols - 2),
        );
        let (fr, fc) = (r - r0 as f64, c - c0 as f64);
        let at = |i: usize, j: usize| f64::from(self.values_m[i * self.cols + j]);
        // Nodes with zero weight do not count (a point on a valid edge next to a void is fine).
        let v: f64 = [
            ((1.0 - fr) * (1.0 - fc), r0, c0),
            ((1.0 - fr) * fc, r0, c0 + 1),
            (fr * (1.0 - fc), r0 + 1, c0),
            (fr * fc, r0 + 1, c0 + 1),
        ]
        .iter()
        .filter(|(w, _, _)| *w > 0.0)
        .map(|&(w, i, j)| w * at(i, j))
        .sum();
        if v.is_finite() {
            Ok(v)
        } else {
            Err(outside())
        }
    }
}

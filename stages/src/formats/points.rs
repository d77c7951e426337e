//! Check points (id, X, Y, Z and optional standard deviations) and their image measurements (point id,
//! panorama, u, v) from delimited lists in any declared layout. Pixel positions are converted to skytie's
//! continuous convention (image corner at 0, first pixel centre at 0.5) from the declared origin.

use super::text_table::{Delimiter, RowReader, TextTable};
use crate::campaign::Problem;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Layout of a point list.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointFormat {
    pub delimiter: Delimiter,
    #[serde(default = "yes")]
    pub header: bool,
    pub id: String,
    /// Easting or latitude.
    pub x: String,
    /// Northing or longitude.
    pub y: String,
    pub z: String,
    #[serde(default)]
    pub sigma_xy: Option<String>,
    #[serde(default)]
    pub sigma_z: Option<String>,
}

/// One point as read (coordinates in the file's CRS).
#[derive(Debug, Clone, PartialEq)]
pub struct PointRow {
    pub line: usize,
    pub id: String,
    pub a: f64,
    pub b: f64,
    pub z: f64,
    pub sigma_xy_m: Option<f64>,
    pub sigma_z_m: Option<f64>,
}

/// Where pixel (0, 0) lies in a measurement file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PixelOrigin {
    /// (0, 0) is the top-left corner of the image (skytie's convention).
    Corner,
    /// (0, 0) is the centre of the top-left pixel (OpenCV, most image viewers): +0.5 on import.
    FirstPixelCentre,
}

/// Layout of an image measurement list.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasurementFormat {
    pub delimiter: Delimiter,
    #[serde(default = "yes")]
    pub header: bool,
    pub point: String,
    pub image: String,
    pub u: String,
    pub v: String,
    pub pixel_origin: PixelOrigin,
}

fn yes() -> bool {
    true
}

/// One measurement in skytie's pixel convention.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasurementRow {
    pub line: usize,
    pub point: String,
    pub image: String,
    pub u_px: f64,
    pub v_px: f64,
}

fn columns(table: &TextTable, names: &[&str], problems: &mut Vec<Problem>) -> Option<Vec<usize>> {
    let cols: Vec<Option<usize>> = names
        .iter()
        .map(|n| table.column(n).map_err(|p| problems.push(p)).ok())
        .collect();
    cols.into_iter().collect()
}

/// Read a point list.
pub fn read_points(path: &Path, f: &PointFormat) -> (Vec<PointRow>, Vec<Problem>) {
    let table = match TextTable::read(path, f.delimiter, f.header, false) {
        Ok(t) => t,
        Err(p) => return (Vec::new(), vec![p]),
    };
    let mut names = vec![f.id.as_str(), &f.x, &f.y, &f.z];
    names.extend(f.sigma_xy.as_deref());
    names.extend(f.sigma_z.as_deref());
    let mut problems = Vec::new();
    let Some(cols) = columns(&table, &names, &mut problems) else {
        return (Vec::new(), problems);
    };
    let mut rows = Vec::new();
    for (line, cells) in &table.rows {
        let mut r = RowReader::new(path, *line, cells);
        let id = r.text(cols[0], names[0]);
        let (a, b, z) = (
            r.number(cols[1], names[1]),
            r.number(cols[2], names[2]),
            r.number(cols[3], names[3]),
        );
        let mut next = 4;
        let mut sigma = |present: bool, r: &mut RowReader| {
            present.then(|| {
                let v = r.number(cols[next], names[next]);
                if v.is_finite() && v <= 0.0 {
                    r.error(
                        names[next],
                        format!("{v} is not a standard deviation"),
                        "give a value > 0 m",
                    );
                }
                next += 1;
                v
            })
        };
        let sigma_xy_m = sigma(f.sigma_xy.is_some(), &mut r);
        let sigma_z_m = sigma(f.sigma_z.is_some(), &mut r);
        if r.ok() {
            rows.push(PointRow {
                line: *line,
                id,
                a,
                b,
                z,
                sigma_xy_m,
                sigma_z_m,
            });
        }
        problems.append(&mut r.problems);
    }
    (rows, problems)
}

/// Read an image measurement list.
pub fn read_measurements(
    path: &Path,
    f: &MeasurementFormat,
) -> (Vec<MeasurementRow>, Vec<Problem>) {
    let table = match TextTable::read(path, f.delimiter, f.header, false) {
        Ok(t) => t,
        Err(p) => return (Vec::new(), vec![p]),
    };
    let names = [f.point.as_str(), &f.image, &f.u, &f.v];
    let mut problems = Vec::new();
    let Some(cols) = columns(&table, &names, &mut problems) else {
        return (Vec::new(), problems);
    };
    let shift = match f.pixel_origin {
        PixelOrigin::Corner => 0.0,
        PixelOrigin::FirstPixelCentre => 0.5,
    };
    let mut rows = Vec::new();
    for (line, cells) in &table.rows {
        let mut r = RowReader::new(path, *line, cells);
        let point = r.text(cols[0], names[0]);
        let image = r.text(cols[1], names[1]);
        let (u, v) = (r.number(cols[2], names[2]), r.number(cols[3], names[3]));
        if r.ok() {
            rows.push(MeasurementRow {
                line: *line,
                point,
                image,
                u_px: u + shift,
                v_px: v + shift,
            });
        }
        problems.append(&mut r.problems);
    }
    (rows, problems)
}

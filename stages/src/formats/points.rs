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

/// Write a point list (comma-separated, header `id,x,y,z` plus `sigma_xy`/`sigma_z` where `rows` carry them)
/// and return the layout that reads it back. `Err` if only some rows carry a σ (one layout cannot hold both).
pub fn write_points(path: &Path, rows: &[PointRow]) -> std::io::Result<PointFormat> {
    let all_or_none = |has: &dyn Fn(&PointRow) -> bool, name: &str| {
        let n = rows.iter().filter(|r| has(r)).count();
        if n != 0 && n != rows.len() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "{n} of {} points have {name}; give it for all or none",
                    rows.len()
                ),
            ));
        }
        Ok(n > 0)
    };
    let with_sxy = all_or_none(&|r| r.sigma_xy_m.is_some(), "sigma_xy")?;
    let with_sz = all_or_none(&|r| r.sigma_z_m.is_some(), "sigma_z")?;
    let mut out = String::from("id,x,y,z");
    out.push_str(if with_sxy { ",sigma_xy" } else { "" });
    out.push_str(if with_sz { ",sigma_z" } else { "" });
    out.push('\n');
    for r in rows {
        out.push_str(&format!("{},{},{},{}", r.id, r.a, r.b, r.z));
        for s in [r.sigma_xy_m, r.sigma_z_m].into_iter().flatten() {
            out.push_str(&format!(",{s}"));
        }
        out.push('\n');
    }
    crate::fsutil::atomic_write(path, out.as_bytes())?;
    Ok(PointFormat {
        delimiter: Delimiter::Comma,
        header: true,
        id: "id".into(),
        x: "x".into(),
        y: "y".into(),
        z: "z".into(),
        sigma_xy: with_sxy.then(|| "sigma_xy".into()),
        sigma_z: with_sz.then(|| "sigma_z".into()),
    })
}

/// Write image measurements (comma-separated `point,image,u,v`, `u_px`/`v_px` of `rows` given in skytie's
/// convention and written with `origin`) and return the layout that reads them back.
pub fn write_measurements(
    path: &Path,
    rows: &[MeasurementRow],
    origin: PixelOrigin,
) -> std::io::Result<MeasurementFormat> {
    let shift = match origin {
        PixelOrigin::Corner => 0.0,
        PixelOrigin::FirstPixelCentre => 0.5,
    };
    let mut out = String::from("point,image,u,v\n");
    for r in rows {
        out.push_str(&format!(
            "{},{},{},{}\n",
            r.point,
            r.image,
            r.u_px - shift,
            r.v_px - shift
        ));
    }
    crate::fsutil::atomic_write(path, out.as_bytes())?;
    Ok(MeasurementFormat {
        delimiter: Delimiter::Comma,
        header: true,
        point: "point".into(),
        image: "image".into(),
        u: "u".into(),
        v: "v".into(),
        pixel_origin: origin,
    })
}

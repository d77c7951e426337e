//! Generic trajectory tables: time, position (latitude/longitude in degrees or radians, or projected
//! easting/northing), height, and the body attitude roll, pitch, heading (degrees or radians), in any
//! delimited layout the user declares. Heading is clockwise from north, pitch nose up, roll right side
//! down (the SBET convention); whether north is true or grid north is declared, never assumed.

use super::angles::AngleUnit;
use super::events::TimeSystem;
use super::text_table::{Delimiter, RowReader, TextTable};
use crate::campaign::Problem;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One trajectory sample in the file's CRS: `a`, `b` its native pair (latitude, longitude in degrees, or
/// easting, northing in metres), `h_m` the height as given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrajectorySample {
    /// Line (text) or record number (binary), 1-based.
    pub line: usize,
    pub time_unix_s: f64,
    pub a: f64,
    pub b: f64,
    pub h_m: f64,
    pub roll_deg: f64,
    pub pitch_deg: f64,
    pub heading_deg: f64,
}

/// Column names (or 1-based positions).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectoryColumns {
    pub time: String,
    /// Latitude or easting.
    pub a: String,
    /// Longitude or northing.
    pub b: String,
    pub height: String,
    pub roll: String,
    pub pitch: String,
    pub heading: String,
}

/// The layout of a trajectory table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectoryCsvFormat {
    pub delimiter: Delimiter,
    #[serde(default = "yes")]
    pub header: bool,
    pub columns: TrajectoryColumns,
    pub time: TimeSystem,
    /// Unit of latitude/longitude (ignored for projected coordinates).
    #[serde(default = "degrees")]
    pub position_unit: AngleUnit,
    pub angle_unit: AngleUnit,
}

fn yes() -> bool {
    true
}

fn degrees() -> AngleUnit {
    AngleUnit::Degrees
}

/// Read a trajectory table; `geographic` says whether a/b are latitude/longitude.
pub fn read_trajectory_csv(
    path: &Path,
    format: &TrajectoryCsvFormat,
    geographic: bool,
) -> (Vec<TrajectorySample>, Vec<Problem>) {
    let table = match TextTable::read(path, format.delimiter, format.header, false) {
        Ok(t) => t,
        Err(p) => return (Vec::new(), vec![p]),
    };
    let c = &format.columns;
    let names = [
        &c.time, &c.a, &c.b, &c.height, &c.roll, &c.pitch, &c.heading,
    ];
    let mut problems = Vec::new();
    let cols: Vec<Option<usize>> = names
        .iter()
        .map(|n| table.column(n).map_err(|p| problems.push(p)).ok())
        .collect();
    if cols.iter().any(Option::is_none) {
        return (Vec::new(), problems);
    }
    let cols: Vec<usize> = cols.into_iter().flatten().collect();
    let mut samples: Vec<TrajectorySample> = Vec::with_capacity(table.rows.len());
    for (line, cells) in &table.rows {
        let mut r = RowReader::new(path, *line, cells);
        let time_text = r.text(cols[0], &c.time);
        let [a, b, h, roll, pitch, heading] =
            [1, 2, 3, 4, 5, 6].map(|k| r.number(cols[k], names[k]));
        let time = if r.ok() {
            format
                .time
                .parse(&time_text)
                .map_err(|m| r.error(&c.time, m, "write the time in the declared time system"))
                .ok()
        } else {
            None
        };
        let (a, b) = if geographic {
            (
                format.position_unit.to_degrees(a),
                format.position_unit.to_degrees(b),
            )
        } else {
            (a, b)
        };
        if geographic && r.ok() && (a.abs() > 90.0 || b.abs() > 360.0) {
            r.error(
                &c.a,
                format!("latitude {a}° / longitude {b}° out of range"),
                "check the column mapping and position_unit",
            );
        }
        if let (Some(t), true) = (time, r.ok()) {
            if samples.last().is_some_and(|s| t <= s.time_unix_s) {
                r.error(
                    &c.time,
                    "does not come after the previous row in time",
                    "sort the trajectory by time and remove duplicates",
                );
            } else {
                let u = format.angle_unit;
                samples.push(TrajectorySample {
                    line: *line,
                    time_unix_s: t,
                    a,
                    b,
                    h_m: h,
                    roll_deg: u.to_degrees(roll),
                    pitch_deg: u.to_degrees(pitch),
                    heading_deg: u.to_degrees(heading),
                });
            }
        }
        problems.append(&mut r.problems);
    }
    (samples, problems)
}

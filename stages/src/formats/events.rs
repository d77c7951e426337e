//! Image event files: one row per exposure with its time and the image it belongs to (POSPac event
//! exports, camera logs), in any delimited layout the user declares; and the time systems of trajectories
//! and events (UTC ISO 8601, GPS seconds of week with the week number, GPS seconds since the GPS epoch,
//! Unix seconds), all turned into Unix seconds UTC.

use super::gps_time::{gps_to_unix_s, GPS_EPOCH_UNIX_S};
use super::text_table::{Delimiter, RowReader, TextTable};
use crate::campaign::{parse_time_s, Problem};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How a time column is written.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "system", rename_all = "kebab-case", deny_unknown_fields)]
pub enum TimeSystem {
    /// ISO 8601 with a zone (`2019-06-14T10:31:07.25Z`).
    UtcIso,
    /// GPS seconds of week; the week is not in the file and must be given.
    GpsSecondsOfWeek {
        gps_week: u32,
        #[serde(default)]
        leap_seconds: Option<f64>,
    },
    /// GPS seconds since 1980-01-06T00:00:00Z.
    GpsSeconds {
        #[serde(default)]
        leap_seconds: Option<f64>,
    },
    /// Seconds since 1970-01-01T00:00:00Z, UTC.
    UnixSeconds,
}

impl TimeSystem {
    /// Unix seconds (UTC) of one cell.
    pub fn parse(&self, cell: &str) -> Result<f64, String> {
        if let Self::UtcIso = self {
            return parse_time_s(cell);
        }
        let v: f64 = cell
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| format!("'{cell}' is not a number of seconds"))?;
        Ok(self.seconds_to_unix(v))
    }

    /// Unix seconds (UTC) of a numeric time in this system (ISO: the value is taken as Unix seconds).
    pub fn seconds_to_unix(&self, v: f64) -> f64 {
        match *self {
            Self::UtcIso | Self::UnixSeconds => v,
            Self::GpsSecondsOfWeek {
                gps_week,
                leap_seconds,
            } => gps_to_unix_s(gps_week, v, leap_seconds),
            Self::GpsSeconds { leap_seconds } => {
                let week = (v / super::gps_time::WEEK_S).floor();
                gps_to_unix_s(
                    week as u32,
                    v - week * super::gps_time::WEEK_S,
                    leap_seconds,
                )
            }
        }
    }
}

/// Unix seconds of the GPS epoch, re-exported for callers that build GPS seconds.
pub const GPS_EPOCH: f64 = GPS_EPOCH_UNIX_S;

/// The layout of an event file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EventFormat {
    pub delimiter: Delimiter,
    #[serde(default = "yes")]
    pub header: bool,
    /// Column of the time (name or 1-based position).
    pub time_column: String,
    /// Column of the image file name (name or 1-based position).
    pub image_column: String,
    pub time: TimeSystem,
}

fn yes() -> bool {
    true
}

/// One exposure.
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    pub line: usize,
    pub image: String,
    /// Unix seconds, UTC.
    pub time_unix_s: f64,
}

/// Read an event file; bad rows are reported and left out.
pub fn read_events(path: &Path, format: &EventFormat) -> (Vec<Event>, Vec<Problem>) {
    let table = match TextTable::read(path, format.delimiter, format.header, false) {
        Ok(t) => t,
        Err(p) => return (Vec::new(), vec![p]),
    };
    let (t_col, i_col) = match (
        table.column(&format.time_column),
        table.column(&format.image_column),
    ) {
        (Ok(t), Ok(i)) => (t, i),
        (a, b) => {
            return (
                Vec::new(),
                [a.err(), b.err()].into_iter().flatten().collect(),
            )
        }
    };
    let mut events = Vec::new();
    let mut problems = Vec::new();
    for (line, cells) in &table.rows {
        let mut r = RowReader::new(path, *line, cells);
        let image = r.text(i_col, &format.image_column);
        let time = r.text(t_col, &format.time_column);
        let parsed = if r.ok() {
            format.time.parse(&time)
        } else {
            Err(String::new())
        };
        match parsed {
            Ok(t) => events.push(Event {
                line: *line,
                image,
                time_unix_s: t,
            }),
            Err(m) if !m.is_empty() => {
                r.error(
                    &format.time_column,
                    m,
                    "write the time in the declared time system",
                );
                problems.append(&mut r.problems);
            }
            Err(_) => problems.append(&mut r.problems),
        }
    }
    (events, problems)
}

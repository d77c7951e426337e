//! The mobile-mapping side: a trajectory (SBET or table) and an image event file → `mm/recordings.csv` rows
//! in the campaign CRS. Each event is placed on the trajectory by linear interpolation between the two
//! samples around its time (events outside the trajectory, or in a gap longer than `max_gap_s`, are
//! skipped); the lever arm moves the IMU position to the panorama centre; the panorama attitude comes from
//! the IMU and the boresight, or from the event file; true north is turned into the campaign's grid north
//! by the meridian convergence at the panorama.

use super::config::{MmSource, North, PanoramaOrientation, TrajectoryFormat};
use super::context::ImportContext;
use super::panorama_row::{panorama_row, PanoramaPlacement};
use super::pose::{body_to_ned, panorama_angles, panorama_matrix, panorama_to_enu, LeverArm};
use super::report::SourceReport;
use crate::campaign::{format_time_iso, Problem, Recording};
use crate::crs::{Crs, Ellipsoid, GridNorth, HorizontalTransform};
use crate::formats::events::{read_events, Event};
use crate::formats::gps_time::gps_to_unix_s;
use crate::formats::sbet::read_sbet;
use crate::formats::text_table::TextTable;
use crate::formats::trajectory_csv::{read_trajectory_csv, TrajectorySample};

const CONFIG: &str = "import configuration";

/// Import the trajectory and events of `[mm]`.
pub fn import_mm(src: &MmSource, ctx: &ImportContext) -> (Vec<Recording>, SourceReport) {
    let mut report = SourceReport::new("mobile mapping", &src.trajectory);
    match import_inner(src, ctx, &mut report) {
        Ok(rows) => {
            report.converted = rows.len();
            (rows, report)
        }
        Err(p) => {
            report.problems.push(p);
            (Vec::new(), report)
        }
    }
}

fn config_error(field: &str, message: impl Into<String>, hint: &str) -> Problem {
    Problem::error(CONFIG, None, Some(field), message, hint)
}

fn import_inner(
    src: &MmSource,
    ctx: &ImportContext,
    report: &mut SourceReport,
) -> Result<Vec<Recording>, Problem> {
    let traj_crs = Crs::parse(&src.crs).map_err(|e| config_error("mm.crs", e.to_string(), ""))?;
    let (samples, true_north) = read_samples(src, &traj_crs, report)?;
    if samples.len() < 2 {
        return Err(Problem::error(
            &src.trajectory,
            None,
            None,
            format!(
                "has {} usable samples; at least 2 are needed",
                samples.len()
            ),
            "check the file and its format",
        ));
    }
    // Geodetic view of the trajectory (the lever arm and attitudes are applied there).
    let to_geo = HorizontalTransform::to_own_geographic(&traj_crs);
    let grid = GridNorth::new(&traj_crs);
    let converter = ctx.converter(Some(&format!("geographic:{}", src.crs)), Some(&src.heights))?;
    report.notes.push(format!(
        "trajectory {} ({} samples, heights {}) → {}; panorama attitude from {}",
        src.crs,
        samples.len(),
        src.heights,
        ctx.campaign_crs.text,
        match src.orientation {
            PanoramaOrientation::Imu => "the IMU with the boresight",
            PanoramaOrientation::EventColumns => "the event file (true north)",
        }
    ));
    let (events, problems) = read_events(&src.events, &src.event_layout);
    report.read = events.len() + problems.len();
    report.problems.extend(problems);
    let pano_cols = pano_columns(src)?;
    let frames = Frames {
        true_north,
        to_geo,
        grid,
        converter,
        ellipsoid: traj_crs.ellipsoid,
    };
    let mut rows = Vec::with_capacity(events.len());
    for ev in &events {
        let fail = |field: &str, msg: String, hint: &str| {
            Problem::error(&src.events, Some(ev.line), Some(field), msg, hint)
        };
        let Some(s) = interpolate(&samples, ev.time_unix_s, src.max_gap_s) else {
            report.problems.push(fail(
                &src.event_layout.time_column,
                format!(
                    "time {} lies outside the trajectory or in a gap longer than {} s; skipped",
                    format_time_iso(ev.time_unix_s).unwrap_or_default(),
                    src.max_gap_s
                ),
                "check the time system and GPS week of the events and the trajectory",
            ));
            continue;
        };
        if !src.panoramas.join(&ev.image).is_file() {
            report.problems.push(fail(
                &src.event_layout.image_column,
                format!(
                    "panorama {} does not exist; skipped",
                    src.panoramas.join(&ev.image).display()
                ),
                "put the image into the panoramas folder or fix its name",
            ));
            continue;
        }
        match recording(src, ev, &s, &frames, pano_cols.as_ref()) {
            Ok(r) => rows.push(r),
            Err(m) => {
                report
                    .problems
                    .push(fail("time", m, "check the trajectory's CRS and values"))
            }
        }
    }
    Ok(rows)
}

/// The event file's panorama attitude columns (orientation = "event-columns").
fn pano_columns(src: &MmSource) -> Result<Option<(TextTable, [usize; 3])>, Problem> {
    if src.orientation != PanoramaOrientation::EventColumns {
        return Ok(None);
    }
    let Some(names) = &src.pano_columns else {
        return Err(config_error(
            "mm.pano_columns",
            "is required with orientation = \"event-columns\"",
            "name the event-file columns of the panorama heading (true north), pitch and roll",
        ));
    };
    let l = &src.event_layout;
    let table = TextTable::read(&src.events, l.delimiter, l.header, false)?;
    let mut cols = [0; 3];
    for (k, n) in names.iter().enumerate() {
        cols[k] = table.column(n)?;
    }
    Ok(Some((table, cols)))
}

fn read_samples(
    src: &MmSource,
    traj_crs: &Crs,
    report: &mut SourceReport,
) -> Result<(Vec<TrajectorySample>, bool), Problem> {
    match src.format {
        TrajectoryFormat::Sbet => {
            if traj_crs.is_projected() {
                return Err(config_error("mm.crs", format!("{} is projected but an SBET holds latitude/longitude", src.crs), "give the geographic CRS the SBET was processed in, e.g. EPSG:4937 (ETRS89) or EPSG:4979 (WGS 84)"));
            }
            let Some(week) = src.gps_week else {
                return Err(config_error(
                    "mm.gps_week",
                    "is required for an SBET (its times are seconds of the GPS week)",
                    "give the GPS week of the survey (e.g. from the POSPac project)",
                ));
            };
            let (records, problems) = read_sbet(&src.trajectory);
            report.problems.extend(problems);
            let samples = records
                .iter()
                .enumerate()
                .map(|(i, r)| TrajectorySample {
                    line: i + 1,
                    time_unix_s: gps_to_unix_s(week, r.time_sow_s, src.leap_seconds),
                    a: r.lat_rad.to_degrees(),
                    b: r.lon_rad.to_degrees(),
                    h_m: r.height_m,
                    roll_deg: r.roll_rad.to_degrees(),
                    pitch_deg: r.pitch_rad.to_degrees(),
                    heading_deg: r.heading_rad.to_degrees(),
                })
                .collect();
            Ok((samples, true))
        }
        TrajectoryFormat::Csv => {
            let Some(layout) = &src.layout else {
                return Err(config_error(
                    "mm.layout",
                    "is required for a trajectory table",
                    "describe the columns in [mm.layout]",
                ));
            };
            let Some(north) = src.heading_north else {
                return Err(config_error(
                    "mm.heading_north",
                    "is required for a trajectory table",
                    "say whether its heading is to \"true\" or \"grid\" north",
                ));
            };
            let (samples, problems) =
                read_trajectory_csv(&src.trajectory, layout, !traj_crs.is_projected());
            report.problems.extend(problems);
            Ok((samples, north == North::True || !traj_crs.is_projected()))
        }
    }
}

/// The sample at time `t`, linear between the neighbours (heading along the shorter arc).
fn interpolate(samples: &[TrajectorySample], t: f64, max_gap_s: f64) -> Option<TrajectorySample> {
    let i = samples.partition_point(|s| s.time_unix_s < t);
    if i < samples.len() && samples[i].time_unix_s == t {
        return Some(samples[i]);
    }
    if i == 0 || i == samples.len() {
        return None;
    }
    let (s0, s1) = (&samples[i - 1], &samples[i]);
    if s1.time_unix_s - s0.time_unix_s > max_gap_s {
        return None;
    }
    let w = (t - s0.time_unix_s) / (s1.time_unix_s - s0.time_unix_s);
    let lerp = |a: f64, b: f64| a + w * (b - a);
    let angle = |a: f64, b: f64| a + w * (b - a + 180.0).rem_euclid(360.0) - w * 180.0;
    Some(TrajectorySample {
        line: s0.line,
        time_unix_s: t,
        a: lerp(s0.a, s1.a),
        b: lerp(s0.b, s1.b),
        h_m: lerp(s0.h_m, s1.h_m),
        roll_deg: angle(s0.roll_deg, s1.roll_deg),
        pitch_deg: angle(s0.pitch_deg, s1.pitch_deg),
        heading_deg: angle(s0.heading_deg, s1.heading_deg),
    })
}

/// The frames an event's pose passes through.
struct Frames {
    /// The trajectory's heading is to true north.
    true_north: bool,
    /// Trajectory native → its own latitude/longitude.
    to_geo: HorizontalTransform,
    /// Convergence of a projected trajectory CRS.
    grid: Option<GridNorth>,
    /// Trajectory geographic → campaign.
    converter: super::convert::Converter,
    /// The trajectory datum's ellipsoid (lever arm).
    ellipsoid: Ellipsoid,
}

fn recording(
    src: &MmSource,
    ev: &Event,
    s: &TrajectorySample,
    f: &Frames,
    pano_cols: Option<&(TextTable, [usize; 3])>,
) -> Result<Recording, String> {
    let converter = &f.converter;
    let (lat, lon) = f.to_geo.apply(s.a, s.b).map_err(|e| e.to_string())?;
    let heading_true = if f.true_north {
        s.heading_deg
    } else {
        let g = f
            .grid
            .as_ref()
            .ok_or("grid heading needs a projected trajectory CRS")?;
        s.heading_deg
            - g.true_north_grid_azimuth_deg(lat, lon)
                .map_err(|e| e.to_string())?
    };
    let r_bn = body_to_ned(s.roll_deg, s.pitch_deg, heading_true);
    let lever = LeverArm {
        ellipsoid: &f.ellipsoid,
        body_to_ned: &r_bn,
        lever_body_m: src.lever_arm_m,
    };
    let (plat, plon, ph) = lever.apply((lat, lon, s.h_m));
    let r_pano_enu = match pano_cols {
        None => panorama_to_enu(&r_bn, src.boresight_deg),
        Some((table, cols)) => {
            let cells = table
                .rows
                .iter()
                .find(|(l, _)| *l == ev.line)
                .map(|(_, c)| c)
                .ok_or("event row vanished")?;
            let v: Vec<f64> = cols
                .iter()
                .map(|&c| {
                    cells
                        .get(c)
                        .and_then(|x| x.parse::<f64>().ok())
                        .filter(|x| x.is_finite())
                })
                .collect::<Option<_>>()
                .ok_or("the panorama heading/pitch/roll cells are not numbers")?;
            panorama_matrix(v[0], v[1], v[2])
        }
    };
    let (x, y, z) = converter
        .position(plat, plon, ph)
        .map_err(|e| e.to_string())?;
    let r_grid = converter
        .rotation(plat, plon, &r_pano_enu)
        .map_err(|e| e.to_string())?;
    let (yaw, pitch, roll) = panorama_angles(&r_grid);
    let north_deg = converter
        .north_azimuth_deg(plat, plon)
        .map_err(|e| e.to_string())?;
    let placement = PanoramaPlacement {
        xyz: (x, y, z),
        ypr_deg: (yaw, pitch, roll),
        heading_deg: heading_true + north_deg,
    };
    Ok(Recording {
        camera_height_m: src.camera_height_m,
        sigma_xy_m: src.sigma_xy_m,
        sigma_z_m: src.sigma_z_m,
        ..panorama_row(&ev.image, ev.time_unix_s, placement)?
    })
}

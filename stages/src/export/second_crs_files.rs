//! The files of a run written also in the second output CRS ([`crate::crs::second_crs`]), into
//! `OUT/epsg_<code>[_<vertical>]/`:
//!
//! - `trajectory_adjusted.csv` — a first line `# crs = …; …` naming the CRS, the heights and the axes, then
//!   `image_id, time, time_s`, the adjusted position (`x, y, z` for a projected CRS, `lat, lon, z` in degrees
//!   for a geographic one; `z` the height the first line names), `sigma_e_m, sigma_n_m, sigma_u_m` (posterior
//!   σ along the CRS's axes), `de_m, dn_m, du_m` (the correction adjusted − recorded along them) and
//!   `correction` (the support word);
//! - `corrections.csv` — the correction series with the columns of the campaign's `corrections.csv`, east and
//!   north turned into the CRS's axes (its grid axes, or true east/north for a geographic CRS);
//! - `control_points.csv` — a first line as above, then `label, source, point_id`, the aerial-triangulated
//!   position in the CRS and its σ along the CRS's axes, for the control the adjustment used (as in
//!   `ground_control/`'s files for other tools).
//!
//! Values in metres keep the campaign's scale: the two projections' scale factors differ by ~10⁻⁴, well
//! below the precision of a correction.

use super::control_status::ControlStatuses;
use super::corrections::CorrectionSeries;
use super::corrections_csv::write_corrections_csv;
use super::gcp::{collect, GcpExport};
use crate::adjustment::AdjustmentRun;
use crate::campaign::time::format_time_iso;
use crate::campaign::Campaign;
use crate::correspondence::AerialControlPoint;
use crate::crs::second_crs::{turn, turn_sigma, SecondCrs};
use crate::fsutil::atomic_write_with;
use skytie_util::csv_out::quote;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The trajectory file of the second CRS.
pub const SECOND_TRAJECTORY_CSV: &str = "trajectory_adjusted.csv";
/// The corrections file of the second CRS.
pub const SECOND_CORRECTIONS_CSV: &str = "corrections.csv";
/// The control-point list of the second CRS.
pub const SECOND_CONTROL_POINTS_CSV: &str = "control_points.csv";

fn invalid(what: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, what)
}

/// What the files of one run are made of.
pub struct SecondCrsRun<'a> {
    pub campaign: &'a Campaign,
    pub run: &'a AdjustmentRun,
    pub series: &'a CorrectionSeries,
    /// (source label, control points), as for `ground_control/`.
    pub control: &'a [(&'a str, &'a [AerialControlPoint])],
}

/// Writes the three files of the module doc into `out/<folder>/`; returns that folder.
pub fn write_second_crs_files(
    out: &Path,
    second: &SecondCrs,
    x: &SecondCrsRun<'_>,
) -> io::Result<PathBuf> {
    let dir = out.join(second.folder_name());
    std::fs::create_dir_all(&dir)?;
    write_trajectory(&dir.join(SECOND_TRAJECTORY_CSV), second, x)?;
    write_corrections_csv(
        &dir.join(SECOND_CORRECTIONS_CSV),
        &turned_series(second, x)?,
    )?;
    write_control_points(&dir.join(SECOND_CONTROL_POINTS_CSV), second, x)?;
    Ok(dir)
}

/// The first line of the files: CRS, heights, axes.
fn first_line(second: &SecondCrs) -> String {
    let axes = if second.is_geographic() {
        "lat, lon in degrees; east/north values along true east/north"
    } else {
        "x, y easting/northing in metres; east/north values along the grid"
    };
    format!(
        "# crs = {}; z: {}; {axes}",
        second.crs.text,
        second.heights_label()
    )
}

fn coordinate_header(second: &SecondCrs) -> &'static str {
    if second.is_geographic() {
        "lat,lon,z"
    } else {
        "x,y,z"
    }
}

/// The first line and the header row of a file: `lead`, the coordinate columns, the σ columns along the CRS's
/// axes, then `tail` (starting with a comma, or empty).
fn write_head(w: &mut dyn Write, second: &SecondCrs, lead: &str, tail: &str) -> io::Result<()> {
    writeln!(w, "{}", first_line(second))?;
    writeln!(
        w,
        "{lead},{},sigma_e_m,sigma_n_m,sigma_u_m{tail}",
        coordinate_header(second)
    )
}

fn write_trajectory(path: &Path, second: &SecondCrs, x: &SecondCrsRun<'_>) -> io::Result<()> {
    let mut rows = Vec::with_capacity(x.run.recordings.len());
    for (r, s) in x.run.recordings.iter().zip(&x.series.recordings) {
        let [ax, ay, _] = r.adjusted_world;
        let fail = |e: String| invalid(format!("recording '{}': {e}", r.image_id));
        let p = second.point(r.adjusted_world).map_err(fail)?;
        let t = second.turn_deg(ax, ay).map_err(fail)?;
        let c = &s.correction;
        let (de, dn) = turn(c.delta_enu_m[0], c.delta_enu_m[1], t);
        let (se, sn) = turn_sigma(r.sigma_m[0], r.sigma_m[1], t);
        rows.push((r, c, p, [de, dn, c.delta_enu_m[2]], [se, sn, r.sigma_m[2]]));
    }
    atomic_write_with(path, |w| {
        write_head(
            w,
            second,
            "image_id,time,time_s",
            ",de_m,dn_m,du_m,correction",
        )?;
        for (r, c, [a, b, h], [de, dn, du], [se, sn, su]) in &rows {
            writeln!(
                w,
                "{},{},{},{a},{b},{h},{se},{sn},{su},{de},{dn},{du},{}",
                quote(&r.image_id),
                format_time_iso(c.time_s).unwrap_or_default(),
                c.time_s,
                c.support.label()
            )?;
        }
        Ok(())
    })
}

/// The series with every recording's east/north correction and σ turned into the second CRS's axes (the
/// rows between recordings interpolate the turned values).
fn turned_series(second: &SecondCrs, x: &SecondCrsRun<'_>) -> io::Result<CorrectionSeries> {
    let mut series = x.series.clone();
    for (s, r) in series.recordings.iter_mut().zip(&x.run.recordings) {
        let t = second
            .turn_deg(r.recorded_world[0], r.recorded_world[1])
            .map_err(|e| invalid(format!("recording '{}': {e}", r.image_id)))?;
        let c = &mut s.correction;
        let (de, dn) = turn(c.delta_enu_m[0], c.delta_enu_m[1], t);
        let (se, sn) = turn_sigma(c.sigma_enu_m[0], c.sigma_enu_m[1], t);
        c.delta_enu_m = [de, dn, c.delta_enu_m[2]];
        c.sigma_enu_m = [se, sn, c.sigma_enu_m[2]];
    }
    Ok(series)
}

fn write_control_points(path: &Path, second: &SecondCrs, x: &SecondCrsRun<'_>) -> io::Result<()> {
    let gcps = collect(x.campaign, x.control, &mut GcpExport::default());
    let statuses = ControlStatuses::of(Some(x.run));
    let mut rows = Vec::with_capacity(gcps.len());
    for g in gcps
        .iter()
        .filter(|g| statuses.get(&g.point.tie_point_id).delivered())
    {
        let fail = |e: String| invalid(format!("control point '{}': {e}", g.label));
        let p = second.point(g.xyz).map_err(fail)?;
        let t = second.turn_deg(g.xyz[0], g.xyz[1]).map_err(fail)?;
        let (se, sn) = turn_sigma(g.sigma[0], g.sigma[1], t);
        rows.push((g, p, [se, sn, g.sigma[2]]));
    }
    atomic_write_with(path, |w| {
        write_head(w, second, "label,source,point_id", "")?;
        for (g, [a, b, h], [se, sn, su]) in &rows {
            writeln!(
                w,
                "{},{},{},{a},{b},{h},{se},{sn},{su}",
                quote(&g.label),
                g.source,
                quote(&g.point.tie_point_id)
            )?;
        }
        Ok(())
    })
}

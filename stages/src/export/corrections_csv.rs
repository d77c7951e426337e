//! `corrections.csv`: the correction time series ([`super::corrections`]) as a table for LiDAR and other
//! sensors' georeferencing software. One row per recording and, between two linked recordings, one per
//! multiple of [`CORRECTION_STEP_S`] (10 Hz). Columns:
//! `time` (ISO 8601 UTC), `time_s` (seconds since the Unix epoch), `image_id` (empty between recordings),
//! `kind` (`recording`, `interpolated`, `gap`), `support` (`controlled`, `bridged`, `extrapolated`,
//! `uncorrected`), `de_m, dn_m, du_m` (adjusted − recorded position, world frame east/north/up, metres),
//! `dyaw_deg` (adjusted − recorded yaw), `sigma_e_m, sigma_n_m, sigma_u_m, sigma_yaw_deg`. Apply as
//! `corrected = recorded + Δ`. Floats in shortest round-trip form; deterministic.

use super::corrections::CorrectionSeries;
use crate::campaign::time::format_time_iso;
use skytie_util::csv_out::{quote, write_csv};
use std::io::{self, Write};
use std::path::Path;

/// Time step of the interpolated rows, seconds.
pub const CORRECTION_STEP_S: f64 = 0.1;

/// Column names of `corrections.csv`.
pub const CORRECTIONS_CSV_HEADER: [&str; 13] = [
    "time",
    "time_s",
    "image_id",
    "kind",
    "support",
    "de_m",
    "dn_m",
    "du_m",
    "dyaw_deg",
    "sigma_e_m",
    "sigma_n_m",
    "sigma_u_m",
    "sigma_yaw_deg",
];

/// Writes `corrections.csv` atomically.
pub fn write_corrections_csv(path: &Path, series: &CorrectionSeries) -> io::Result<()> {
    write_csv(path, &CORRECTIONS_CSV_HEADER, |w| {
        for (id, c) in series.rows(CORRECTION_STEP_S) {
            let time = format_time_iso(c.time_s).unwrap_or_default();
            let [de, dn, du] = c.delta_enu_m;
            let [se, sn, su] = c.sigma_enu_m;
            writeln!(
                w,
                "{time},{},{},{},{},{de},{dn},{du},{},{se},{sn},{su},{}",
                c.time_s,
                id.map(quote).unwrap_or_default(),
                c.kind.label(),
                c.support.label(),
                c.delta_yaw_deg,
                c.sigma_yaw_deg
            )?;
        }
        Ok(())
    })
}

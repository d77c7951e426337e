//! Applanix SBET ("smoothed best estimate of trajectory", POSPac output `sbet_*.out`): a headerless binary
//! file of records of 17 little-endian f64 — GPS seconds of week; latitude, longitude (rad); ellipsoidal
//! height (m); velocities x, y, z (m/s); roll, pitch, platform heading, wander angle (rad); body
//! accelerations x, y, z (m/s²); body angular rates x, y, z (rad/s). Roll, pitch and heading are the body
//! (IMU) attitude relative to the local level north-east-down frame: heading clockwise from true north,
//! pitch nose up, roll right side down. Followed: the record layout published in the POSPac MMS user guide
//! and reproduced by trajectory tools (e.g. PDAL's sbet reader, which likewise reads the platform heading as
//! the true heading). Latitude/longitude/height are on the datum the user processed in (ETRS89, WGS84, ...),
//! which the import configuration declares.

use crate::campaign::Problem;
use std::path::Path;

/// Bytes of one record.
pub const RECORD_BYTES: usize = 17 * 8;

/// One SBET record (units as in the file, see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SbetRecord {
    pub time_sow_s: f64,
    pub lat_rad: f64,
    pub lon_rad: f64,
    pub height_m: f64,
    pub velocity_m_s: [f64; 3],
    pub roll_rad: f64,
    pub pitch_rad: f64,
    pub heading_rad: f64,
    pub wander_rad: f64,
    pub acceleration_m_s2: [f64; 3],
    pub angular_rate_rad_s: [f64; 3],
}

impl SbetRecord {
    fn from_bytes(b: &[u8]) -> Self {
        let f = |i: usize| f64::from_le_bytes(b[i * 8..i * 8 + 8].try_into().expect("8 bytes"));
        Self {
            time_sow_s: f(0),
            lat_rad: f(1),
            lon_rad: f(2),
            height_m: f(3),
            velocity_m_s: [f(4), f(5), f(6)],
            roll_rad: f(7),
            pitch_rad: f(8),
            heading_rad: f(9),
            wander_rad: f(10),
            acceleration_m_s2: [f(11), f(12), f(13)],
            angular_rate_rad_s: [f(14), f(15), f(16)],
        }
    }

    fn to_bytes(self, out: &mut Vec<u8>) {
        let v = self.velocity_m_s;
        let a = self.acceleration_m_s2;
        let w = self.angular_rate_rad_s;
        for x in [
            self.time_sow_s,
            self.lat_rad,
            self.lon_rad,
            self.height_m,
            v[0],
            v[1],
            v[2],
            self.roll_rad,
            self.pitch_rad,
            self.heading_rad,
            self.wander_rad,
            a[0],
            a[1],
            a[2],
            w[0],
            w[1],
            w[2],
        ] {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
}

/// Every record of an SBET as stored, valid or not; `Err` for a file that cannot be read or whose size is not
/// a multiple of 136 bytes (not an SBET, or truncated).
pub fn read_sbet_records(path: &Path) -> Result<Vec<SbetRecord>, Problem> {
    let bytes = std::fs::read(path).map_err(|e| super::unreadable(path, &e))?;
    if bytes.is_empty() || bytes.len() % RECORD_BYTES != 0 {
        return Err(Problem::error(path, None, None, format!("is {} bytes, not a whole number of 136-byte SBET records", bytes.len()), "give the binary SBET (sbet_*.out) itself, not a text export; a truncated copy must be exported again"));
    }
    Ok(bytes
        .chunks_exact(RECORD_BYTES)
        .map(SbetRecord::from_bytes)
        .collect())
}

/// Why a record cannot be used (`None`: it can), given the time of the last usable record before it.
pub fn record_problem(r: &SbetRecord, last_time_sow_s: f64) -> Option<&'static str> {
    if ![
        r.time_sow_s,
        r.lat_rad,
        r.lon_rad,
        r.height_m,
        r.roll_rad,
        r.pitch_rad,
        r.heading_rad,
    ]
    .iter()
    .all(|v| v.is_finite())
    {
        Some("has a non-finite time, position or attitude")
    } else if r.lat_rad.abs() > std::f64::consts::FRAC_PI_2
        || r.lon_rad.abs() > 2.0 * std::f64::consts::PI
    {
        Some("has a latitude/longitude outside ±90°/±360° (not radians?)")
    } else if !(0.0..=crate::formats::gps_time::WEEK_S + 86_400.0).contains(&r.time_sow_s) {
        Some("has a time outside the GPS week (0 … 604800 s)")
    } else if r.time_sow_s <= last_time_sow_s {
        Some("does not come after the previous record in time")
    } else {
        None
    }
}

/// Read an SBET. A file whose size is not a multiple of 136 bytes is refused (not an SBET, or truncated);
/// records with non-finite or out-of-range values, or whose time does not increase, are skipped and
/// reported as "record N" (1-based) in the problem's row.
pub fn read_sbet(path: &Path) -> (Vec<SbetRecord>, Vec<Problem>) {
    let all = match read_sbet_records(path) {
        Ok(r) => r,
        Err(p) => return (Vec::new(), vec![p]),
    };
    let mut records = Vec::with_capacity(all.len());
    let mut problems = Vec::new();
    let mut last_time = f64::NEG_INFINITY;
    for (i, r) in all.into_iter().enumerate() {
        let reason = record_problem(&r, last_time);
        match reason {
            Some(reason) => problems.push(Problem::error(
                path,
                Some(i + 1),
                None,
                format!("record {} {reason}; skipped", i + 1),
                "check that the file is an SBET of one GPS week",
            )),
            None => {
                last_time = r.time_sow_s;
                records.push(r);
            }
        }
    }
    (records, problems)
}

/// Write records as an SBET.
pub fn write_sbet(path: &Path, records: &[SbetRecord]) -> std::io::Result<()> {
    let mut out = Vec::with_capacity(records.len() * RECORD_BYTES);
    for r in records {
        r.to_bytes(&mut out);
    }
    crate::fsutil::atomic_write(path, &out)
}

//! The corrected trajectory as an SBET, for campaigns imported from one (`[source.trajectory]` in
//! `campaign.toml`): `sbet_adjusted.out` has every record of the imported SBET in its order, layout and time
//! base (GPS seconds of week), with latitude, longitude, ellipsoidal height and heading corrected and every
//! other field as it was; `sbet_adjusted_quality.csv` says for each record how its correction was obtained and
//! how precise it is, so LiDAR software can re-process with the corrected trajectory and know where to trust it.
//!
//! A record's correction is the campaign's correction series at its time ([`CorrectionSeries::at`]: the
//! adjustment's value at a recording, interpolated between recordings, flagged across gaps, the nearest value
//! with growing σ outside the recorded span). It is applied where it was estimated — at the panorama centre,
//! in the campaign frame: the record's IMU position plus the lever arm gives the panorama centre, which is
//! taken into the campaign CRS with the importer's own conversion, moved by ΔE, ΔN, ΔU and taken back; the
//! heading turns by the yaw correction (a rotation about the vertical, the same angle to grid and to true
//! north); the lever arm under the corrected attitude gives the corrected IMU position. Velocities,
//! accelerations, angular rates and the wander angle are copied: the correction varies over seconds, its
//! effect on them is below their precision. A record the importer could not use (non-finite, out of range,
//! time not increasing) is copied unchanged and flagged `not_corrected`.

use super::corrections::{Correction, CorrectionSeries};
use crate::campaign::source::{read_source, ProvenanceFormat, TrajectoryProvenance};
use crate::crs::Ellipsoid;
use crate::formats::gps_time::gps_to_unix_s;
use crate::formats::sbet::{read_sbet_records, record_problem, write_sbet, SbetRecord};
use crate::import::config::CampaignSection;
use crate::import::context::ImportContext;
use crate::import::convert::{Converter, Inverse};
use crate::import::export::inverse;
use crate::import::pose::{body_to_ned, LeverArm};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::io;
use std::path::Path;

/// The corrected SBET.
pub const SBET_ADJUSTED: &str = "sbet_adjusted.out";
/// Its per-record quality file.
pub const SBET_QUALITY_CSV: &str = "sbet_adjusted_quality.csv";
/// Header of [`SBET_QUALITY_CSV`].
pub const SBET_QUALITY_HEADER: &str = "record,time_sow_s,kind,support,de_m,dn_m,du_m,dyaw_deg,sigma_e_m,sigma_n_m,sigma_u_m,sigma_yaw_deg";

/// What [`write_corrected_sbet`] wrote: records per kind of correction.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SbetOutput {
    pub records: usize,
    pub at_recording: usize,
    pub interpolated: usize,
    pub across_gap: usize,
    pub extrapolated: usize,
    /// Copied unchanged (the record or its conversion failed).
    pub not_corrected: usize,
}

fn invalid(message: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, message)
}

/// The frames a record's correction passes through.
struct Frames {
    forward: Converter,
    back: Inverse,
    ellipsoid: Ellipsoid,
    lever_arm_m: [f64; 3],
}

impl Frames {
    fn new(root: &Path, campaign_crs: &str, p: &TrajectoryProvenance) -> io::Result<Self> {
        let section = CampaignSection {
            name: String::new(),
            crs: campaign_crs.to_string(),
            geoid_grid: p.geoid_grid.as_ref().map(|g| root.join(g)),
            geoid_separation_m: p.geoid_separation_m,
            // Forward and back use the same datum shift, so a correction (a difference) maps back alike.
            datum_grid: None,
            frame: Default::default(),
        };
        let ctx = ImportContext::new(&section).map_err(|e| invalid(e.to_string()))?;
        let geographic = format!("geographic:{}", p.crs);
        let forward = ctx
            .converter(Some(&geographic), Some(&p.heights))
            .map_err(|e| invalid(e.to_string()))?;
        let back = inverse(&ctx, &geographic, &p.heights).map_err(|e| invalid(e.to_string()))?;
        let ellipsoid = crate::crs::Crs::parse(&p.crs)
            .map_err(|e| invalid(e.to_string()))?
            .ellipsoid;
        Ok(Self {
            forward,
            back,
            ellipsoid,
            lever_arm_m: p.lever_arm_m,
        })
    }

    /// `r` moved by `c` (see the module doc).
    fn correct(&self, r: &SbetRecord, c: &Correction) -> Result<SbetRecord, String> {
        let (lat, lon) = (r.lat_rad.to_degrees(), r.lon_rad.to_degrees());
        let (roll, pitch) = (r.roll_rad.to_degrees(), r.pitch_rad.to_degrees());
        let heading = r.heading_rad.to_degrees();
        let r_bn = body_to_ned(roll, pitch, heading);
        let lever = LeverArm {
            ellipsoid: &self.ellipsoid,
            body_to_ned: &r_bn,
            lever_body_m: self.lever_arm_m,
        };
        let (plat, plon, ph) = lever.apply((lat, lon, r.height_m));
        let (x, y, z) = self
            .forward
            .position(plat, plon, ph)
            .map_err(|e| e.to_string())?;
        let [de, dn, du] = c.delta_enu_m;
        let (qlat, qlon, qh) = self
            .back
            .position(x + de, y + dn, z + du)
            .map_err(|e| e.to_string())?;
        let heading_new = heading + c.delta_yaw_deg;
        let r_bn_new = body_to_ned(roll, pitch, heading_new);
        let lever_new = LeverArm {
            body_to_ned: &r_bn_new,
            ..lever
        };
        let (ilat, ilon, ih) = lever_new.remove((qlat, qlon, qh));
        let heading_rad = heading_new.to_radians();
        Ok(SbetRecord {
            lat_rad: ilat.to_radians(),
            lon_rad: ilon.to_radians(),
            height_m: ih,
            // Keep the input's heading range ([0, 2π) or (−π, π]).
            heading_rad: if r.heading_rad < 0.0 {
                (heading_rad + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI
            } else {
                heading_rad.rem_euclid(std::f64::consts::TAU)
            },
            ..*r
        })
    }
}

/// Where the campaign in `root` was imported from an SBET, write the corrected SBET and its quality file
/// into `dir`; `Ok(None)` when it was not.
pub fn write_corrected_sbet(
    root: &Path,
    campaign_crs: &str,
    series: &CorrectionSeries,
    dir: &Path,
) -> io::Result<Option<SbetOutput>> {
    let source = read_source(root).map_err(|p| invalid(p.to_string()))?;
    let Some(p) = source.trajectory else {
        return Ok(None);
    };
    match p.format {
        ProvenanceFormat::Sbet => {}
    }
    let frames = Frames::new(root, campaign_crs, &p)?;
    let input = root.join(&p.file);
    let records = read_sbet_records(&input).map_err(|e| invalid(e.to_string()))?;
    let mut out = Vec::with_capacity(records.len());
    let mut quality = String::with_capacity(records.len() * 120);
    quality.push_str(SBET_QUALITY_HEADER);
    quality.push('\n');
    let mut summary = SbetOutput {
        records: records.len(),
        ..SbetOutput::default()
    };
    let mut last_time = f64::NEG_INFINITY;
    let usable: Vec<bool> = records
        .iter()
        .map(|r| {
            let ok = record_problem(r, last_time).is_none();
            if ok {
                last_time = r.time_sow_s;
            }
            ok
        })
        .collect();
    let corrected: Vec<Option<(SbetRecord, Correction)>> = records
        .par_iter()
        .zip(&usable)
        .map(|(r, &ok)| {
            let t = gps_to_unix_s(p.gps_week, r.time_sow_s, p.leap_seconds);
            let c = ok.then(|| series.at(t)).flatten()?;
            frames.correct(r, &c).ok().map(|n| (n, c))
        })
        .collect();
    for (i, (r, corrected)) in records.iter().zip(corrected).enumerate() {
        let _ = write!(quality, "{},{},", i + 1, r.time_sow_s);
        match corrected {
            Some((n, c)) => {
                out.push(n);
                count(&mut summary, &c);
                let [de, dn, du] = c.delta_enu_m;
                let [se, sn, su] = c.sigma_enu_m;
                let _ = writeln!(
                    quality,
                    "{},{},{de},{dn},{du},{},{se},{sn},{su},{}",
                    c.kind.label(),
                    c.support.label(),
                    c.delta_yaw_deg,
                    c.sigma_yaw_deg
                );
            }
            None => {
                out.push(*r);
                summary.not_corrected += 1;
                quality.push_str("not_corrected,none,0,0,0,0,,,,\n");
            }
        }
    }
    write_sbet(&dir.join(SBET_ADJUSTED), &out)?;
    crate::fsutil::atomic_write(&dir.join(SBET_QUALITY_CSV), quality.as_bytes())?;
    Ok(Some(summary))
}

fn count(s: &mut SbetOutput, c: &Correction) {
    use super::corrections::SampleKind;
    match c.kind {
        SampleKind::Recording => s.at_recording += 1,
        SampleKind::Interpolated => s.interpolated += 1,
        SampleKind::Gap => s.across_gap += 1,
        SampleKind::Extrapolated => s.extrapolated += 1,
    }
}

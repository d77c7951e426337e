//! The corrected SBET (`sbet_adjusted.out`) of a campaign imported from an SBET, checked by importing it again:
//! with a known correction applied, every panorama of the re-imported campaign must sit at the original
//! position + (ΔE, ΔN, ΔU) to < 1 mm with its yaw and heading turned by Δyaw to < 0.0001°, interpolated
//! corrections must be the linear mix of their neighbours, every other SBET field must be copied, and a
//! record the importer cannot use must pass through unchanged and flagged.

use skytie_stages::campaign::source::read_source;
use skytie_stages::campaign::{read_campaign, Campaign};
use skytie_stages::export::corrections::{Correction, CorrectionSeries, SeriesRecording};
use skytie_stages::export::{write_corrected_sbet, SampleKind, Support, SBET_ADJUSTED};
use skytie_stages::formats::gps_time::unix_to_gps;
use skytie_stages::formats::sbet::{read_sbet_records, write_sbet, SbetRecord};
use skytie_stages::import::{run_import, ImportConfig};
use std::path::Path;

const T0_UNIX_S: f64 = 1_560_508_267.0; // 2019-06-14T10:31:07Z
const STEP_S: f64 = 0.25;
const RECORDS: usize = 41;
/// Records with a panorama event.
const EVENTS: [usize; 9] = [0, 5, 10, 15, 20, 25, 30, 35, 40];

/// A vehicle driving north-east through Utrecht, rolling and pitching, at 4 Hz.
fn trajectory() -> (u32, Vec<SbetRecord>) {
    let (week, sow0) = unix_to_gps(T0_UNIX_S, None);
    let records = (0..RECORDS)
        .map(|i| {
            let f = i as f64;
            SbetRecord {
                time_sow_s: sow0 + STEP_S * f,
                lat_rad: (52.0907 + 9e-6 * f).to_radians(),
                lon_rad: (5.1214 + 1.4e-5 * f).to_radians(),
                height_m: 45.3 + 0.01 * f,
                velocity_m_s: [3.0, 4.0, 0.01 * f],
                roll_rad: (1.5 - 0.05 * f).to_radians(),
                pitch_rad: (-0.8 + 0.02 * f).to_radians(),
                heading_rad: (40.0 + 0.5 * f).to_radians(),
                wander_rad: 0.125,
                acceleration_m_s2: [0.1, -0.2, 9.81],
                angular_rate_rad_s: [0.001, 0.002, 0.003 * f],
            }
        })
        .collect();
    (week, records)
}

fn import(dir: &Path, sbet: &str, week: u32, out: &str) -> Campaign {
    let config = format!(
        "[campaign]\nname = \"sbet\"\ncrs = \"EPSG:28992+5709\"\ngeoid_separation_m = 43.25\n[mm]\ntrajectory = \"{sbet}\"\nformat = \"sbet\"\ncrs = \"EPSG:4937\"\nheights = \"ellipsoidal\"\ngps_week = {week}\nevents = \"events.csv\"\norientation = \"imu\"\npanoramas = \"panos\"\ncamera_height_m = 2.4\nboresight_deg = [0.4, -0.3, 1.2]\nlever_arm_m = [0.35, -0.12, -1.85]\nmax_gap_s = 0.3\n[mm.event_layout]\ndelimiter = \"comma\"\ntime_column = \"time\"\nimage_column = \"image\"\ntime = {{ system = \"gps-seconds-of-week\", gps_week = {week} }}\n"
    );
    let path = dir.join(format!("{out}.toml"));
    std::fs::write(&path, config).unwrap();
    let report = run_import(&ImportConfig::read(&path).unwrap(), &dir.join(out)).unwrap();
    assert_eq!(report.skipped(), 0, "{report}");
    read_campaign(&dir.join(out)).unwrap().0
}

/// A series that corrects the recordings at `with` (indices into the campaign's recordings) by `delta(k)`.
fn series(
    c: &Campaign,
    with: &[usize],
    delta: impl Fn(usize) -> ([f64; 3], f64),
) -> CorrectionSeries {
    CorrectionSeries {
        recordings: with
            .iter()
            .map(|&k| {
                let (d, yaw) = delta(k);
                SeriesRecording {
                    image_id: c.recordings[k].image_id.clone(),
                    correction: Correction {
                        time_s: c.recordings[k].time_s,
                        delta_enu_m: d,
                        delta_yaw_deg: yaw,
                        sigma_enu_m: [0.02, 0.02, 0.04],
                        sigma_yaw_deg: 0.01,
                        kind: SampleKind::Recording,
                        support: Support::Controlled,
                    },
                    group: 0,
                    linked_to_next: true,
                }
            })
            .collect(),
        q_position_m2_per_s: 1e-4,
        q_yaw_deg2_per_s: 0.0,
    }
}

/// Write the corrected SBET of campaign `a` under `s`, import it with the same events, and check each
/// recording against `a` + `expected(k)`.
fn check(
    dir: &Path,
    week: u32,
    a: &Campaign,
    s: &CorrectionSeries,
    expected: impl Fn(usize) -> ([f64; 3], f64),
    name: &str,
) {
    let out = dir.join(format!("{name}-out"));
    std::fs::create_dir_all(&out).unwrap();
    let summary = write_corrected_sbet(&a.root, &a.crs, s, &out)
        .unwrap()
        .unwrap();
    assert_eq!(summary.records, RECORDS, "{summary:?}");
    std::fs::copy(out.join(SBET_ADJUSTED), dir.join(format!("{name}.out"))).unwrap();
    let b = import(dir, &format!("{name}.out"), week, name);
    assert_eq!(a.recordings.len(), b.recordings.len());
    for (k, (ra, rb)) in a.recordings.iter().zip(&b.recordings).enumerate() {
        let (d, dyaw) = expected(k);
        let off = [rb.x - ra.x - d[0], rb.y - ra.y - d[1], rb.z - ra.z - d[2]];
        let e = off.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(e < 1e-3, "{name} {}: off by {off:?} m", ra.image_id);
        let turn = |x: f64, y: f64| (y - x - dyaw + 180.0).rem_euclid(360.0) - 180.0;
        assert!(
            turn(ra.yaw_deg, rb.yaw_deg).abs() < 1e-4,
            "{name} {}: yaw {} → {}",
            ra.image_id,
            ra.yaw_deg,
            rb.yaw_deg
        );
        assert!(
            turn(ra.heading_deg, rb.heading_deg).abs() < 1e-4,
            "{name} {}: heading",
            ra.image_id
        );
        assert!(
            (ra.pitch_deg - rb.pitch_deg).abs() < 1e-4 && (ra.roll_deg - rb.roll_deg).abs() < 1e-4
        );
    }
}

#[test]
fn corrected_sbet_round_trips_a_known_correction() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    let (week, mut records) = trajectory();
    write_sbet(&dir.join("sbet.out"), &records).unwrap();
    std::fs::create_dir_all(dir.join("panos")).unwrap();
    let mut events = String::from("time,image\n");
    for (k, &i) in EVENTS.iter().enumerate() {
        std::fs::write(dir.join(format!("panos/p{k}.jpg")), b"jpg").unwrap();
        events.push_str(&format!("{},p{k}.jpg\n", records[i].time_sow_s));
    }
    std::fs::write(dir.join("events.csv"), events).unwrap();
    let a = import(dir, "sbet.out", week, "a");

    // The import kept the SBET and said so in campaign.toml.
    let source = read_source(&a.root)
        .unwrap()
        .trajectory
        .expect("[source.trajectory]");
    assert_eq!((source.crs.as_str(), source.gps_week), ("EPSG:4937", week));
    assert_eq!(source.lever_arm_m, [0.35, -0.12, -1.85]);
    assert_eq!(source.geoid_separation_m, Some(43.25));
    assert!(a.root.join(&source.file).is_file());

    // A constant correction everywhere.
    let constant = ([0.8, -0.45, 0.12], 0.3);
    let all: Vec<usize> = (0..a.recordings.len()).collect();
    check(
        dir,
        week,
        &a,
        &series(&a, &all, |_| constant),
        |_| constant,
        "constant",
    );

    // Corrections at every other panorama, interpolated (linearly in time) at the ones between.
    let at = |k: usize| ([0.1 * k as f64, -0.05 * k as f64, 0.02], 0.05 * k as f64);
    let even: Vec<usize> = all.iter().copied().filter(|k| k % 2 == 0).collect();
    check(dir, week, &a, &series(&a, &even, at), at, "interpolated");

    // Everything but position, height and heading is copied; an unusable record passes unchanged.
    records[7].lat_rad = f64::NAN;
    write_sbet(&a.root.join(&source.file), &records).unwrap();
    let out = dir.join("nan-out");
    std::fs::create_dir_all(&out).unwrap();
    let s = series(&a, &all, |_| constant);
    let summary = write_corrected_sbet(&a.root, &a.crs, &s, &out)
        .unwrap()
        .unwrap();
    assert_eq!(summary.not_corrected, 1, "{summary:?}");
    assert_eq!(summary.at_recording + summary.interpolated + 1, RECORDS);
    let got = read_sbet_records(&out.join(SBET_ADJUSTED)).unwrap();
    assert!(got[7].lat_rad.is_nan());
    assert_eq!(
        (got[7].lon_rad, got[7].height_m, got[7].heading_rad),
        (
            records[7].lon_rad,
            records[7].height_m,
            records[7].heading_rad
        )
    );
    for (g, r) in got.iter().zip(&records) {
        assert_eq!(
            (
                g.time_sow_s,
                g.velocity_m_s,
                g.roll_rad,
                g.pitch_rad,
                g.wander_rad
            ),
            (
                r.time_sow_s,
                r.velocity_m_s,
                r.roll_rad,
                r.pitch_rad,
                r.wander_rad
            )
        );
        assert_eq!(
            (g.acceleration_m_s2, g.angular_rate_rad_s),
            (r.acceleration_m_s2, r.angular_rate_rad_s)
        );
    }
    let quality = std::fs::read_to_string(out.join("sbet_adjusted_quality.csv")).unwrap();
    assert_eq!(quality.lines().count(), RECORDS + 1);
    assert!(
        quality.lines().nth(8).unwrap().contains(",not_corrected,"),
        "{quality}"
    );
    assert!(
        quality
            .lines()
            .nth(2)
            .unwrap()
            .contains(",interpolated,controlled,"),
        "{quality}"
    );
}

//! Outputs in a second CRS (`campaign.toml` `[outputs]`): conversions checked against published reference
//! coordinates, the height rules, and the files written from a run.
//!
//! References:
//! - EPSG Guidance Note 7-2 (IOGP Publication 373-7-2, "Coordinate Conversions and Transformations including
//!   Formulas"), worked example of the Oblique Stereographic method (EPSG 9809): Amersfoort / RD New,
//!   φ = 53°00'00"N, λ = 6°00'00"E on the Amersfoort (Bessel 1841) datum ⇔ E = 196 105.283 m,
//!   N = 557 057.739 m.
//! - The RD origin, the Onze Lieve Vrouwetoren in Amersfoort, RD (155 000 m, 463 000 m), has WGS84 latitude
//!   52.15517440° and longitude 5.38720621° (the reference point of Schreutelkamp and Strang van Hees,
//!   "Benaderingsformules voor de transformatie tussen RD- en WGS84-kaartcoördinaten", Geodesia 2001/2, used
//!   by every published RD ↔ WGS84 approximation). The EPSG definition's Helmert parameters reach it to
//!   0.3 m. That reference is a WGS84 position of the approximation's time, not an RDNAPTRANS™ result, hence
//!   the metre bound here; the decimetre check against RDNAPTRANS™2018's own self-validation point is a unit
//!   test of the CRS layer. A national NTv2 grid (`datum_grid`) is what gives millimetres.

use skytie_stages::crs::{OutputHeights, OutputsSection, SecondCrs, VerticalDatum};
use skytie_stages::export::synthetic_outputs::OutputsSpec;
use skytie_stages::export::{write_second_crs_files, CorrectionSeries, SecondCrsRun};
use std::path::Path;

fn section(also: &str) -> OutputsSection {
    OutputsSection {
        also_crs: Some(also.to_string()),
        ..OutputsSection::default()
    }
}

fn second(campaign: &str, s: &OutputsSection) -> SecondCrs {
    SecondCrs::new(campaign, s, Path::new("."))
        .unwrap()
        .expect("also_crs is set")
}

#[test]
fn rd_new_to_its_own_geographic_crs_matches_the_guidance_note_example() {
    let s = second("EPSG:28992+5709", &section("EPSG:4289"));
    let [lat, lon, h] = s.point([196_105.283, 557_057.739, 12.5]).unwrap();
    // 1 mm is 9·10⁻⁹° of latitude.
    assert!((lat - 53.0).abs() < 1e-8, "{lat}");
    assert!((lon - 6.0).abs() < 1e-8, "{lon}");
    // No vertical part in also_crs: the campaign's NAP heights are copied and named.
    assert_eq!(h, 12.5);
    assert!(matches!(
        s.heights,
        OutputHeights::Copied(VerticalDatum::Orthometric { code: 5709, .. })
    ));
    assert_eq!(s.folder_name(), "epsg_4289");
    // Geographic axes are true east/north; east of RD's central meridian its grid north lies east of true
    // north by ≈ (6° − 5.3876°)·sin 53° ≈ 0.49°, so grid vectors turn clockwise by that much.
    let t = s.turn_deg(196_105.283, 557_057.739).unwrap();
    assert!((t - 0.49).abs() < 0.02, "{t}");
}

#[test]
fn the_rd_origin_in_etrs89_is_within_a_metre_of_the_published_coordinates() {
    let s = second("EPSG:28992", &section("EPSG:4258"));
    let [lat, lon, _] = s.point([155_000.0, 463_000.0, 0.0]).unwrap();
    let (ref_lat, ref_lon) = (52.155_174_40, 5.387_206_21);
    let north_m = (lat - ref_lat).to_radians() * 6_381_000.0;
    let east_m = (lon - ref_lon).to_radians() * 6_381_000.0 * ref_lat.to_radians().cos();
    let off_m = north_m.hypot(east_m);
    eprintln!("RD origin in ETRS89 (Helmert): {off_m:.3} m from the published position");
    assert!(off_m < 1.0, "{off_m} m off ({lat}, {lon})");
    // And into ETRS89 / UTM 31N: a projected second CRS, grid axes turned by the two convergences.
    let utm = second("EPSG:28992", &section("EPSG:25831"));
    let [e, n, _] = utm.point([155_000.0, 463_000.0, 0.0]).unwrap();
    assert!(
        (e - 663_000.0).abs() < 5_000.0 && (n - 5_780_000.0).abs() < 5_000.0,
        "{e} {n}"
    );
    let t = utm.turn_deg(155_000.0, 463_000.0).unwrap();
    // UTM 31N's central meridian is 3°E: its grid north lies (5.387° − 3°)·sin 52.16° ≈ 1.88° east of true
    // north there (RD's coincides with true north at its origin), so vectors turn counter-clockwise.
    assert!((t + 1.88).abs() < 0.03, "{t}");
}

#[test]
fn heights_are_converted_only_when_both_systems_are_known() {
    // Ellipsoidal heights from NAP heights need a geoid model …
    let e = SecondCrs::new("EPSG:28992+5709", &section("EPSG:4937"), Path::new(".")).err();
    assert!(e.unwrap().contains("geoid_grid"));
    // … and with one, h = H + N.
    let with_geoid = OutputsSection {
        geoid_separation_m: Some(43.25),
        ..section("EPSG:4937")
    };
    let s = second("EPSG:28992+5709", &with_geoid);
    let [_, _, h] = s.point([155_000.0, 463_000.0, 2.0]).unwrap();
    assert!((h - 45.25).abs() < 1e-12, "{h}");
    // A campaign without a height system cannot be converted into one.
    let e = SecondCrs::new("EPSG:28992", &section("EPSG:4937"), Path::new(".")).err();
    assert!(e.unwrap().contains("declares no height system"));
    // Two different orthometric systems would need two geoids.
    let e = SecondCrs::new(
        "EPSG:28992+5709",
        &section("EPSG:4258+5730"),
        Path::new("."),
    )
    .err();
    assert!(e.unwrap().contains("converts heights only"));
    // Unknown codes are refused with the key's name.
    let e = SecondCrs::new("EPSG:28992+5709", &section("EPSG:999999"), Path::new(".")).err();
    assert!(e.unwrap().starts_with("outputs.also_crs"));
    // No also_crs: nothing to do.
    let none = SecondCrs::new("EPSG:28992", &OutputsSection::default(), Path::new(".")).unwrap();
    assert!(none.is_none());
}

#[test]
fn the_outputs_table_is_read_from_campaign_toml_and_refuses_unknown_keys() {
    let dir = std::env::temp_dir().join(format!("skytie_second_crs_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let toml = dir.join("campaign.toml");
    std::fs::write(
        &toml,
        "crs = \"EPSG:28992+5709\"\n[outputs]\nalso_crs = \"EPSG:4937\"\ngeoid_separation_m = 43.0\n",
    )
    .unwrap();
    let s = OutputsSection::read(&dir).unwrap();
    assert_eq!(s.also_crs.as_deref(), Some("EPSG:4937"));
    assert_eq!(s.geoid_separation_m, Some(43.0));
    std::fs::write(
        &toml,
        "crs = \"EPSG:28992\"\n[outputs]\nalso = \"EPSG:4937\"\n",
    )
    .unwrap();
    assert!(OutputsSection::read(&dir)
        .unwrap_err()
        .contains("[outputs]"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_run_writes_its_trajectory_corrections_and_control_points_in_the_second_crs() {
    let outputs = OutputsSpec {
        recordings: 60,
        failed_every: 0,
        ..OutputsSpec::default()
    }
    .generate();
    let dir = std::env::temp_dir().join(format!("skytie_second_crs_run_{}", std::process::id()));
    let campaign = outputs.campaign(&dir);
    let series = CorrectionSeries::from_run(&outputs.recordings, &outputs.run).unwrap();
    let s = second(&outputs.crs, &section("EPSG:4258"));
    let control = [("nadir", outputs.control.as_slice())];
    let run = SecondCrsRun {
        campaign: &campaign,
        run: &outputs.run,
        series: &series,
        control: &control,
    };
    let folder = write_second_crs_files(&dir, &s, &run).unwrap();
    assert_eq!(folder, dir.join("epsg_4258"));
    let trajectory = std::fs::read_to_string(folder.join("trajectory_adjusted.csv")).unwrap();
    let mut lines = trajectory.lines();
    assert!(lines
        .next()
        .unwrap()
        .starts_with("# crs = EPSG:4258; z: heights as in the campaign"));
    assert!(lines
        .next()
        .unwrap()
        .starts_with("image_id,time,time_s,lat,lon,z,"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), outputs.run.recordings.len());
    for (row, r) in rows.iter().zip(&outputs.run.recordings) {
        let f: Vec<&str> = row.split(',').collect();
        let expected = s.point(r.adjusted_world).unwrap();
        assert_eq!(f[0], r.image_id);
        for (text, value) in f[3..6].iter().zip(expected) {
            assert_eq!(text.parse::<f64>().unwrap(), value);
        }
        // A correction turned by less than 1° keeps its length.
        let d: Vec<f64> = f[9..12].iter().map(|v| v.parse().unwrap()).collect();
        let c = [0, 1, 2].map(|k| r.adjusted_world[k] - r.recorded_world[k]);
        let (len, len_c) = (d[0].hypot(d[1]), c[0].hypot(c[1]));
        assert!((len - len_c).abs() < 1e-9, "{len} {len_c}");
    }
    let corrections = std::fs::read_to_string(folder.join("corrections.csv")).unwrap();
    assert!(corrections.starts_with("time,time_s,image_id,"));
    assert!(corrections.lines().count() > outputs.run.recordings.len());
    let control = std::fs::read_to_string(folder.join("control_points.csv")).unwrap();
    let n_control = outputs
        .control
        .iter()
        .filter(|c| c.point_world.is_some())
        .count();
    assert!(n_control > 0);
    assert_eq!(control.lines().count(), n_control + 2);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_campaign_naming_an_unusable_second_crs_is_reported_when_read() {
    let dir = std::env::temp_dir().join(format!("skytie_second_crs_read_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("campaign.toml"),
        "name = \"t\"\ncrs = \"EPSG:28992+5709\"\n[outputs]\nalso_crs = \"EPSG:4937\"\n",
    )
    .unwrap();
    let (_, problems) = skytie_stages::campaign::read_campaign(&dir).unwrap();
    let p = problems
        .iter()
        .find(|p| p.field.as_deref() == Some("outputs"))
        .expect("the [outputs] table is reported");
    assert!(p.is_error(), "{p}");
    assert!(
        p.to_string().contains("campaign.toml") && p.to_string().contains("geoid"),
        "{p}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

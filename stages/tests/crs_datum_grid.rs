//! Grid-based datum shifts: an NTv2 grid written by the test (the public NTv2 layout: an overview header of
//! 11 records, a sub-grid header of 11 records — bounds and spacing in arc-seconds, longitudes positive west
//! — then per node the latitude and longitude shift in arc-seconds and their accuracies, rows from south to
//! north, each row from east to west) replaces the Helmert parameters of RD New's EPSG definition, for the
//! second output CRS and for imports; a missing or unreadable grid and a point outside it are errors.

use skytie_stages::crs::{Crs, DatumGridError, HorizontalTransform, OutputsSection, SecondCrs};
use std::path::{Path, PathBuf};

/// Shift of the fixture grid, arc-seconds: north and east.
const SHIFT_NORTH_SEC: f64 = 2.0;
const SHIFT_EAST_SEC: f64 = 3.0;

fn record(out: &mut Vec<u8>, key: &str, value: &[u8]) {
    let mut k = key.as_bytes().to_vec();
    k.resize(8, b' ');
    out.extend_from_slice(&k);
    let mut v = value.to_vec();
    v.resize(8, 0);
    out.extend_from_slice(&v);
}

fn text(s: &str) -> Vec<u8> {
    let mut v = s.as_bytes().to_vec();
    v.resize(8, b' ');
    v
}

/// A little-endian NTv2 file with one sub-grid over latitudes 51°–53.5° and longitudes 4°–7° E (0.5°
/// spacing) shifting every point by the constants above.
fn ntv2_fixture() -> Vec<u8> {
    let (south, north, west_e, east_e, step) = (51.0, 53.5, 4.0, 7.0, 0.5);
    let rows = ((north - south) / step) as usize + 1;
    let cols = ((east_e - west_e) / step) as usize + 1;
    let mut out = Vec::new();
    record(&mut out, "NUM_OREC", &11i32.to_le_bytes());
    record(&mut out, "NUM_SREC", &11i32.to_le_bytes());
    record(&mut out, "NUM_FILE", &1i32.to_le_bytes());
    record(&mut out, "GS_TYPE", &text("SECONDS"));
    record(&mut out, "VERSION", &text("NTv2.0"));
    record(&mut out, "SYSTEM_F", &text("BESSEL"));
    record(&mut out, "SYSTEM_T", &text("ETRS89"));
    record(&mut out, "MAJOR_F", &6_377_397.155f64.to_le_bytes());
    record(&mut out, "MINOR_F", &6_356_078.963f64.to_le_bytes());
    record(&mut out, "MAJOR_T", &6_378_137.0f64.to_le_bytes());
    record(&mut out, "MINOR_T", &6_356_752.314f64.to_le_bytes());
    record(&mut out, "SUB_NAME", &text("FIXTURE"));
    record(&mut out, "PARENT", &text("NONE"));
    record(&mut out, "CREATED", &text("fixture"));
    record(&mut out, "UPDATED", &text("fixture"));
    record(&mut out, "S_LAT", &(south * 3600.0f64).to_le_bytes());
    record(&mut out, "N_LAT", &(north * 3600.0f64).to_le_bytes());
    // Longitudes positive west.
    record(&mut out, "E_LONG", &(-east_e * 3600.0f64).to_le_bytes());
    record(&mut out, "W_LONG", &(-west_e * 3600.0f64).to_le_bytes());
    record(&mut out, "LAT_INC", &(step * 3600.0f64).to_le_bytes());
    record(&mut out, "LONG_INC", &(step * 3600.0f64).to_le_bytes());
    record(&mut out, "GS_COUNT", &((rows * cols) as i32).to_le_bytes());
    for _ in 0..rows * cols {
        for v in [SHIFT_NORTH_SEC, -SHIFT_EAST_SEC, 0.01, 0.01] {
            out.extend_from_slice(&(v as f32).to_le_bytes());
        }
    }
    out
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skytie_datum_grid_{}_{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_grid(dir: &Path) -> PathBuf {
    let path = dir.join("fixture.gsb");
    std::fs::write(&path, ntv2_fixture()).unwrap();
    path
}

#[test]
fn an_ntv2_grid_replaces_the_helmert_datum_shift() {
    let dir = scratch("shift");
    let grid = write_grid(&dir);
    let rd = Crs::parse("EPSG:28992+5709").unwrap();
    let etrs89 = Crs::parse("EPSG:4258").unwrap();
    let rd_grid = rd.with_datum_grid(&grid).unwrap();
    let (e, n) = (155_000.0, 463_000.0);
    // On the Bessel datum itself, RD's origin.
    let (lat_b, lon_b) = HorizontalTransform::to_own_geographic(&rd)
        .apply(e, n)
        .unwrap();
    let (lat, lon) = HorizontalTransform::new(&rd_grid, &etrs89)
        .apply(e, n)
        .unwrap();
    // 10⁻⁸° ≈ 1 mm.
    assert!(
        (lat - (lat_b + SHIFT_NORTH_SEC / 3600.0)).abs() < 1e-8,
        "{lat} {lat_b}"
    );
    assert!(
        (lon - (lon_b + SHIFT_EAST_SEC / 3600.0)).abs() < 1e-8,
        "{lon} {lon_b}"
    );
    // The Helmert parameters give something else (RD's datum shift is ≈ 100 m, not 2–3 arc-seconds).
    let (lat_h, _) = HorizontalTransform::new(&rd, &etrs89).apply(e, n).unwrap();
    assert!((lat_h - lat).abs() > 1e-4);
    // The way back lands on the same map point.
    let (e2, n2) = HorizontalTransform::new(&etrs89, &rd_grid)
        .apply(lat, lon)
        .unwrap();
    assert!((e2 - e).abs() < 1e-3 && (n2 - n).abs() < 1e-3, "{e2} {n2}");
    // Outside the grid: an error, not a silent Helmert shift (≈ 50.8°N 2.8°E).
    assert!(HorizontalTransform::new(&rd_grid, &etrs89)
        .apply(-30_000.0, 320_000.0)
        .is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn missing_and_unreadable_grids_are_refused_with_their_path() {
    let dir = scratch("bad");
    let rd = Crs::parse("EPSG:28992").unwrap();
    let missing = dir.join("rdtrans2018.gsb");
    let e = rd.with_datum_grid(&missing).err().unwrap();
    assert!(matches!(
        e,
        skytie_stages::crs::CrsError::DatumGrid(DatumGridError::Missing { .. })
    ));
    assert!(e.to_string().contains("rdtrans2018.gsb"), "{e}");
    let junk = dir.join("junk.gsb");
    std::fs::write(&junk, b"not a grid at all").unwrap();
    let e = rd.with_datum_grid(&junk).err().unwrap();
    assert!(e.to_string().contains("NTv2"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_second_output_crs_uses_the_campaigns_datum_grid() {
    let dir = scratch("outputs");
    write_grid(&dir);
    let section = OutputsSection {
        also_crs: Some("EPSG:4258".into()),
        datum_grid: Some("fixture.gsb".into()),
        ..OutputsSection::default()
    };
    let s = SecondCrs::new("EPSG:28992", &section, &dir)
        .unwrap()
        .unwrap();
    let rd = Crs::parse("EPSG:28992").unwrap();
    let (lat_b, _) = HorizontalTransform::to_own_geographic(&rd)
        .apply(155_000.0, 463_000.0)
        .unwrap();
    let [lat, _, _] = s.point([155_000.0, 463_000.0, 0.0]).unwrap();
    assert!((lat - (lat_b + SHIFT_NORTH_SEC / 3600.0)).abs() < 1e-8);
    let missing = OutputsSection {
        datum_grid: Some("nowhere.gsb".into()),
        ..section
    };
    let e = SecondCrs::new("EPSG:28992", &missing, &dir).err().unwrap();
    assert!(
        e.starts_with("outputs.datum_grid") && e.contains("nowhere.gsb"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_import_names_its_missing_datum_grid() {
    use skytie_stages::import::config::CampaignSection;
    use skytie_stages::import::context::ImportContext;
    let section = CampaignSection {
        name: "t".into(),
        crs: "EPSG:28992+5709".into(),
        geoid_grid: None,
        geoid_separation_m: Some(43.25),
        datum_grid: Some(std::env::temp_dir().join("skytie_no_such_grid.gsb")),
        frame: Default::default(),
    };
    let e = ImportContext::new(&section).err().unwrap();
    assert_eq!(e.field.as_deref(), Some("campaign.datum_grid"));
    assert!(e.to_string().contains("skytie_no_such_grid.gsb"), "{e}");
}

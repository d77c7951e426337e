//! `skytie.gpkg` read back by GDAL (`ogrinfo`, Debian package `gdal-bin`, installed best-effort by
//! `.ci/run`): the six layers with their feature counts, geometry types and the campaign's EPSG code; an
//! unknown CRS gives layers without a CRS. Without `ogrinfo` the test says SKIPPED for that part and still
//! checks the file with SQLite.

mod support;

use skytie_stages::adjustment::synthetic_campaign::SyntheticCampaign;
use skytie_stages::adjustment::{AdjustConfig, AdjustmentRun, SyntheticBlockSpec, ViewSelection};
use skytie_stages::export::checkpoint_rows;
use skytie_stages::export::gpkg::{run_layers, srs_for, write_geopackage, RunLayers};
use skytie_stages::export::CorrectionSeries;
use std::path::Path;
use std::process::Command;

fn setup() -> (SyntheticCampaign, AdjustmentRun) {
    let block = SyntheticBlockSpec {
        recordings: 12,
        control_points: 6,
        seed: 5,
        ..SyntheticBlockSpec::default()
    };
    support::adjusted::adjusted_campaign(block, &AdjustConfig::default())
}

fn ogrinfo(args: &[&str], file: &Path) -> Option<String> {
    let out = Command::new("ogrinfo").args(args).arg(file).output().ok()?;
    assert!(
        out.status.success(),
        "ogrinfo failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(String::from_utf8_lossy(&out.stdout).into_owned())
}

fn write(dir: &Path, crs: &str) -> (std::path::PathBuf, Vec<(String, usize)>) {
    let (c, r) = setup();
    let series = CorrectionSeries::from_run(&c.recordings, &r).unwrap();
    let cmp = support::adjusted::checkpoint_comparison(
        &c,
        &r,
        ViewSelection::WithinRadius { radius_m: 15.0 },
    );
    let rows = checkpoint_rows(&cmp);
    let groups = [("nadir", &c.control[..])];
    let layers = run_layers(&RunLayers {
        recordings: &c.recordings,
        run: &r,
        series: &series,
        checkpoints: &c.checkpoints,
        checkpoint_rows: &rows,
        control: &groups,
        verification: None,
        verification_adjusted: None,
    });
    let srs = srs_for(crs).unwrap_or_else(|(s, _)| s);
    let path = dir.join("skytie.gpkg");
    write_geopackage(&path, &srs, &layers, "2020-01-01T00:00:00.000Z").unwrap();
    let counts = layers
        .iter()
        .map(|l| (l.name.clone(), l.features.len()))
        .collect();
    (path, counts)
}

#[test]
fn ogrinfo_lists_the_layers_and_feature_counts() {
    let d = tempfile::tempdir().unwrap();
    let (path, counts) = write(d.path(), "EPSG:28992");
    let names: Vec<&str> = counts.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "recordings_recorded",
            "recordings_adjusted",
            "corrections",
            "control_points",
            "check_points",
            "verification_segments"
        ]
    );
    assert_eq!(counts[0].1, 12);
    assert!(counts[3].1 > 0 && counts[4].1 > 0);
    let Some(list) = ogrinfo(&["-ro", "-q"], &path) else {
        println!(
            "SKIPPED: ogrinfo not installed (apt-get install -y gdal-bin); the SQLite checks ran"
        );
        return;
    };
    for (name, n) in &counts {
        assert!(list.contains(name.as_str()), "{name} not listed: {list}");
        let out = Command::new("ogrinfo")
            .args(["-ro", "-so", "-nomd"])
            .arg(&path)
            .arg(name)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains(&format!("Feature Count: {n}")),
            "{name}: expected {n} features: {text}"
        );
        assert!(text.contains("28992"), "{name}: CRS not EPSG:28992: {text}");
        let geometry = if name == "corrections" || name == "verification_segments" {
            "Line String"
        } else {
            "Point"
        };
        assert!(text.contains(geometry), "{name}: {text}");
    }
    println!("ogrinfo read {} layers", counts.len());
}

#[test]
fn an_unknown_crs_gives_layers_without_a_crs() {
    let d = tempfile::tempdir().unwrap();
    let (path, _) = write(d.path(), "local grid");
    let out = Command::new("ogrinfo")
        .args(["-ro", "-so", "-nomd"])
        .arg(&path)
        .arg("recordings_adjusted")
        .output();
    let Ok(out) = out else {
        println!("SKIPPED: ogrinfo not installed (apt-get install -y gdal-bin)");
        return;
    };
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("Feature Count: 12"), "{text}");
    assert!(!text.contains("28992"), "{text}");
}

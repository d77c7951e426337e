//! The report of a city-scale output folder stays bounded: 30 000 image-free synthetic recordings
//! (`skytie_stages::export::synthetic_outputs`, written with the real export writers) give an interactive
//! map that carries every flagged recording (those in failed segments of the adjusted trajectory's
//! verification, or not corrected) but not every recording, a map data file under 3 MB, an `index.html` under
//! 1 MB with the per-segment tables cut to their worst rows, and a static trajectory figure under 2 MB. With
//! `chromium` on PATH the thinned map must initialise and show a flagged recording selected by `#select=<id>`.

#[path = "support/report_check.rs"]
mod report_check;

use skytie::report::map_thinning::MAP_DETAIL_LIMIT;
use skytie::report::{build_report, ReportOptions};
use skytie_stages::export::synthetic_outputs::{write_outputs, OutputsSpec};
use std::collections::HashSet;

/// The bounds the report keeps for a campaign whose flagged recordings and status-run ends number ≤ 10⁴.
const MAP_DATA_MAX_BYTES: u64 = 3_000_000;
const INDEX_MAX_BYTES: u64 = 1_000_000;
const STATIC_MAP_MAX_BYTES: u64 = 2_000_000;

#[test]
fn thinned_map_of_a_large_output_keeps_every_flagged_recording_within_the_bounds() {
    let tmp = tempfile::tempdir().unwrap();
    let (campaign, out) = (tmp.path().join("campaign"), tmp.path().join("out"));
    let n = 30_000;
    let synth = OutputsSpec {
        recordings: n,
        failed_every: 3_000,
        ..OutputsSpec::default()
    }
    .generate();
    write_outputs(&synth, &campaign, &out).unwrap();
    let summary = build_report(&out, &ReportOptions::standard(None)).unwrap();

    // Flagged: the recordings of the failed segments of verification_adjusted.csv.
    let ver = std::fs::read_to_string(out.join("verification_adjusted.csv")).unwrap();
    let mut lines = ver.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let ids: Vec<&str> = synth
        .recordings
        .iter()
        .map(|r| r.image_id.as_str())
        .collect();
    let position = |id: &str| ids.iter().position(|x| *x == id).unwrap();
    let mut flagged = Vec::new();
    for l in lines {
        let cells: Vec<&str> = l.split(',').collect();
        if cells[col("segment")] != "all" && cells[col("status")] == "fail" {
            let (a, b) = (
                position(cells[col("first_image_id")]),
                position(cells[col("last_image_id")]),
            );
            flagged.extend(ids[a..=b].iter().map(|s| s.to_string()));
        }
    }
    assert!(
        flagged.len() >= 10 * synth.spec.segment_recordings / 2,
        "the synthetic output has failed segments: {}",
        flagged.len()
    );

    let data_path = out.join("report/figures/map-data.js");
    let text = std::fs::read_to_string(&data_path).unwrap();
    let json = text
        .split_once("] = ")
        .map(|(_, rest)| rest.trim_end().trim_end_matches(';'))
        .unwrap();
    let doc: serde_json::Value = serde_json::from_str(json).unwrap();
    let shown: HashSet<&str> = doc["recordings"]["id"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    for id in &flagged {
        assert!(
            shown.contains(id.as_str()),
            "flagged {id} is not on the map"
        );
    }
    assert!(shown.len() < n, "the map is thinned");
    assert!(shown.len() <= MAP_DETAIL_LIMIT + flagged.len() + 2 * 200);
    assert_eq!(doc["thinned"]["recordings"], serde_json::json!(n));
    // Segments index the kept recordings and every failed run is drawn.
    let kept = shown.len() as u64;
    for s in doc["segments"].as_array().unwrap() {
        assert!(s["from"].as_u64().unwrap() <= s["to"].as_u64().unwrap());
        assert!(s["to"].as_u64().unwrap() < kept);
    }
    let size = |p: &std::path::Path| std::fs::metadata(p).unwrap().len();
    assert!(
        size(&data_path) <= MAP_DATA_MAX_BYTES,
        "{} bytes",
        size(&data_path)
    );
    assert!(
        size(&summary.index) <= INDEX_MAX_BYTES,
        "{} bytes",
        size(&summary.index)
    );
    let html = std::fs::read_to_string(&summary.index).unwrap();
    assert!(
        html.contains("rows shown (failed segments first"),
        "long tables are cut"
    );
    assert!(
        html.contains(&format!("of the {n} recordings")),
        "the map says it is thinned"
    );
    let figure = out.join("report/figures/trajectory.svg");
    assert!(
        size(&figure) <= STATIC_MAP_MAX_BYTES,
        "{} bytes",
        size(&figure)
    );
    if let Some(chromium) = report_check::find_chromium() {
        let profile = tmp.path().join("chromium-profile");
        let fragment = format!("#select={}", flagged[0]);
        let dom = report_check::dump_dom_fragment(&chromium, &summary.index, &fragment, &profile);
        let attr = |id: &str, a: &str| report_check::element_attr(&dom, id, a);
        assert_eq!(attr("map-run", "data-ready").as_deref(), Some("1"));
        assert_eq!(
            attr("map-run", "data-recordings"),
            Some(shown.len().to_string())
        );
        assert_eq!(
            attr("panel-run", "data-selected").as_deref(),
            Some(flagged[0].as_str())
        );
    } else {
        println!("SKIPPED the browser check: chromium not installed (apt-get install -y chromium)");
    }
    // Every row stays in the table files.
    let table = std::fs::read_to_string(out.join("report/tables/verification.csv")).unwrap();
    assert_eq!(
        table.lines().count(),
        ver.lines().count(),
        "all verification rows in the CSV"
    );
}

//! The HTML report: `workflows/tiny.toml` on the generated tiny campaign through the real binary
//! (the run writes `OUT/report/`), then `skytie report OUT` rebuilds it byte-identically in ≤ 10 s; every
//! image and table file the page references exists and is non-empty; with `chromium` on PATH the page is
//! rendered headless, every image must load with a non-zero natural size, and a screenshot is written.
//! The page opens with the answer (`#answer`) and the interactive map (`#map-run`, Leaflet from `assets/`),
//! diagnostics last; in Chromium the map must initialise, draw the recordings and show a recording's numbers
//! when selected (`#select=<id>`, the click's code path). A second test builds a sweep report from a hand-made
//! OUT whose tables have known values; a third a map of 10⁴ recordings from a hand-made OUT.

#[path = "support/cli.rs"]
mod cli;
#[path = "support/report_check.rs"]
mod report_check;

use cli::{files_under, run_ok, run_workflow, skytie};
use report_check::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Every referenced image / table file of `page` exists and is non-empty; returns the image paths.
fn check_references(page: &Path) -> Vec<PathBuf> {
    let (imgs, links) = referenced_files(page);
    for f in imgs.iter().chain(&links) {
        let len = std::fs::metadata(f)
            .unwrap_or_else(|e| panic!("{} references {}: {e}", page.display(), f.display()))
            .len();
        assert!(len > 0, "{} is empty", f.display());
    }
    imgs
}

/// Where the test leaves its screenshots (kept after the test for a person to look at).
fn screenshot_dir() -> PathBuf {
    let d = std::env::temp_dir().join("skytie-report-test");
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn report_of_a_tiny_run() {
    let tmp = tempfile::tempdir().unwrap();
    let (cache, out) = (tmp.path().join("cache"), tmp.path().join("out"));
    let wf = Path::new(env!("CARGO_MANIFEST_DIR")).join("workflows/tiny.toml");
    let _ = run_workflow(&wf, &cache, &out);
    let report = out.join("report");
    let index = report.join("index.html");
    assert!(
        index.is_file(),
        "skytie run did not write {}",
        index.display()
    );
    let first = files_under(&report, &[]);
    // A figure and a table an earlier build left (e.g. of a removed variant) are stale: the rebuild removes them.
    let stale = [
        report.join("figures/registration-nadir-gone-000000000000.png"),
        report.join("tables/gone-variant-accuracy.csv"),
    ];
    for s in &stale {
        std::fs::write(s, b"stale").unwrap();
    }

    // Rebuild from OUT alone: byte-identical, fast.
    let t0 = Instant::now();
    run_ok(skytie().arg("report").arg(&out));
    let rebuild_s = t0.elapsed().as_secs_f64();
    println!("report rebuild: {rebuild_s:.2} s");
    assert!(rebuild_s <= 10.0, "report rebuild took {rebuild_s:.1} s");
    for s in &stale {
        assert!(!s.exists(), "{} was not removed", s.display());
    }
    let second = files_under(&report, &[]);
    let differing: Vec<&String> = first
        .keys()
        .chain(second.keys())
        .filter(|k| first.get(*k) != second.get(*k))
        .collect();
    assert!(differing.is_empty(), "rebuild changed: {differing:?}");

    // Structure: sections and tables, their CSV + Markdown files.
    let html = std::fs::read_to_string(&index).unwrap();
    for id in [
        "summary-run",
        "table-3-1",
        "thesis-table-3-1",
        "accuracy",
        "verification",
        "thesis-table-5-13",
    ] {
        assert!(
            html.contains(&format!("id=\"table-{id}\"")),
            "table {id} missing"
        );
        for ext in ["csv", "md"] {
            let f = report.join("tables").join(format!("{id}.{ext}"));
            assert!(
                std::fs::metadata(&f).map(|m| m.len() > 0).unwrap_or(false),
                "{}",
                f.display()
            );
        }
    }
    // The rejections table carries the nadir refinement's funnel as metrics.json counts it.
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    let rejections = std::fs::read_to_string(report.join("tables/summary-rejections.csv")).unwrap();
    let mut listed = 0;
    for (key, reason) in [
        ("unusable_templates", "no usable template"),
        ("weak_peaks", "correlation peak below min_peak"),
        ("beyond_search", "found beyond the search margin"),
    ] {
        let n = metrics["nadir"][key].as_u64().unwrap();
        let row = rejections.lines().find(|l| l.contains(reason));
        if n == 0 {
            assert!(row.is_none(), "{key} is 0 but listed");
        } else {
            let row = row.unwrap_or_else(|| panic!("{key} = {n} not listed"));
            assert!(row.ends_with(&format!(",{n}")), "{row} vs {key} = {n}");
            listed += 1;
        }
    }
    assert!(listed > 0, "the tiny run locates every tie point it tries");
    // The run's own log (times, nodes executed / cached) is kept apart from the result tables.
    for id in ["summary-engine", "summary-stages"] {
        assert!(
            html.contains(&format!("id=\"table-{id}\"")),
            "table {id} missing"
        );
        assert!(
            html.contains(&format!("href=\"run-log/{id}.csv\"")),
            "{id} not linked from run-log/"
        );
        assert!(!report.join("tables").join(format!("{id}.csv")).exists());
    }
    assert!(html.contains("thesis (Rotterdam data)") && html.contains("skytie (this campaign)"));
    // Answer first, then the map; diagnostics (engine counters) after the results.
    let pos = |needle: &str| {
        html.find(needle)
            .unwrap_or_else(|| panic!("{needle} missing from the page"))
    };
    assert!(pos("id=\"answer\"") < pos("id=\"map\""));
    assert!(pos("id=\"map\"") < pos("id=\"accuracy\""));
    assert!(pos("id=\"accuracy\"") < pos("id=\"summary\""));
    assert!(pos("id=\"summary\"") < pos("id=\"table-summary-engine\""));
    assert!(html.contains("Sign convention everywhere"));
    assert!(
        html.contains("Per segment, recorded poses: MM − aerial"),
        "our offsets are labelled MM − aerial"
    );
    assert!(
        !html.contains("centre_offset_n_m"),
        "rejection reasons must be words"
    );
    for f in [
        "assets/leaflet.js",
        "assets/leaflet.css",
        "assets/map.js",
        "figures/map-data.js",
    ] {
        assert!(report.join(f).is_file(), "{f} missing");
    }
    let md = std::fs::read_to_string(report.join("run-log/summary-stages.md")).unwrap();
    assert!(
        md.contains("| stage | executed | cached | failed | skipped | seconds |"),
        "{md}"
    );
    let imgs = check_references(&index);
    let names: Vec<String> = imgs
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert!(names.contains(&"trajectory.svg".to_string()), "{names:?}");
    assert!(
        names.contains(&"checkpoint-residuals.svg".to_string()),
        "{names:?}"
    );
    let map = std::fs::read_to_string(report.join("figures/trajectory.svg")).unwrap();
    assert!(
        map.contains("easting") && map.contains("northing") && map.contains("recorded position")
    );
    let has_nadir_rows = std::fs::read_to_string(out.join("correspondences.csv"))
        .map(|t| t.lines().skip(1).any(|l| l.starts_with("nadir,")))
        .unwrap_or(false);
    if has_nadir_rows {
        assert!(
            names.iter().any(|n| n.starts_with("registration-nadir-")),
            "no nadir registration view although correspondences.csv has nadir rows: {names:?}"
        );
    }

    // Re-running the workflow (warm cache: nothing executes) reproduces every result table byte-identically;
    // only the run log (times, nodes executed / cached) differs.
    let rerun = tmp.path().join("out-rerun");
    let _ = run_workflow(&wf, &cache, &rerun);
    let (tables, tables_rerun) = (
        files_under(&report.join("tables"), &[]),
        files_under(&rerun.join("report/tables"), &[]),
    );
    assert!(tables.len() > 10, "{} tables", tables.len());
    let differing: Vec<&String> = tables
        .keys()
        .chain(tables_rerun.keys())
        .filter(|k| tables.get(*k) != tables_rerun.get(*k))
        .collect();
    assert!(
        differing.is_empty(),
        "a rerun changed the tables {differing:?}"
    );
    let engine = std::fs::read_to_string(rerun.join("report/run-log/summary-engine.csv")).unwrap();
    assert!(engine.contains("nodes executed,0"), "{engine}");

    // Headless Chromium: every image loads with a non-zero natural size; screenshot.
    let Some(chromium) = find_chromium() else {
        println!("SKIPPED: chromium not installed (apt-get install -y chromium); the HTML checks above ran");
        return;
    };
    let profile = tmp.path().join("chromium-profile");
    let dom = dump_dom(&chromium, &index, &profile);
    let sizes = image_sizes(&dom);
    // `imgs` also holds the scripts' src (Leaflet, the map and its data); the page's images are its <img> tags.
    assert_eq!(
        sizes.len(),
        html.matches("<img ").count(),
        "images in the rendered DOM vs the page"
    );
    for (src, w, h) in &sizes {
        assert!(
            *w > 0 && *h > 0,
            "image {src} did not load in chromium ({w} × {h})"
        );
    }
    let png = screenshot_dir().join("tiny-index.png");
    screenshot(&chromium, &index, &png, &profile, 1400, 6000);
    assert!(
        std::fs::metadata(&png).unwrap().len() > 10_000,
        "{}",
        png.display()
    );
    println!(
        "chromium: {} images loaded; screenshot {}",
        sizes.len(),
        png.display()
    );
    check_map_in_chromium(&chromium, &index, &profile, &out);
}

/// The map initialises, draws the recordings and shows a selected recording's numbers.
fn check_map_in_chromium(chromium: &Path, index: &Path, profile: &Path, out: &Path) {
    let dom = dump_dom(chromium, index, profile);
    assert_eq!(
        element_attr(&dom, "map-run", "data-ready").as_deref(),
        Some("1"),
        "the map did not initialise"
    );
    let n: usize = element_attr(&dom, "map-run", "data-recordings")
        .unwrap()
        .parse()
        .unwrap();
    let drawn: usize = element_attr(&dom, "map-run", "data-drawn")
        .unwrap()
        .parse()
        .unwrap();
    assert!(n > 0 && drawn == n, "{drawn} of {n} recordings drawn");
    // A recording to select: the first one of the run's GeoJSON (written whether or not anything was
    // corrected).
    let geojson: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("trajectory.geojson")).unwrap())
            .unwrap();
    let first = geojson["features"]
        .as_array()
        .unwrap()
        .iter()
        .find_map(|f| f["properties"]["image_id"].as_str())
        .expect("a recording in trajectory.geojson")
        .to_string();
    let dom = dump_dom_fragment(chromium, index, &format!("#select={first}"), profile);
    assert_eq!(
        element_attr(&dom, "panel-run", "data-selected").as_deref(),
        Some(first.as_str())
    );
    assert!(dom.contains("moved horizontally"), "panel without numbers");
    println!(
        "map: {n} recordings drawn, init {} ms",
        element_attr(&dom, "map-run", "data-init-ms").unwrap_or_default()
    );
}

fn write(path: &Path, text: &str) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

fn variant_metrics(tie: u32, correct: u32, after_3d: f64, inl: u32, outl: u32, nm: u32) -> String {
    serde_json::json!({
        "campaign": {"name": "fixture", "recordings": 10},
        "nadir": {"tie_points": tie, "correct_tie_points": correct,
                  "inlier_ratio": correct as f64 / tie as f64, "transforms_accepted": 10,
                  "control_points": 5},
        "oblique": {"inliers": inl, "outliers": outl, "non_matchable": nm,
                    "inliers_after_consensus": inl, "outliers_after_consensus": outl / 2,
                    "non_matchable_after_consensus": nm / 2},
        "adjust": {"nadir": {"checkpoints": {
            "before": {"x": 0.5, "y": 0.4, "z": 0.1, "2d": 0.64, "3d": 0.65, "count": 4},
            "after": {"x": 0.1, "y": 0.1, "z": 0.05, "2d": 0.14, "3d": after_3d, "count": 4}}}},
        "verify": {"passed": true, "segments": 1, "segments_failed": 0}
    })
    .to_string()
}

#[test]
fn sweep_report_from_a_fixture_has_known_tables() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    write(
        &out.join("metrics.json"),
        &serde_json::json!({
            "engine": {"nodes_total": 4, "nodes_executed": 3, "nodes_cached": 1, "nodes_failed": 0,
                       "nodes_skipped": 0, "seconds": 1.5, "warnings": 0},
            "stages": {"adjust": {"executed": 2, "cached": 0, "failed": 0, "skipped": 0, "seconds": 0.5}},
            "variants": ["w1", "w2"]
        })
        .to_string(),
    );
    write(
        &out.join("provenance.json"),
        &serde_json::json!({
            "workflow": {"name": "fixture-sweep", "pipeline": "skytie"},
            "stages": {"adjust": {"params": {
                "w1": {"sources": "nadir", "dimensions": "horizontal", "weighting_method": 1},
                "w2": {"sources": "nadir", "dimensions": "horizontal", "weighting_method": 2}}}}
        })
        .to_string(),
    );
    write(
        &out.join("variants/w1/metrics.json"),
        &variant_metrics(100, 90, 0.2, 30, 10, 10),
    );
    write(
        &out.join("variants/w2/metrics.json"),
        &variant_metrics(50, 20, 0.3, 10, 30, 0),
    );
    write(
        &out.join("sweep.csv"),
        "variant,nadir.tie_points\nw1,100\nw2,50\n",
    );

    let s =
        skytie::report::build_report(&out, &skytie::report::ReportOptions::standard(None)).unwrap();
    let table =
        |id: &str| std::fs::read_to_string(out.join(format!("report/tables/{id}.csv"))).unwrap();
    // Table 2-10 structure: per tile = / 10 accepted transforms; ratio from inlier_ratio.
    assert_eq!(
        table("sweep-table-2-10"),
        "variant,matches,inliers,matches/tile,inliers/tile,ratio %\nw1,100,90,10.0,9.0,90.0\nw2,50,20,5.0,2.0,40.0\n"
    );
    // Oblique: inlier % of all and of matchable correspondences, before and after the consensus (the fixture
    // keeps every inlier and half the outliers and non-matchable ones: w1 30/(30+5+5), 30/35; w2 10/25).
    assert_eq!(
        table("sweep-oblique"),
        "variant,inliers,outliers,non-matchable,inlier %,inlier % without non-matchable,\
         inlier % after outlier removal,inlier % after outlier removal without non-matchable\n\
         w1,30,10,10,60.0,75.0,75.0,85.7\nw2,10,30,0,25.0,25.0,40.0,40.0\n"
    );
    // Tables 5-11 structure: one column per weighting method, before from the recorded poses.
    let adj = table("sweep-adjust-nadir-horizontal");
    assert!(
        adj.starts_with("\"\",before,method 1 (w1),method 2 (w2)\n")
            || adj.starts_with(",before,method 1 (w1),method 2 (w2)\n"),
        "{adj}"
    );
    assert!(adj.contains("RMSE 3D,0.650,0.200,0.300\n"), "{adj}");
    assert!(s.tables.contains(&"thesis-table-5-11".to_string()));
    assert!(
        !s.tables.contains(&"thesis-table-5-12".to_string()),
        "no full adjustment in the sweep"
    );
    // Pages: index + one per variant, all references resolve.
    assert_eq!(s.pages.len(), 3);
    for p in &s.pages {
        check_references(p);
    }
    let index = std::fs::read_to_string(&s.index).unwrap();
    for f in [
        "sweep-nadir-tie-points.svg",
        "sweep-oblique-correspondences.svg",
        "sweep-adjust-rmse.svg",
    ] {
        assert!(
            index.contains(&format!("figures/{f}")),
            "{f} not on the index page"
        );
    }
    assert!(index.contains("href=\"variant-w1.html\""));
    if let Some(chromium) = find_chromium() {
        let profile = tmp.path().join("chromium-profile");
        let sizes = image_sizes(&dump_dom(&chromium, &s.index, &profile));
        assert_eq!(sizes.len(), 3);
        assert!(sizes.iter().all(|(_, w, h)| *w > 0 && *h > 0), "{sizes:?}");
        screenshot(
            &chromium,
            &s.index,
            &screenshot_dir().join("sweep-index.png"),
            &profile,
            1400,
            4000,
        );
    } else {
        println!("SKIPPED: chromium not installed (apt-get install -y chromium); the HTML checks above ran");
    }
}

/// A hand-made OUT with `n` recordings along a winding street, each moved by a known correction.
fn large_run(out: &Path, n: usize) {
    let pos = |i: usize| {
        let s = i as f64 * 5.0;
        [85_000.0 + s, 445_000.0 + 200.0 * (s / 2000.0).sin()]
    };
    let mut features = Vec::new();
    let mut corr = String::from(
        "time,time_s,image_id,kind,support,de_m,dn_m,du_m,dyaw_deg,sigma_e_m,sigma_n_m,sigma_u_m,sigma_yaw_deg\n",
    );
    for i in 0..n {
        let p = pos(i);
        let (de, dn) = (0.8 + 0.1 * (i as f64 * 0.01).sin(), -0.2);
        let support = ["controlled", "bridged", "extrapolated", "uncorrected"][i % 4];
        for (layer, x, y) in [("recorded", p[0], p[1]), ("adjusted", p[0] + de, p[1] + dn)] {
            features.push(serde_json::json!({"type": "Feature",
                "geometry": {"type": "Point", "coordinates": [x, y, 1.0]},
                "properties": {"layer": layer, "image_id": format!("r{i:05}")}}));
        }
        corr.push_str(&format!(
            "2020-01-01T00:00:00Z,{},r{i:05},recording,{support},{de},{dn},0,0,0.03,0.03,0.05,0\n",
            1_577_836_800 + i
        ));
    }
    write(
        &out.join("trajectory.geojson"),
        &serde_json::json!({"type": "FeatureCollection", "features": features}).to_string(),
    );
    write(&out.join("corrections.csv"), &corr);
    let mut ver = String::from(
        "segment,first_image_id,last_image_id,recordings,points,mean_x,mean_y,mean_z,status\n",
    );
    for s in 0..n / 100 {
        let status = if s % 7 == 3 { "fail" } else { "pass" };
        ver.push_str(&format!(
            "{s},r{:05},r{:05},100,12,0.02,0.01,0.0,{status}\n",
            s * 100,
            s * 100 + 99
        ));
    }
    write(&out.join("verification_adjusted.csv"), &ver);
    write(
        &out.join("metrics.json"),
        &serde_json::json!({
            "campaign": {"name": "large", "recordings": n},
            "adjust": {"combined": {"checkpoints": {
                "before": {"2d": 0.8, "count": 10}, "after": {"2d": 0.05, "count": 10}}}}
        })
        .to_string(),
    );
}

#[test]
fn map_of_ten_thousand_recordings() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let n = 10_000;
    large_run(&out, n);
    let t0 = Instant::now();
    let s =
        skytie::report::build_report(&out, &skytie::report::ReportOptions::standard(None)).unwrap();
    println!(
        "report of {n} recordings built in {:.2} s",
        t0.elapsed().as_secs_f64()
    );
    let html = std::fs::read_to_string(&s.index).unwrap();
    assert!(
        html.contains("7500 of 10000 recordings corrected"),
        "headline"
    );
    assert!(html.contains("2500 not corrected"));
    assert!(html.contains("id=\"table-verification-adjusted\""));
    let Some(chromium) = find_chromium() else {
        println!("SKIPPED: chromium not installed (apt-get install -y chromium); the HTML checks above ran");
        return;
    };
    let profile = tmp.path().join("chromium-profile");
    let dom = dump_dom_fragment(&chromium, &s.index, "#select=r05000", &profile);
    assert_eq!(
        element_attr(&dom, "map-run", "data-ready").as_deref(),
        Some("1")
    );
    assert_eq!(
        element_attr(&dom, "map-run", "data-recordings").as_deref(),
        Some("10000")
    );
    assert_eq!(
        element_attr(&dom, "panel-run", "data-selected").as_deref(),
        Some("r05000")
    );
    let ms = |a: &str| element_attr(&dom, "map-run", a).unwrap_or_default();
    println!(
        "map of {n} recordings in headless Chromium: init {} ms, last redraw {} ms",
        ms("data-init-ms"),
        ms("data-redraw-ms")
    );
    screenshot(
        &chromium,
        &s.index,
        &screenshot_dir().join("large-index.png"),
        &profile,
        1400,
        1400,
    );
}

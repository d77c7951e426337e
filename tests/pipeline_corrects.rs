//! End-to-end check that fails when registration or adjustment breaks: the shipped default workflow
//! (`skytie run default --campaign DIR`) on a tiny street that has content to register, with its results
//! asserted against the campaign's truth.
//!
//! The tiny preset's own 1024-px panoramas resolve the road markings too coarsely for the refinement to locate
//! tie points in the aerial frames (none of its 6 recordings registers), so this street is the tiny preset with
//! 2048-px panoramas (`skytie synth --preset tiny --panorama-width 2048`, seed 1, the thesis' error profile:
//! 0.80 m systematic + N(0, 0.10 m)). Measured: 112 MM tie points (all correct against the truth), 13 aerial
//! tie points located (all correct), 5 of 6 recordings with their own aerial evidence, recordings 0.785 →
//! 0.066 m RMSE 2D (worst 0.122 m), check points 0.738 → 0.499 m (of its 3 check points the one behind the
//! first recording is intersected from two nearly parallel rays, so the check points say little here).
//! The campaign also asks for its outputs in a second CRS (`[outputs] also_crs`), checked against the run's
//! campaign-CRS trajectory.

#[path = "support/cli.rs"]
mod cli;

use cli::{json, run_ok, skytie, synth_tiny};

/// A number in metrics.json, by path.
fn num(m: &serde_json::Value, path: &[&str]) -> f64 {
    let mut v = m;
    for k in path {
        v = &v[*k];
    }
    v.as_f64()
        .unwrap_or_else(|| panic!("{} missing in metrics.json: {m}", path.join(".")))
}

#[test]
fn a_tiny_street_with_road_markings_is_corrected() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let camp = dir.join("tiny2048");
    synth_tiny(&camp, 1, &["--panorama-width", "2048"]);
    // The campaign also asks for its outputs in ETRS89 / UTM zone 31N ([outputs], docs/outputs.md).
    let toml_path = camp.join("campaign.toml");
    let mut toml = std::fs::read_to_string(&toml_path).unwrap();
    toml.push_str("\n[outputs]\nalso_crs = \"EPSG:25831\"\n");
    std::fs::write(&toml_path, toml).unwrap();
    let out = dir.join("out");
    // Exit 0: the run corrected the trajectory and delivered it.
    run_ok(
        skytie()
            .args(["run", "default", "--campaign"])
            .arg(&camp)
            .arg("--cache")
            .arg(dir.join("cache"))
            .arg("--out")
            .arg(&out)
            .arg("--quiet"),
    );
    let m = json(&out.join("metrics.json"));

    // Registration (thesis ch. 3): the MM tie points and the aerial tie points are right.
    let mm = num(&m, &["nadir", "mm_tie_points"]);
    assert!(mm >= 80.0, "MM tie points: {mm}");
    assert!(
        num(&m, &["nadir", "mm_tie_points_correct"])
            >= 0.95 * num(&m, &["nadir", "mm_tie_points_graded"]),
        "MM tie points against the truth: {}",
        m["nadir"]
    );
    assert!(num(&m, &["nadir", "tie_points"]) >= 8.0, "{}", m["nadir"]);
    assert!(
        num(&m, &["nadir", "inlier_ratio"]) >= 0.97,
        "{}",
        m["nadir"]
    );
    assert!(
        num(&m, &["nadir", "recordings_with_aerial"]) >= 2.0,
        "{}",
        m["nadir"]
    );

    // The default workflow's second registration pass: every recording with a window is counted, the
    // recordings the first pass left without control are searched again, and none is lost.
    let passes = &m["registration_passes"];
    let first = num(passes, &["registered_first_pass"]);
    let windows = num(passes, &["recordings"]);
    assert!(windows >= 5.0, "{passes}");
    assert!(
        num(passes, &["registered_second_pass"]) >= first,
        "{passes}"
    );
    assert!(
        num(passes, &["searched_again"]) <= windows - first,
        "only unregistered recordings are searched again: {passes}"
    );

    // The oblique chain's second pass, registered again from the adjusted poses: graded apart from the first
    // (whose numbers stay the thesis' registration), and what correspondences.csv delivers.
    let second = &m["oblique_pass2"];
    assert!(num(second, &["consensus_kept"]) > 0.0, "{second}");
    assert!(
        num(second, &["inlier_ratio_after_consensus"]) >= 0.8,
        "{second}"
    );
    let exported = std::fs::read_to_string(out.join("correspondences.csv")).unwrap();
    let oblique_points: std::collections::BTreeSet<String> = csv_rows(&exported)
        .into_iter()
        .filter(|r| r["source"] == "oblique")
        .map(|r| r["point_id"].clone())
        .collect();
    assert_eq!(
        oblique_points.len() as f64,
        num(second, &["control_points"]) + num(second, &["single_image_points"]),
        "correspondences.csv holds the second pass's oblique points: {second}"
    );

    // Adjustment (thesis ch. 5): every recording corrected, the error at least 5× smaller, none left > 0.15 m.
    let a = &m["adjust"]["combined"];
    assert_eq!(a["verdict"].as_str(), Some("corrected"), "{a}");
    let before = num(a, &["recordings", "before", "rmse_2d"]);
    let after = num(a, &["recordings", "after", "rmse_2d"]);
    assert!(before > 0.7, "the deterioration must show: {before}");
    assert!(
        after * 5.0 <= before,
        "recordings {before} → {after} m RMSE 2D"
    );
    assert!(num(a, &["recordings", "after", "max_2d"]) <= 0.15, "{a}");
    assert!(
        num(a, &["checkpoints", "after", "2d"]) < num(a, &["checkpoints", "before", "2d"]),
        "check points must improve: {a}"
    );
    let adjusted = std::fs::read_to_string(out.join("trajectory_adjusted.csv")).unwrap();
    assert_eq!(adjusted.lines().count(), 7, "6 recordings + header");
    second_crs_matches_the_campaign_crs(&adjusted, &out.join("epsg_25831"));
}

/// Rows of a CSV (first line = header) as maps from column name to value; `#` lines skipped.
fn csv_rows(text: &str) -> Vec<std::collections::HashMap<String, String>> {
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(h, v)| (h.to_string(), v.to_string()))
                .collect()
        })
        .collect()
}

/// The second-CRS trajectory holds every recording, in UTM 31N where this RD New street lies (around
/// 51.9° N, 3.9° E), with the same distances between recordings and corrections of the same length (a
/// rotation by the difference of the two grids' convergence) as the campaign-CRS trajectory.
fn second_crs_matches_the_campaign_crs(adjusted_rd: &str, folder: &std::path::Path) {
    let text = std::fs::read_to_string(folder.join("trajectory_adjusted.csv"))
        .unwrap_or_else(|e| panic!("{}: {e}", folder.display()));
    assert!(text.starts_with("# crs = EPSG:25831"), "{text}");
    for file in ["corrections.csv", "control_points.csv"] {
        assert!(
            folder.join(file).is_file(),
            "{file} in {}",
            folder.display()
        );
    }
    let rd = csv_rows(adjusted_rd);
    let utm = csv_rows(&text);
    assert_eq!(rd.len(), utm.len());
    let f = |r: &std::collections::HashMap<String, String>, k: &str| -> f64 {
        r[k].parse().unwrap_or_else(|_| panic!("{k} in {r:?}"))
    };
    for (a, b) in rd.iter().zip(&utm) {
        assert_eq!(a["image_id"], b["image_id"]);
        let (e, n) = (f(b, "x"), f(b, "y"));
        assert!(
            (500_000.0..700_000.0).contains(&e) && (5_700_000.0..5_850_000.0).contains(&n),
            "{b:?}"
        );
        let moved_rd = f(a, "dx_m").hypot(f(a, "dy_m"));
        let moved_utm = f(b, "de_m").hypot(f(b, "dn_m"));
        assert!((moved_rd - moved_utm).abs() < 1e-6, "{a:?} vs {b:?}");
        assert!(
            (f(a, "z") - f(b, "z")).abs() < 1e-9,
            "no vertical CRS: heights copied"
        );
    }
    for k in 1..rd.len() {
        let d = |rows: &[std::collections::HashMap<String, String>]| {
            (f(&rows[k], "x") - f(&rows[k - 1], "x")).hypot(f(&rows[k], "y") - f(&rows[k - 1], "y"))
        };
        // The two projections' scale factors differ by a few 10⁻⁴ at most.
        assert!(
            (d(&rd) - d(&utm)).abs() < 1e-3 * d(&rd),
            "{} vs {}",
            d(&rd),
            d(&utm)
        );
    }
}

//! End-to-end check that fails when registration or adjustment breaks: the shipped default workflow
//! (`skytie run default --campaign DIR`) on a tiny street that has content to register, with its results
//! asserted against the campaign's truth.
//!
//! The tiny preset's own 1024-px panoramas resolve the road markings too coarsely for the refinement to locate
//! tie points in the aerial frames (none of its 6 recordings registers), so this street is the tiny preset with
//! 2048-px panoramas (`skytie synth --preset tiny --panorama-width 2048`, seed 1, the thesis' error profile:
//! 0.80 m systematic + N(0, 0.10 m)). Measured: 112 MM tie points (all correct against the truth), 13 aerial
//! tie points located (all correct), 5 of 6 recordings with their own aerial evidence, recordings 0.785 →
//! 0.066 m RMSE 2D (worst 0.101 m), check points 0.738 → 0.508 m (of its 3 check points the one behind the
//! first recording is intersected from two nearly parallel rays, so the check points say little here).

#[path = "support/cli.rs"]
mod cli;

use cli::{json, run_ok, skytie};

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
    run_ok(
        skytie()
            .args(["synth", "--preset", "tiny", "--seed", "1"])
            .args(["--panorama-width", "2048", "--out"])
            .arg(&camp),
    );
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
}

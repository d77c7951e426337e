//! End-to-end on the real `skytie` binary and the tiny synthetic campaign: `synth` + `check` are clean, the
//! `synth:` workflow node generates the same bytes as the CLI, a second run executes nothing, and adding one
//! recording to a user campaign re-runs only that recording's nodes, and the shipped full chain
//! (`workflows/tiny.toml`) runs through registration, adjustment, verification and the exports — with results
//! that must hold: nadir correspondences registered with a high inlier ratio, the adjustment bringing check
//! points and recordings at least 3× closer to the truth, and the verification flagging the 0.8 m offset.

#[path = "support/cli.rs"]
mod cli;

use cli::{run_ok, skytie};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn files(root: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(
                    p.strip_prefix(root).unwrap().display().to_string(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(root, root, &mut out);
    out
}

fn metrics(out: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(out.join("metrics.json")).unwrap()).unwrap()
}

fn stage(m: &serde_json::Value, stage: &str, what: &str) -> u64 {
    m["stages"][stage][what]
        .as_u64()
        .unwrap_or_else(|| panic!("stages.{stage}.{what} missing in {m}"))
}

/// `skytie run WF --cache CACHE --out OUT --quiet`, then OUT's metrics.
fn run_workflow(wf: &Path, cache: &Path, out: &Path) -> serde_json::Value {
    let _ = cli::run_workflow(wf, cache, out);
    metrics(out)
}

/// [`run_workflow`] that must exit 0: nothing dropped, failed or flagged (the adjustment corrected the
/// trajectory and the check points did not get worse).
fn run_workflow_clean(wf: &Path, cache: &Path, out: &Path) -> serde_json::Value {
    run_ok(
        skytie()
            .arg("run")
            .arg(wf)
            .arg("--cache")
            .arg(cache)
            .arg("--out")
            .arg(out)
            .arg("--quiet"),
    );
    metrics(out)
}

fn write_workflow(dir: &Path, campaign: &str, gsd_m: f64) -> PathBuf {
    let wf = dir.join(format!("wf-{gsd_m}.toml"));
    std::fs::write(
        &wf,
        // The vehicle box as given: a detected box depends on the sampled panoramas, so a campaign that grows
        // by a recording may get a slightly different mask and re-run every ortho image (correctly: the mask
        // changed); this workflow checks the per-recording caching alone.
        format!("name = \"t\"\ncampaign = \"{campaign}\"\nseed = 1\nstages = [\"synth\", \"load\", \"ortho\", \"summary\"]\n[ortho]\ngsd_m = {gsd_m}\n[ortho.vehicle]\ndetect = false\n"),
    )
    .unwrap();
    wf
}

/// The results the tiny campaign (thesis profile: 0.80 m systematic + N(0, 0.10 m)) must reach, seed 1:
/// measured 14 MM–aerial correspondences (inlier ratio 0.93), 3 of 6 recordings registered to aerial images,
/// recordings 0.785 → 0.151 m RMSE 2D. The bars leave room for small changes, not for a broken chain.
fn registration_and_adjustment_hold(m: &serde_json::Value, recordings: u64) {
    let n = &m["nadir"];
    let num = |v: &serde_json::Value| {
        v.as_f64()
            .unwrap_or_else(|| panic!("missing number in {m}"))
    };
    assert!(
        num(&n["tie_points"]) >= 8.0,
        "too few MM–aerial correspondences: {n}"
    );
    assert!(num(&n["inlier_ratio"]) >= 0.85, "nadir inlier ratio: {n}");
    assert!(
        num(&n["recordings_with_aerial"]) >= 2.0,
        "recordings registered: {n}"
    );
    assert!(
        num(&n["control_points"]) >= 2.0,
        "aerial control points: {n}"
    );
    let a = &m["adjust"]["combined"];
    assert_eq!(
        a["recordings"]["after"]["count"].as_u64(),
        Some(recordings),
        "{m}"
    );
    let (cp0, cp1) = (
        num(&a["checkpoints"]["before"]["2d"]),
        num(&a["checkpoints"]["after"]["2d"]),
    );
    assert!(
        cp0 > 0.5,
        "the deterioration must show at the check points: {cp0}"
    );
    assert!(
        cp1 * 3.0 <= cp0,
        "check points {cp0:.3} → {cp1:.3} m: not 3× better"
    );
    let (r0, r1) = (
        num(&a["recordings"]["before"]["rmse_2d"]),
        num(&a["recordings"]["after"]["rmse_2d"]),
    );
    assert!(
        r1 * 3.0 <= r0,
        "recordings {r0:.3} → {r1:.3} m: not 3× better"
    );
    // Verification without adjustment: the recorded positions are 0.8 m off, so the segment fails.
    assert!(
        m["verify"]["segments_failed"].as_u64() >= Some(1),
        "verification missed the offset: {}",
        m["verify"]
    );
}

#[test]
fn tiny_campaign_end_to_end() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let cache = dir.join("cache");

    // 1. The CLI generator and the checker.
    let camp = dir.join("tiny");
    run_ok(
        skytie()
            .args(["synth", "--preset", "tiny", "--seed", "1", "--out"])
            .arg(&camp),
    );
    let report = run_ok(skytie().arg("check").arg("--json").arg(&camp));
    let report: serde_json::Value =
        serde_json::from_str(&report).expect("check --json prints JSON");
    assert_eq!(
        report["problems"].as_array().map(|p| p.len()),
        Some(0),
        "check is not clean: {report}"
    );

    // 2. The same campaign as a cached workflow node: identical bytes; a second run executes nothing.
    let wf = write_workflow(dir, "synth:tiny", 0.05);
    let out = dir.join("out1");
    let m = run_workflow(&wf, &cache, &out);
    let recordings = m["campaign"]["recordings"].as_u64().unwrap();
    assert!(recordings >= 4, "{m}");
    assert_eq!(stage(&m, "synth", "executed"), 1);
    assert_eq!(stage(&m, "ortho", "executed"), recordings);
    assert_eq!(m["campaign"]["input_errors"].as_u64(), Some(0));
    let generated: Vec<PathBuf> = std::fs::read_dir(cache.join("dirs"))
        .unwrap()
        .map(|e| e.unwrap().path().join("campaign"))
        .filter(|p| p.join("campaign.toml").is_file())
        .collect();
    // Two folders: the error-free rendering and the campaign with the error profile applied to it.
    assert_eq!(generated.len(), 2, "{generated:?}");
    let camp_files = files(&camp);
    assert!(
        generated.iter().any(|g| files(g) == camp_files),
        "the synth node's campaign differs from `skytie synth`'s"
    );
    let m = run_workflow(&wf, &cache, &out);
    assert_eq!(m["engine"]["nodes_executed"].as_u64(), Some(0), "{m}");

    // 3. A user campaign (other ortho params) that grows by one recording re-runs only that recording's ortho.
    let user = dir.join("user");
    std::fs::create_dir_all(&user).unwrap();
    for (rel, bytes) in files(&camp) {
        let p = user.join(&rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, bytes).unwrap();
    }
    let csv_path = user.join("mm/recordings.csv");
    let full = std::fs::read_to_string(&csv_path).unwrap();
    let lines: Vec<&str> = full.lines().collect();
    std::fs::write(&csv_path, lines[..lines.len() - 1].join("\n") + "\n").unwrap();
    let wf_user = write_workflow(dir, &user.display().to_string(), 0.04);
    let out2 = dir.join("out2");
    let m = run_workflow(&wf_user, &cache, &out2);
    assert_eq!(m["campaign"]["recordings"].as_u64(), Some(recordings - 1));
    assert_eq!(stage(&m, "ortho", "executed"), recordings - 1, "{m}");
    std::fs::write(&csv_path, full).unwrap();
    let m = run_workflow(&wf_user, &cache, &out2);
    assert_eq!(m["campaign"]["recordings"].as_u64(), Some(recordings));
    assert_eq!(
        stage(&m, "ortho", "executed"),
        1,
        "only the added recording's ortho runs: {m}"
    );
    assert_eq!(stage(&m, "ortho", "cached"), recordings - 1);
    assert_eq!(stage(&m, "summary", "executed"), 1);

    // 4. The shipped full chain (workflows/tiny.toml: nadir and oblique registration, adjustment, verification) on the same
    //    synthetic campaign: every stage ran without failures, the metrics sections and the exports exist, and
    //    a second run is served from the cache.
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("workflows/tiny.toml");
    let out3 = dir.join("out3");
    let m = run_workflow_clean(&shipped, &cache, &out3);
    assert_eq!(m["engine"]["nodes_failed"].as_u64(), Some(0), "{m}");
    for s in [
        "mm_match",
        "transform",
        "refine",
        "control",
        "adjust",
        "verify",
    ] {
        assert!(stage(&m, s, "executed") >= 1, "{s} did not run: {m}");
    }
    assert!(m["nadir"]["mm_tie_points"].as_u64().unwrap() > 0, "{m}");
    assert!(m["nadir"]["transforms_tried"].as_u64().unwrap() > 0, "{m}");
    registration_and_adjustment_hold(&m, recordings);
    assert_eq!(
        m["adjust"]["combined"]["recordings"]["after"]["count"].as_u64(),
        Some(recordings),
        "{m}"
    );
    assert!(m["adjust"]["combined"]["checkpoints"]["before"]["2d"].is_number());
    assert!(m["verify"]["passed"].is_boolean(), "{m}");
    // The oblique chain (thesis ch. 4): one sparse cloud and one façade node per triplet of the 6-recording
    // street, façade planes from its points, the consensus and its grading.
    let triplets = recordings - 2;
    assert_eq!(m["oblique"]["triplets"].as_u64(), Some(triplets), "{m}");
    assert_eq!(stage(&m, "sparse_cloud", "executed"), triplets);
    assert_eq!(stage(&m, "facades", "executed"), triplets);
    assert!(m["oblique"]["sparse_points"].as_u64().unwrap() > 0, "{m}");
    assert!(m["oblique"]["planes"].as_u64().unwrap() > 0, "{m}");
    assert!(stage(&m, "patches", "executed") >= 1, "{m}");
    assert!(
        m["oblique"]["inlier_ratio_after_consensus"].is_number(),
        "{m}"
    );
    // Each street side's oblique correspondences are reported, so a side without façade matches shows.
    for side in ["left", "right"] {
        assert!(
            m["oblique"]["sides"][side]["correspondences"].is_u64(),
            "{m}"
        );
    }
    // The generator wrote truth/scene.toml, so the grading compares with the seen surface and can tell
    // non-matchable correspondences (a count, not null).
    assert_eq!(
        m["oblique"]["truth_reference"], "scene surface point",
        "{m}"
    );
    assert!(m["oblique"]["non_matchable"].is_u64(), "{m}");
    // The tiny street has content to register: the adjustment corrects the trajectory and delivers it.
    assert_eq!(
        m["adjust"]["combined"]["verdict"].as_str(),
        Some("corrected"),
        "{m}"
    );
    assert!(out3.join("trajectory_adjusted.csv").is_file());
    for f in [
        "trajectory.geojson",
        "tie_points.ply",
        "checkpoints.csv",
        "verification.csv",
        "correspondences.csv",
        "colmap/cameras.txt",
        "colmap/images.txt",
        "colmap/points3D.txt",
    ] {
        let len = std::fs::metadata(out3.join(f))
            .map(|m| m.len())
            .unwrap_or(0);
        assert!(len > 0, "{f} missing or empty");
    }
    let adjusted = std::fs::read_to_string(out3.join("trajectory_adjusted.csv")).unwrap();
    assert_eq!(adjusted.lines().count() as u64, recordings + 1);
    let m = run_workflow(&shipped, &cache, &out3);
    assert_eq!(m["engine"]["nodes_executed"].as_u64(), Some(0), "{m}");
}

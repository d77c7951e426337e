//! Run-level bad input and faults on the real binary and the tiny synthetic campaign: a damaged copy (a JPEG
//! panorama truncated to 10 %, a 1:1 panorama that is a PNG named .jpg, a nadir frame whose header claims
//! 100000 × 100000 px) runs through adjustment, verification, the summary and the exports for the rest, counts
//! the dropped rows in metrics.json, exits with the partial-success code 3 and says so in its last line; a
//! corrupted cache object is detected, recomputed, and the outputs stay byte-identical.

#[path = "support/cli.rs"]
mod cli;

use cli::{finish, skytie, synth_tiny};
use std::path::Path;

fn png(path: &Path, w: u32, h: u32, claim: Option<(u32, u32)>) {
    let img = image::GrayImage::from_fn(w, h, |x, y| image::Luma([(x * 7 + y) as u8]));
    img.save_with_format(path, image::ImageFormat::Png).unwrap();
    if let Some((cw, ch)) = claim {
        let mut b = std::fs::read(path).unwrap();
        b[16..20].copy_from_slice(&cw.to_be_bytes());
        b[20..24].copy_from_slice(&ch.to_be_bytes());
        // Recompute the IHDR CRC so that only the size is absurd.
        let crc = crc32(&b[12..29]);
        b[29..33].copy_from_slice(&crc.to_be_bytes());
        std::fs::write(path, b).unwrap();
    }
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

fn run(wf: &Path, campaign: &Path, cache: &Path, out: &Path) -> (i32, String) {
    let (code, stdout, stderr) = finish(
        skytie()
            .arg("run")
            .arg(wf)
            .arg("--campaign")
            .arg(campaign)
            .arg("--cache")
            .arg(cache)
            .arg("--out")
            .arg(out)
            .arg("--quiet"),
    );
    // Warnings (stderr) first: the run's own last line is the last line of stdout.
    (code, stderr + &stdout)
}

/// Written by every run that reached the adjustment (`trajectory_adjusted.csv` only when it corrected
/// something: see [`assert_adjusted_trajectory_follows_the_verdict`]).
const EXPORTS: [&str; 4] = [
    "checkpoints.csv",
    "verification.csv",
    "correspondences.csv",
    "tie_points.ply",
];

/// A run of the intact tiny campaign: every item processed (the last line names no input error, failed or
/// skipped node). A flagged result (exit 3, e.g. "NOT CORRECTED") is about the result, not about lost items,
/// and is accepted here; `tests/pipeline_tiny.rs` requires the correction.
fn assert_complete_input(code: i32, text: &str) {
    let last = text.trim_end().lines().last().unwrap_or("");
    assert!(matches!(code, 0 | 3), "{text}");
    assert!(
        last.starts_with("run complete")
            || (!last.contains("input error")
                && !last.contains("failed")
                && !last.contains("skipped")),
        "{text}"
    );
}

#[test]
fn bad_items_are_dropped_counted_and_the_run_finishes_partially() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let wf = Path::new(env!("CARGO_MANIFEST_DIR")).join("workflows/tiny.toml");
    let tiny = dir.join("tiny");
    synth_tiny(&tiny, 1, &[]);
    let cache = dir.join("cache");
    let (code, text) = run(&wf, &tiny, &cache, &dir.join("clean"));
    assert_complete_input(code, &text);

    // The damaged copy.
    let bad = dir.join("bad");
    copy_dir(&tiny, &bad);
    let panos = bad.join("mm/panoramas");
    let jpeg = std::fs::read(panos.join("pano_0_003.jpg")).unwrap();
    std::fs::write(panos.join("pano_0_003.jpg"), &jpeg[..jpeg.len() / 10]).unwrap();
    png(&panos.join("pano_0_005.jpg"), 64, 64, None);
    png(
        &bad.join("aerial/nadir/nadir_0_s0_02.jpg"),
        4,
        4,
        Some((100_000, 100_000)),
    );
    let report =
        String::from_utf8(skytie().arg("check").arg(&bad).output().unwrap().stdout).unwrap();
    for needle in [
        "mm/recordings.csv:5: field 'file': mm/panoramas/pano_0_003.jpg is a truncated JPEG file",
        "mm/recordings.csv:7: field 'file': mm/panoramas/pano_0_005.jpg is 64×64 px, not 2:1",
        "mm/recordings.csv:7: warning: field 'file': mm/panoramas/pano_0_005.jpg is a PNG file",
        "aerial/nadir/cameras.csv:3: field 'file': aerial/nadir/nadir_0_s0_02.jpg is a PNG file whose header claims 100000×100000 px",
    ] {
        assert!(report.contains(needle), "check does not say '{needle}':\n{report}");
    }
    let out = dir.join("bad-out");
    let (code, text) = run(&wf, &bad, &cache, &out);
    assert_eq!(code, 3, "{text}");
    let last = text.trim_end().lines().last().unwrap().to_string();
    assert!(
        last.starts_with("run PARTIAL: 5 input error(s), 5 row(s) dropped"),
        "{last}"
    );
    assert!(last.ends_with("(exit 3)"), "{last}");
    let m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("metrics.json")).unwrap()).unwrap();
    let c = &m["campaign"];
    assert_eq!(c["recordings"], 4, "{c}");
    assert_eq!(c["dropped_rows"]["mm/recordings.csv"], 2, "{c}");
    assert_eq!(c["dropped_rows"]["aerial/nadir/cameras.csv"], 1, "{c}");
    // Both observations in the truncated panorama (check points cp_0_01 and cp_0_02).
    assert_eq!(c["dropped_rows"]["control/observations.csv"], 2, "{c}");
    assert_eq!(c["input_errors_by_kind"]["image_size"], 2, "{c}");
    assert_eq!(c["input_errors_by_kind"]["image_damaged"], 1, "{c}");
    assert_eq!(m["engine"]["nodes_failed"], 0, "{m}");
    assert!(
        m["adjust"].is_object() && m["verify"]["segments"].as_u64() > Some(0),
        "{m}"
    );
    for f in EXPORTS {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    assert_adjusted_trajectory_follows_the_verdict(&out, &m);
}

/// The adjusted trajectory is delivered exactly when the adjustment's verdict is "corrected".
fn assert_adjusted_trajectory_follows_the_verdict(out: &Path, m: &serde_json::Value) {
    let corrected = m["adjust"]
        .to_string()
        .contains("\"verdict\":\"corrected\"");
    assert_eq!(
        out.join("trajectory_adjusted.csv").is_file(),
        corrected,
        "trajectory_adjusted.csv must exist exactly when the verdict is 'corrected': {}",
        m["adjust"]
    );
}

#[test]
fn a_corrupted_cache_object_is_detected_and_recomputed() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let wf = dir.join("wf.toml");
    std::fs::write(
        &wf,
        "name = \"t\"\ncampaign = \"synth:tiny\"\nseed = 1\nstages = [\"synth\", \"load\", \"ortho\", \"summary\", \"mm_match\"]\n",
    )
    .unwrap();
    let cache = dir.join("cache");
    let tiny = dir.join("tiny");
    synth_tiny(&tiny, 1, &[]);
    let (code, text) = run(&wf, &tiny, &cache, &dir.join("a"));
    assert_eq!(code, 0, "{text}");
    // Flip one byte in the middle of every stored object.
    let mut damaged = 0;
    let objects = cache.join("objects");
    for shard in std::fs::read_dir(&objects).unwrap() {
        for e in std::fs::read_dir(shard.unwrap().path()).unwrap() {
            let p = e.unwrap().path();
            let mut b = std::fs::read(&p).unwrap();
            let n = b.len();
            b[n / 2] ^= 0x5A;
            std::fs::write(&p, b).unwrap();
            damaged += 1;
        }
    }
    assert!(damaged > 0);
    let (code, text) = run(&wf, &tiny, &cache, &dir.join("b"));
    assert_complete_input(code, &text);
    assert!(
        text.contains("recomputing"),
        "no corruption warning:\n{text}"
    );
    let metrics = |d: &str| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(dir.join(d).join("metrics.json")).unwrap()).unwrap()
    };
    let (a, b) = (metrics("a"), metrics("b"));
    assert_eq!(a["campaign"], b["campaign"]);
    assert_eq!(a["ortho"], b["ortho"]);
    assert!(b["engine"]["nodes_executed"].as_u64() > Some(0), "{b}");
}

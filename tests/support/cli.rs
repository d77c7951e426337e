//! Shared helpers of the tests that drive the real `skytie` binary: the command, a run that must succeed, a
//! workflow run.
#![allow(dead_code)]

use std::path::Path;
use std::process::Command;

/// The `skytie` binary built for these tests.
pub fn skytie() -> Command {
    Command::new(env!("CARGO_BIN_EXE_skytie"))
}

/// Runs `cmd`, which must succeed; returns stdout + stderr.
pub fn run_ok(cmd: &mut Command) -> String {
    let out = cmd.output().expect("start skytie");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{cmd:?} failed: {text}");
    text
}

/// Runs `cmd`, which must finish with exit 0 or 3 (a flagged result, see `skytie run --help`); returns stdout +
/// stderr.
pub fn run_finished(cmd: &mut Command) -> String {
    let out = cmd.output().expect("start skytie");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        matches!(out.status.code(), Some(0 | 3)),
        "{cmd:?} failed: {text}"
    );
    text
}

/// `skytie run WORKFLOW --cache CACHE --out OUT --quiet`, which must finish: exit 0, or 3 when the result is
/// flagged (e.g. a tiny campaign with too little to register: "NOT CORRECTED"); returns stdout + stderr.
pub fn run_workflow(wf: &Path, cache: &Path, out: &Path) -> String {
    run_finished(
        skytie()
            .arg("run")
            .arg(wf)
            .arg("--cache")
            .arg(cache)
            .arg("--out")
            .arg(out)
            .arg("--quiet"),
    )
}

/// Every output file under `root` except the HTML report and the per-shard summaries, by relative path.
pub fn output_files(root: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut std::collections::BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().display().to_string();
            if rel == "report" || rel == "shards" {
                continue;
            }
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = std::collections::BTreeMap::new();
    walk(root, root, &mut out);
    out
}

/// A JSON file, parsed.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

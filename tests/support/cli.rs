//! Shared helpers of the tests that drive the real `skytie` binary: the command, a run that must succeed, a
//! workflow run.
#![allow(dead_code)]

use std::path::Path;
use std::process::Command;

/// The `skytie` binary built for these tests.
pub fn skytie() -> Command {
    Command::new(env!("CARGO_BIN_EXE_skytie"))
}

/// `skytie synth --preset tiny --seed SEED OPTIONS… --out OUT`, which must succeed.
pub fn synth_tiny(out: &Path, seed: u64, options: &[&str]) {
    run_ok(
        skytie()
            .args(["synth", "--preset", "tiny", "--seed", &seed.to_string()])
            .args(options)
            .arg("--out")
            .arg(out),
    );
}

/// Runs `cmd` to its end: its exit code (-1 when a signal ended it), stdout and stderr.
pub fn finish(cmd: &mut Command) -> (i32, String, String) {
    let out = cmd.output().expect("start skytie");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs `cmd` to its end: its exit code and stdout + stderr.
pub fn exit_and_output(cmd: &mut Command) -> (i32, String) {
    let (code, stdout, stderr) = finish(cmd);
    (code, stdout + &stderr)
}

/// Runs `cmd`, which must succeed; returns stdout + stderr.
pub fn run_ok(cmd: &mut Command) -> String {
    let (code, text) = exit_and_output(cmd);
    assert_eq!(code, 0, "{cmd:?} failed: {text}");
    text
}

/// Runs `cmd`, which must finish with exit 0 or 3 (a flagged result, see `skytie run --help`); returns stdout +
/// stderr.
pub fn run_finished(cmd: &mut Command) -> String {
    let (code, text) = exit_and_output(cmd);
    assert!(matches!(code, 0 | 3), "{cmd:?} failed: {text}");
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

/// Every file under `root` with its bytes, by relative path, leaving out the top-level entries named in `skip`.
pub fn files_under(root: &Path, skip: &[&str]) -> std::collections::BTreeMap<String, Vec<u8>> {
    fn walk(
        root: &Path,
        dir: &Path,
        skip: &[&str],
        out: &mut std::collections::BTreeMap<String, Vec<u8>>,
    ) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().display().to_string();
            if skip.contains(&rel.as_str()) {
                continue;
            }
            if p.is_dir() {
                walk(root, &p, skip, out);
            } else {
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = std::collections::BTreeMap::new();
    walk(root, root, skip, &mut out);
    out
}

/// Every output file under `root` except the HTML report and the per-shard summaries, by relative path.
pub fn output_files(root: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    files_under(root, &["report", "shards"])
}

/// A JSON file, parsed.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// A run's metrics.json without the engine's bookkeeping (node counts, seconds).
pub fn results_of(metrics: &serde_json::Value) -> serde_json::Value {
    let mut m = metrics.clone();
    let obj = m.as_object_mut().unwrap();
    obj.remove("engine");
    obj.remove("stages");
    m
}

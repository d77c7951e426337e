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

//! The shard contract on the real binary and the tiny synthetic campaign (the full default chain): running
//! `--prepare`, the shards `K/N` one after another and `--merge N` on one cache gives byte-identical outputs to a
//! single run on another cache (every output file; `metrics.json` apart from its engine bookkeeping), every node
//! is computed once (shards + merge executed exactly what the single run executed, the merge only the
//! campaign-wide nodes), a merge with a shard missing refuses and names it, and re-running everything executes
//! nothing.

#[path = "support/cli.rs"]
mod cli;

use cli::{exit_and_output, json, output_files, results_of, skytie};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// Executed nodes per stage.
fn executed(metrics: &Value) -> BTreeMap<String, u64> {
    metrics["stages"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| (k.clone(), v["executed"].as_u64().unwrap()))
        .filter(|(_, n)| *n > 0)
        .collect()
}

/// `skytie run tiny --cache CACHE --out OUT --quiet EXTRA…`: (exit code, stdout + stderr).
fn run(cache: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    exit_and_output(
        skytie()
            .args(["run", "tiny", "--quiet", "--cache"])
            .arg(cache)
            .arg("--out")
            .arg(out)
            .args(extra),
    )
}

fn add(total: &mut BTreeMap<String, u64>, part: &BTreeMap<String, u64>) {
    for (k, v) in part {
        *total.entry(k.clone()).or_default() += v;
    }
}

#[test]
fn shards_and_merge_equal_a_single_run() {
    let tmp = tempfile::tempdir().unwrap();
    let (single_cache, single_out) = (tmp.path().join("c1"), tmp.path().join("o1"));
    let (cache, out) = (tmp.path().join("c2"), tmp.path().join("o2"));
    let (single_code, text) = run(&single_cache, &single_out, &[]);
    assert!(matches!(single_code, 0 | 3), "single run: {text}");
    let single = json(&single_out.join("metrics.json"));

    let (code, text) = run(&cache, &out, &["--prepare"]);
    assert_eq!(code, 0, "prepare: {text}");
    let mut total = executed(&json(&out.join("shards/prepare.json")));
    // Shards 1 and 3 only: the merge must refuse and name shard 2.
    for k in ["1/3", "3/3"] {
        let (code, text) = run(&cache, &out, &["--shard", k]);
        assert_eq!(code, 0, "shard {k}: {text}");
    }
    let (code, text) = run(&cache, &out, &["--merge", "3"]);
    assert_eq!(code, 1, "a merge with a missing shard must fail: {text}");
    assert!(
        text.contains("shard 2/3") && !text.contains("shard 1/3:") && !text.contains("shard 3/3:"),
        "the error names the incomplete shard only: {text}"
    );
    assert!(
        !out.join("metrics.json").exists(),
        "no outputs before the merge"
    );
    let (code, text) = run(&cache, &out, &["--shard", "2/3"]);
    assert_eq!(code, 0, "shard 2/3: {text}");
    for k in 1..=3 {
        add(
            &mut total,
            &executed(&json(&out.join(format!("shards/shard-{k}-of-3.json")))),
        );
    }
    let (code, text) = run(&cache, &out, &["--merge", "3"]);
    assert_eq!(code, single_code, "merge: {text}");
    let merged = json(&out.join("metrics.json"));

    // The merge runs only campaign-wide stages.
    for stage in skytie::pipelines::shards::PER_ITEM_STAGES {
        assert!(
            !executed(&merged).contains_key(stage),
            "the merge executed {stage} nodes: {:?}",
            executed(&merged)
        );
    }
    add(&mut total, &executed(&merged));
    assert_eq!(
        total,
        executed(&single),
        "prepare + shards + merge execute each node once"
    );
    assert_eq!(results_of(&merged), results_of(&single));
    let (a, b) = (output_files(&single_out), output_files(&out));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "the same output files"
    );
    for (name, bytes) in &a {
        if name == "metrics.json" || name == "provenance.json" {
            continue;
        }
        assert!(&b[name] == bytes, "{name} differs from the single run's");
    }

    // Re-submitting the finished campaign executes nothing.
    for k in ["1/3", "2/3", "3/3"] {
        let (code, text) = run(&cache, &out, &["--shard", k]);
        assert_eq!(code, 0, "shard {k} again: {text}");
        let again = json(&out.join(format!("shards/shard-{}-of-3.json", &k[..1])));
        assert_eq!(again["engine"]["nodes_executed"], 0, "shard {k} again");
    }
    let (code, text) = run(&cache, &out, &["--merge", "3"]);
    assert_eq!(code, single_code, "merge again: {text}");
    let again = json(&out.join("metrics.json"));
    assert_eq!(again["engine"]["nodes_executed"], 0, "merge again");
    assert_eq!(results_of(&again), results_of(&single));
}

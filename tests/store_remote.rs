//! The cache with a remote object store behind it (`object_store`'s in-memory and local-folder backends):
//! a second host with an empty cache folder executes nothing and gives the same outputs, generated folders
//! travel with their entries, a damaged remote object is detected, deleted and recomputed, concurrent writers
//! of one key are harmless, remote gc removes exactly the unreachable results, and the real tiny pipeline
//! sharded on one host merges on another.
//!
//! "Hosts" are cache folders: hosts of a cluster use the same local cache path (artifacts of generated folders
//! record absolute paths, see docs/cache.md), so host B is host A's path emptied.

#[path = "support/cli.rs"]
mod cli;
mod support;

use cli::{exit_and_output, json, output_files, results_of, skytie};
use serde_json::Value;
use skytie::dag::progress::{Progress, ProgressMode};
use skytie::dag::{execute, DagBuilder, Env, Mode, Outcome};
use skytie::hashing::{KeyBuilder, NodeKey, StatCache};
use skytie::store::{EntryMeta, Lookup, Store};
use skytie::testing::toy::{ToyGen, ToyGenParams, ToyScaleParams};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::Duration;
use support::{add_toy, make_items, ToyConfig};

fn exec(store: &Store, dag: &skytie::dag::Dag) -> Outcome {
    let stat = StatCache::open(store.root());
    let progress = Progress::new(ProgressMode::Silent);
    let env = Env {
        store,
        stat_cache: &stat,
        progress: &progress,
    };
    execute(dag, &env, Mode::Run)
}

/// The toy DAG (parse → scale per item → sum) plus one generated folder (`toy_gen`).
fn toy_with_folder(
    items: &[PathBuf],
    factor: f64,
    seed: u64,
) -> (
    skytie::dag::Dag,
    skytie::dag::Handle<skytie::testing::toy::ToySummary>,
) {
    let mut b = DagBuilder::new();
    let cfg = ToyConfig {
        scale: ToyScaleParams {
            factor,
            ..ToyScaleParams::default()
        },
        ..ToyConfig::default()
    };
    let h = add_toy(&mut b, items, &cfg);
    let g = b
        .add(
            ToyGen,
            "gen",
            ToyGenParams {
                count: 3,
                seed,
                ..ToyGenParams::default()
            },
            (),
        )
        .unwrap();
    b.request(g);
    (b.build(), h)
}

/// Keys of every node an outcome processed.
fn keys(o: &Outcome) -> BTreeSet<NodeKey> {
    o.reports.iter().filter_map(|r| r.key).collect()
}

/// The key of the (only) node of `stage`.
fn keys_of_stage(o: &Outcome, stage: &str) -> NodeKey {
    o.reports
        .iter()
        .find(|r| r.stage == stage)
        .and_then(|r| r.key)
        .unwrap()
}

/// Entry files below a `file://` remote's folder, by key.
fn remote_entries(root: &Path) -> BTreeMap<NodeKey, PathBuf> {
    let mut out = BTreeMap::new();
    let Ok(shards) = std::fs::read_dir(root.join("objects")) else {
        return out;
    };
    for shard in shards {
        let shard = shard.unwrap().path();
        for f in std::fs::read_dir(&shard).unwrap() {
            let p = f.unwrap().path();
            let hex = format!(
                "{}{}",
                shard.file_name().unwrap().to_string_lossy(),
                p.file_name().unwrap().to_string_lossy()
            );
            if let Ok(k) = NodeKey::from_hex(&hex) {
                out.insert(k, p);
            }
        }
    }
    out
}

/// A new host: the cache folder `cache` moved aside (to `cache.N`), so the same path starts empty.
fn new_host(cache: &Path) -> &Path {
    if cache.exists() {
        let mut n = 1;
        while cache.with_extension(n.to_string()).exists() {
            n += 1;
        }
        std::fs::rename(cache, cache.with_extension(n.to_string())).unwrap();
    }
    cache
}

/// Every file below `dir`.
fn remote_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(remote_files(&p));
        } else {
            out.push(p);
        }
    }
    out
}

fn file_url(p: &Path) -> String {
    format!("file://{}", p.display())
}

/// A temporary folder holding a local-folder remote, the toy items of `values` and a cache path (not created).
struct FileRemote {
    tmp: tempfile::TempDir,
    remote: PathBuf,
    url: String,
    items: Vec<PathBuf>,
    cache: PathBuf,
}

fn file_remote(values: &[f64]) -> FileRemote {
    let tmp = tempfile::tempdir().unwrap();
    let remote = tmp.path().join("remote");
    let url = file_url(&remote);
    let items = make_items(tmp.path(), values);
    let cache = tmp.path().join("cache");
    FileRemote {
        tmp,
        remote,
        url,
        items,
        cache,
    }
}

#[test]
fn memory_remote_second_host_executes_nothing_and_gets_the_same_values() {
    let tmp = tempfile::tempdir().unwrap();
    let items = make_items(tmp.path(), &[1.0, 2.0, 3.0, 4.0]);
    let (dag, h) = toy_with_folder(&items, 2.0, 1);
    let url = "memory://second-host";
    let cache = tmp.path().join("cache");
    let a = exec(&Store::open_with_remote(&cache, Some(url)).unwrap(), &dag);
    assert_eq!(a.failed(), 0, "{:?}", a.warnings);
    assert_eq!(a.executed(), dag.len());
    // Host B: an empty cache folder.
    let b_root = new_host(&cache);
    let b = exec(&Store::open_with_remote(b_root, Some(url)).unwrap(), &dag);
    assert_eq!(b.executed(), 0, "host B executed nodes: {:?}", b.warnings);
    assert_eq!(b.cached(), dag.len());
    assert!(b.warnings.is_empty(), "{:?}", b.warnings);
    assert_eq!(a.get(h).unwrap().sum, b.get(h).unwrap().sum);
    assert_eq!(keys(&a), keys(&b));
    // Host B now holds verified local copies: a run without the remote is all cached too.
    assert!(b_root
        .join("dirs")
        .join(keys_of_stage(&b, "toy_gen").to_string())
        .join("items/item_002.txt")
        .is_file());
    let local = exec(&Store::open(b_root).unwrap(), &dag);
    assert_eq!(local.executed(), 0);
}

#[test]
fn a_corrupt_remote_entry_is_reported_deleted_and_recomputed() {
    let r = file_remote(&[1.0, 2.0, 3.0]);
    let (dag, h) = toy_with_folder(&r.items, 2.0, 1);
    let a = exec(
        &Store::open_with_remote(&r.cache, Some(&r.url)).unwrap(),
        &dag,
    );
    assert_eq!(a.failed(), 0);
    // Damage one payload byte of the sum's remote entry.
    let sum_key = keys_of_stage(&a, "toy_sum");
    let path = remote_entries(&r.remote)[&sum_key].clone();
    let mut bytes = std::fs::read(&path).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 0x20;
    std::fs::write(&path, &bytes).unwrap();

    let b = exec(
        &Store::open_with_remote(new_host(&r.cache), Some(&r.url)).unwrap(),
        &dag,
    );
    assert_eq!(b.executed(), 1, "only the damaged node is recomputed");
    assert_eq!(b.executed_of("toy_sum"), 1);
    assert!(
        b.warnings.iter().any(|w| w.contains("on the remote")
            && w.contains("corrupt")
            && w.contains("payload hash mismatch")),
        "{:?}",
        b.warnings
    );
    assert_eq!(a.get(h).unwrap().sum, b.get(h).unwrap().sum);
    // The recomputed entry replaced the damaged one: a third host finds everything intact.
    assert_eq!(std::fs::read(&path).unwrap().len(), bytes.len());
    let c = exec(
        &Store::open_with_remote(new_host(&r.cache), Some(&r.url)).unwrap(),
        &dag,
    );
    assert_eq!(c.executed(), 0, "{:?}", c.warnings);
    assert!(c.warnings.is_empty(), "{:?}", c.warnings);
}

#[test]
fn a_damaged_generated_folder_on_the_remote_is_detected_and_recomputed() {
    let r = file_remote(&[1.0]);
    let (dag, _) = toy_with_folder(&r.items, 1.0, 7);
    let a = exec(
        &Store::open_with_remote(&r.cache, Some(&r.url)).unwrap(),
        &dag,
    );
    let gen_key = keys_of_stage(&a, "toy_gen");
    let file = r
        .remote
        .join("dirs")
        .join(gen_key.to_string())
        .join("items/item_001.txt");
    assert!(file.is_file(), "the folder's files are on the remote");
    std::fs::write(&file, b"999\n").unwrap();
    let b_root = new_host(&r.cache);
    let b = exec(
        &Store::open_with_remote(b_root, Some(&r.url)).unwrap(),
        &dag,
    );
    assert_eq!(b.executed_of("toy_gen"), 1, "{:?}", b.warnings);
    assert!(
        b.warnings
            .iter()
            .any(|w| w.contains("generated folder") && w.contains("item_001.txt")),
        "{:?}",
        b.warnings
    );
    // The recomputed folder is the original one, and it is on the remote again.
    let local = b_root
        .join("dirs")
        .join(gen_key.to_string())
        .join("items/item_001.txt");
    assert_ne!(std::fs::read(&local).unwrap(), b"999\n");
    assert_eq!(
        std::fs::read(&file).unwrap(),
        std::fs::read(&local).unwrap()
    );
}

#[test]
fn verify_checks_the_remote_and_deletes_damaged_objects() {
    let r = file_remote(&[1.0, 2.0]);
    let (dag, _) = toy_with_folder(&r.items, 1.0, 1);
    let store = Store::open_with_remote(&r.tmp.path().join("a"), Some(&r.url)).unwrap();
    exec(&store, &dag);
    let clean = store.verify_remote().unwrap().unwrap();
    assert_eq!(clean.entries_checked, dag.len() as u64);
    assert_eq!(clean.folders_checked, 1);
    assert!(clean.bad.is_empty(), "{:?}", clean.bad);
    let entries = remote_entries(&r.remote);
    let (key, path) = entries.iter().next().unwrap();
    let mut bytes = std::fs::read(path).unwrap();
    bytes[10] ^= 1; // inside the header's key
    std::fs::write(path, &bytes).unwrap();
    let report = store.verify_remote().unwrap().unwrap();
    assert_eq!(report.bad.len(), 1, "{:?}", report.bad);
    assert_eq!(report.bad[0].key, *key);
    assert!(report.bad[0].removed);
    assert!(
        !path.exists(),
        "the damaged object is deleted from the remote"
    );
    // Without a remote there is nothing to check remotely.
    assert!(Store::open(&r.tmp.path().join("a"))
        .unwrap()
        .verify_remote()
        .is_none());
}

#[test]
fn concurrent_writers_of_one_key_are_harmless() {
    let tmp = tempfile::tempdir().unwrap();
    for url in [
        file_url(&tmp.path().join("remote")),
        "memory://writers".to_string(),
    ] {
        let key = KeyBuilder::new("writers", 1)
            .params(url.as_bytes())
            .finish();
        let payload: Vec<u8> = (0..300_000u32).map(|i| (i * 7 % 251) as u8).collect();
        let meta = EntryMeta::new("writers", "1", "item");
        std::thread::scope(|s| {
            for w in 0..6 {
                let (url, payload, meta, root) = (
                    &url,
                    &payload,
                    &meta,
                    tmp.path().join(format!("w{w}-{}", url.len())),
                );
                s.spawn(move || {
                    let store = Store::open_with_remote(&root, Some(url)).unwrap();
                    for _ in 0..3 {
                        store.save(&key, meta, payload).unwrap();
                    }
                });
            }
        });
        let reader = Store::open_with_remote(
            &tmp.path().join(format!("reader-{}", url.len())),
            Some(&url),
        )
        .unwrap();
        match reader.load(&key).unwrap() {
            Lookup::Hit(e) => assert!(e.payload == payload && e.meta == meta),
            other => panic!("{url}: expected the entry, got {other:?}"),
        }
    }
}

#[test]
fn remote_gc_removes_exactly_the_unreachable_results() {
    let r = file_remote(&[1.0, 2.0, 3.0]);
    let store = Store::open_with_remote(&r.cache, Some(&r.url)).unwrap();
    let (dag1, _) = toy_with_folder(&r.items, 2.0, 1);
    let first = exec(&store, &dag1);
    // New parameters: the scale and sum nodes and the generated folder get new keys; parse nodes stay.
    let (dag2, _) = toy_with_folder(&r.items, 3.0, 2);
    let second = exec(&store, &dag2);
    assert_eq!(second.executed_of("toy_parse"), 0);
    let superseded: Vec<NodeKey> = keys(&first).difference(&keys(&second)).copied().collect();
    assert_eq!(
        superseded.len(),
        3 + 1 + 1,
        "3 scale nodes, the sum and the folder node"
    );
    let old_gen = keys_of_stage(&first, "toy_gen");
    assert!(r
        .remote
        .join("dirs")
        .join(format!("{old_gen}.manifest"))
        .is_file());

    let root_key = |payload: &[u8]| {
        let v: Value = serde_json::from_slice(payload).ok()?;
        NodeKey::from_hex(v["key"].as_str()?).ok()
    };
    // Everything is younger than an hour: nothing goes.
    let young = store
        .gc_remote("nodes", &root_key, "outputs", Duration::from_secs(3600))
        .unwrap()
        .unwrap();
    assert!(young.removed_keys.is_empty());
    assert_eq!(young.young_entries, superseded.len() as u64);
    let report = store
        .gc_remote("nodes", &root_key, "outputs", Duration::ZERO)
        .unwrap()
        .unwrap();
    let mut expected = superseded.clone();
    expected.sort();
    assert_eq!(
        report.removed_keys, expected,
        "exactly the superseded results"
    );
    assert_eq!(report.removed_folders, 1);
    assert_eq!(report.removed_records, superseded.len() as u64);
    assert_eq!(
        remote_entries(&r.remote)
            .keys()
            .copied()
            .collect::<BTreeSet<_>>(),
        keys(&second),
        "every result of the last run stays"
    );
    assert!(!r
        .remote
        .join("dirs")
        .join(format!("{old_gen}.manifest"))
        .exists());
    // (the folder backend may leave empty directories behind; no file of the folder stays)
    let old_dir = r.remote.join("dirs").join(old_gen.to_string());
    assert!(!old_dir.exists() || remote_files(&old_dir).is_empty());
    // A fresh host still gets everything of the last run from the remote.
    drop(store);
    let b = exec(
        &Store::open_with_remote(new_host(&r.cache), Some(&r.url)).unwrap(),
        &dag2,
    );
    assert_eq!(b.executed(), 0, "{:?}", b.warnings);
}

#[test]
fn remote_urls_are_checked_when_the_store_opens() {
    let tmp = tempfile::tempdir().unwrap();
    for (url, says) in [
        ("s3://", "no bucket"),
        ("gs://bucket/x", "unknown scheme `gs://`"),
        ("file://relative/path", "absolute path"),
        ("cache-folder", "--cache DIR"),
    ] {
        let Err(e) = Store::open_with_remote(tmp.path(), Some(url)) else {
            panic!("{url} was accepted");
        };
        let e = e.to_string();
        assert!(
            e.contains(says) && e.contains(url.trim_end_matches('/')),
            "{url}: {e}"
        );
    }
}

/// `skytie run WORKFLOW --cache CACHE --cache-remote URL --out OUT --quiet EXTRA…`: (exit code, output).
fn cli_run(
    workflow: &str,
    cache: &Path,
    remote: &str,
    out: &Path,
    extra: &[&str],
) -> (i32, String) {
    exit_and_output(
        skytie()
            .args(["run", workflow, "--quiet", "--cache"])
            .arg(cache)
            .arg("--cache-remote")
            .arg(remote)
            .arg("--out")
            .arg(out)
            .args(extra),
    )
}

/// Outputs equal apart from run bookkeeping (metrics' engine and stage counters, provenance).
fn assert_same_outputs(a: &Path, b: &Path) {
    let (fa, fb) = (output_files(a), output_files(b));
    assert_eq!(fa.keys().collect::<Vec<_>>(), fb.keys().collect::<Vec<_>>());
    for (name, bytes) in &fa {
        if name == "metrics.json" || name == "provenance.json" {
            continue;
        }
        assert!(&fb[name] == bytes, "{name} differs between the hosts");
    }
    assert_eq!(
        results_of(&json(&a.join("metrics.json"))),
        results_of(&json(&b.join("metrics.json")))
    );
}

#[test]
fn cli_file_remote_second_host_with_a_generated_campaign_executes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let wf = tmp.path().join("remote.toml");
    std::fs::write(
        &wf,
        "name = \"remote\"\npipeline = \"toy\"\ncampaign = \"synth:tiny\"\n\
         stages = [\"toy_gen\", \"toy_parse\", \"toy_scale\", \"toy_sum\"]\n[toy_gen]\ncount = 5\n",
    )
    .unwrap();
    let wf = wf.to_str().unwrap();
    let (cache, remote) = (tmp.path().join("cache"), tmp.path().join("remote"));
    let url = file_url(&remote);
    let (code, text) = cli_run(wf, &cache, &url, &tmp.path().join("oa"), &[]);
    assert_eq!(code, 0, "host A: {text}");
    let a = json(&tmp.path().join("oa/metrics.json"));
    assert!(a["engine"]["nodes_executed"].as_u64().unwrap() >= 12, "{a}");
    // Host B: the same cache path, emptied.
    std::fs::rename(&cache, tmp.path().join("cache-host-a")).unwrap();
    let (code, text) = cli_run(wf, &cache, &url, &tmp.path().join("ob"), &[]);
    assert_eq!(code, 0, "host B: {text}");
    let b = json(&tmp.path().join("ob/metrics.json"));
    assert_eq!(
        b["engine"]["nodes_executed"], 0,
        "host B executed nodes: {text}"
    );
    assert_same_outputs(&tmp.path().join("oa"), &tmp.path().join("ob"));
    // The environment variable works as the flag does, and `cache verify` checks the remote.
    let o = skytie()
        .args(["cache", "verify", "--cache"])
        .arg(&cache)
        .env("SKYTIE_CACHE_REMOTE", &url)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && text.contains("remote file://") && text.contains("0 bad"),
        "{text}"
    );
}

#[test]
fn tiny_pipeline_sharded_on_one_host_merges_on_another() {
    let tmp = tempfile::tempdir().unwrap();
    let (cache, remote) = (tmp.path().join("cache"), tmp.path().join("remote"));
    let url = file_url(&remote);
    let out_a = tmp.path().join("oa");
    let (code, text) = cli_run("tiny", &cache, &url, &out_a, &["--prepare"]);
    assert_eq!(code, 0, "prepare: {text}");
    for k in ["1/2", "2/2"] {
        let (code, text) = cli_run("tiny", &cache, &url, &out_a, &["--shard", k]);
        assert_eq!(code, 0, "shard {k}: {text}");
    }
    // Host B merges from the remote alone.
    std::fs::rename(&cache, tmp.path().join("cache-host-a")).unwrap();
    let out_b = tmp.path().join("ob");
    let (code_b, text) = cli_run("tiny", &cache, &url, &out_b, &["--merge", "2"]);
    assert!(matches!(code_b, 0 | 3), "merge on host B: {text}");
    let merged = json(&out_b.join("metrics.json"));
    for stage in skytie::pipelines::shards::PER_ITEM_STAGES {
        assert_eq!(
            merged["stages"][stage]["executed"].as_u64().unwrap_or(0),
            0,
            "the merge on host B recomputed {stage} nodes"
        );
    }
    // Host C: a fresh cache again; the finished campaign executes nothing and gives the same bytes.
    std::fs::rename(&cache, tmp.path().join("cache-host-b")).unwrap();
    let out_c = tmp.path().join("oc");
    let (code_c, text) = cli_run("tiny", &cache, &url, &out_c, &["--merge", "2"]);
    assert_eq!(code_c, code_b, "merge on host C: {text}");
    assert_eq!(
        json(&out_c.join("metrics.json"))["engine"]["nodes_executed"],
        0,
        "{text}"
    );
    assert_same_outputs(&out_b, &out_c);
}

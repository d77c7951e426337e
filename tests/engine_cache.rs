//! Engine caching behaviour with toy stages: no-op reruns, param changes, early cutoff, version bumps, new
//! items, sweeps sharing a prefix, corrupt artifacts, failures and panics, thread-count independence.

mod support;

use skytie::dag::{DagBuilder, Mode, NodeStatus, Outcome};
use skytie::testing::toy::{Faults, ToyScaleParams, ToySumParams, ToySummary};
use std::path::{Path, PathBuf};
use support::*;

const VALUES: [f64; 4] = [1.0, 2.0, 3.0, 4.0];

/// The toy summary of `count` numbers adding up to `sum`.
fn summary(sum: f64, count: u64) -> ToySummary {
    ToySummary { sum, count }
}

/// The default toy workflow but toy_scale's `factor` and `quantum`.
fn scaling(factor: f64, quantum: f64) -> ToyConfig {
    ToyConfig {
        scale: ToyScaleParams {
            factor,
            quantum,
            ..ToyScaleParams::default()
        },
        ..Default::default()
    }
}

/// Runs the toy workflow and checks the nodes executed per stage (parse, scale, sum) and the sum; the outcome
/// for further checks.
fn run_checked(
    cache: &Path,
    items: &[PathBuf],
    cfg: &ToyConfig,
    executed_per_stage: (usize, usize, usize),
    sum: f64,
) -> Outcome {
    let (o, h) = run_toy(cache, items, cfg);
    assert_eq!(executed(&o), executed_per_stage);
    assert_eq!(o.get(h).unwrap().sum, sum);
    o
}

#[test]
fn first_run_executes_all_and_second_identical_run_executes_nothing() {
    let (_d, cache, items) = toy_workspace(&VALUES);
    let cfg = ToyConfig::default();
    let (o1, h) = run_toy(&cache, &items, &cfg);
    assert_eq!(executed(&o1), (4, 4, 1));
    assert_eq!(o1.cached(), 0);
    assert_eq!(*o1.get(h).unwrap(), summary(20.0, 4));
    let (o2, h) = run_toy(&cache, &items, &cfg);
    assert_eq!(o2.executed(), 0);
    assert_eq!(o2.cached(), 9);
    assert!(o2.warnings.is_empty(), "{:?}", o2.warnings);
    // The requested output is loaded from the cache.
    assert_eq!(*o2.get(h).unwrap(), summary(20.0, 4));
}

#[test]
fn changing_one_param_reruns_that_stage_and_its_dependents_only() {
    let (_d, cache, items) = toy_workspace(&VALUES);
    let mut cfg = ToyConfig::default();
    run_toy(&cache, &items, &cfg);
    cfg.scale.factor = 3.0;
    let o = run_checked(&cache, &items, &cfg, (0, 4, 1), 30.0);
    assert_eq!(o.cached(), 4);
    // Only the sum's param: only the sum.
    cfg.sum.offset = 1.5;
    run_checked(&cache, &items, &cfg, (0, 0, 1), 31.5);
}

#[test]
fn early_cutoff_keeps_dependents_cached_when_output_is_identical() {
    let (_d, cache, items) = toy_workspace(&VALUES);
    let mut cfg = scaling(2.0, 1.0);
    run_toy(&cache, &items, &cfg);
    // 2.001 * v rounds to the same integers: toy_scale re-runs, its outputs are identical, toy_sum is cached.
    cfg.scale.factor = 2.001;
    let o = run_checked(&cache, &items, &cfg, (0, 4, 0), 20.0);
    assert_eq!(o.cached(), 5);
}

#[test]
fn stage_version_bump_reruns_that_stage() {
    let (_d, cache, items) = toy_workspace(&VALUES);
    let mut cfg = ToyConfig::default();
    run_toy(&cache, &items, &cfg);
    cfg.scale_v2 = true;
    // The twin computes the same values, so the sum is cut off early.
    run_checked(&cache, &items, &cfg, (0, 4, 0), 20.0);
    let plan = run(
        &cache,
        &toy_dag(&items, &ToyConfig::default()).0,
        Mode::Plan,
    );
    assert_eq!(plan.will_run(), 0, "version 1 results are still cached");
}

#[test]
fn adding_one_item_reruns_only_the_nodes_that_involve_it() {
    let (d, cache, items) = toy_workspace(&VALUES);
    let cfg = ToyConfig::default();
    run_toy(&cache, &items, &cfg);
    let items5 = make_items(d.path(), &[1.0, 2.0, 3.0, 4.0, 10.0]);
    let (o, h) = run_toy(&cache, &items5, &cfg);
    assert_eq!(executed(&o), (1, 1, 1));
    assert_eq!(o.cached(), 8);
    assert_eq!(*o.get(h).unwrap(), summary(40.0, 5));
    let new: Vec<_> = o
        .reports
        .iter()
        .filter(|r| r.status == NodeStatus::Executed)
        .map(|r| r.identity.clone())
        .collect();
    assert_eq!(
        new,
        vec!["toy_parse[item_004]", "toy_scale[item_004]", "toy_sum"]
    );
}

#[test]
fn sweep_variants_sharing_a_prefix_execute_shared_nodes_once() {
    let (_d, cache, items) = toy_workspace(&VALUES);
    let mut b = DagBuilder::new();
    let mut handles = Vec::new();
    for (name, offset) in [("a", 0.0), ("b", 100.0), ("c", 200.0)] {
        b.set_variant(name);
        let cfg = ToyConfig {
            sum: ToySumParams {
                offset,
                faults: Faults::default(),
            },
            ..Default::default()
        };
        handles.push(add_toy(&mut b, &items, &cfg));
    }
    let dag = b.build();
    assert_eq!(
        dag.len(),
        4 + 4 + 3,
        "parse and scale nodes are shared by the three variants"
    );
    let o = run(&cache, &dag, Mode::Run);
    assert_eq!(executed(&o), (4, 4, 3));
    let sums: Vec<f64> = handles.iter().map(|h| o.get(*h).unwrap().sum).collect();
    assert_eq!(sums, vec![20.0, 120.0, 220.0]);
    let shared = o
        .reports
        .iter()
        .find(|r| r.identity == "toy_scale[item_000]")
        .unwrap();
    assert_eq!(shared.variants, vec!["a", "b", "c"]);
}

#[test]
fn corrupt_or_truncated_artifacts_warn_once_and_are_recomputed() {
    let (_d, cache, items) = toy_workspace(&VALUES);
    let mut cfg = ToyConfig::default();
    let (o1, _) = run_toy(&cache, &items, &cfg);
    let store = skytie::store::Store::open(&cache).unwrap();
    let key_of = |identity: &str| {
        o1.reports
            .iter()
            .find(|r| r.identity == identity)
            .unwrap()
            .key
            .unwrap()
    };
    // Flip the last byte of the sum's payload.
    let sum_path = store.object_path(&key_of("toy_sum"));
    let mut bytes = std::fs::read(&sum_path).unwrap();
    *bytes.last_mut().unwrap() ^= 0x55;
    std::fs::write(&sum_path, &bytes).unwrap();
    let (o2, h) = run_toy(&cache, &items, &cfg);
    assert_eq!(o2.warnings.len(), 1, "{:?}", o2.warnings);
    assert!(o2.warnings[0].contains("toy_sum"), "{}", o2.warnings[0]);
    assert_eq!(executed(&o2), (0, 0, 1));
    assert_eq!(*o2.get(h).unwrap(), summary(20.0, 4));
    // Truncate one scale artifact, then change the sum so it needs the scale values: the truncated one is
    // recomputed (with a warning), the others are loaded.
    let scale_path = store.object_path(&key_of("toy_scale[item_002]"));
    let len = std::fs::metadata(&scale_path).unwrap().len();
    std::fs::OpenOptions::new()
        .write(true)
        .open(&scale_path)
        .unwrap()
        .set_len(len / 2)
        .unwrap();
    cfg.sum.offset = 1.0;
    let (o3, h) = run_toy(&cache, &items, &cfg);
    assert_eq!(o3.warnings.len(), 1, "{:?}", o3.warnings);
    assert!(
        o3.warnings[0].contains("toy_scale[item_002]"),
        "{}",
        o3.warnings[0]
    );
    assert_eq!(executed(&o3), (0, 1, 1));
    assert_eq!(o3.get(h).unwrap().sum, 21.0);
    // And everything is healthy again.
    let o4 = run_toy(&cache, &items, &cfg).0;
    assert_eq!((o4.executed(), o4.warnings.len()), (0, 0));
}

#[test]
fn failing_and_panicking_nodes_are_not_recorded_and_dependents_are_skipped() {
    for panic in [false, true] {
        let (_d, cache, items) = toy_workspace(&VALUES);
        let mut cfg = ToyConfig::default();
        if panic {
            cfg.scale.faults.panic_item = "item_001".into();
        } else {
            cfg.scale.faults.fail_item = "item_001".into();
        }
        let (o, h) = run_toy(&cache, &items, &cfg);
        let bad = o
            .reports
            .iter()
            .find(|r| r.identity == "toy_scale[item_001]")
            .unwrap();
        match &bad.status {
            NodeStatus::Failed(m) => assert!(
                m.contains(if panic {
                    "panicked"
                } else {
                    "failure injected"
                }),
                "{m}"
            ),
            s => panic!("expected failure, got {s:?}"),
        }
        let store = skytie::store::Store::open(&cache).unwrap();
        assert!(
            !store.contains(&bad.key.unwrap()),
            "a failed node must never be stored"
        );
        let sum = o.reports.iter().find(|r| r.identity == "toy_sum").unwrap();
        assert_eq!(
            sum.status,
            NodeStatus::Skipped {
                upstream: "toy_scale[item_001]".into()
            }
        );
        assert_eq!((o.executed(), o.failed(), o.skipped()), (7, 1, 1));
        assert!(o.get(h).is_none());
        // Same failure again: the failure was not cached as a success.
        let o = run_toy(&cache, &items, &cfg).0;
        assert_eq!(
            (o.executed(), o.cached(), o.failed(), o.skipped()),
            (0, 7, 1, 1)
        );
        // Fix it: only the failed node and its dependent run.
        cfg.scale.faults = Faults::default();
        // The fault params are part of the key, so all scale nodes re-run; their outputs are unchanged.
        run_checked(&cache, &items, &cfg, (0, 4, 1), 20.0);
    }
}

#[test]
fn results_are_identical_for_one_or_many_threads() {
    let (d, _, items) = toy_workspace(&VALUES);
    let cfg = scaling(0.1, 0.0);
    let mut hashes = Vec::new();
    for threads in [1, 4] {
        let cache = d.path().join(format!("cache{threads}"));
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let o = pool.install(|| run_toy(&cache, &items, &cfg).0);
        let h: Vec<_> = o
            .reports
            .iter()
            .map(|r| (r.identity.clone(), r.key.unwrap(), r.output_hash.unwrap()))
            .collect();
        hashes.push(h);
    }
    assert_eq!(hashes[0], hashes[1]);
}

//! A node that failed is remembered until it succeeds: `plan` says "failed last time: <error>" (plus what
//! changed since that attempt) instead of calling it a new node.

mod support;

use skytie::dag::record::{self, FailureRecord};
use skytie::dag::Mode;
use skytie::plan::plan_text;
use skytie::store::Store;
use skytie::testing::harness::SilentEngine;
use support::*;

/// Runs (or plans) the toy DAG of `cfg` in a session; in run mode the phase's failures are recorded.
/// Returns the plan text in plan mode, the failed count in run mode.
fn session(
    cache: &std::path::Path,
    items: &[std::path::PathBuf],
    cfg: &ToyConfig,
    mode: Mode,
) -> (String, usize) {
    let engine = SilentEngine::open(cache).unwrap();
    let mut s = engine.session(mode);
    s.execute("items", toy_dag(items, cfg).0);
    let phase = &s.phases[0];
    let failed = phase
        .reports
        .iter()
        .filter(|r| matches!(r.status, skytie::dag::NodeStatus::Failed(_)))
        .count();
    if mode == Mode::Run {
        // Idempotent: a session that records failures itself writes the same record.
        let n = skytie::dag::failures::save_failures(&engine.store, &phase.dag, &phase.reports)
            .unwrap();
        assert_eq!(n, failed);
    }
    (plan_text(&s, None), failed)
}

fn line_of<'a>(plan: &'a str, identity: &str) -> &'a str {
    plan.lines()
        .find(|l| l.trim_start().starts_with(&format!("{identity}:")))
        .unwrap_or_else(|| panic!("no line for {identity} in\n{plan}"))
}

#[test]
fn plan_says_a_node_failed_last_time_until_it_succeeds() {
    let (_dir, cache, items) = toy_workspace(&[1.0, 2.0, 3.0]);
    let mut cfg = ToyConfig::default();
    cfg.scale.faults.fail_item = "item_001".into();
    let (_, failed) = session(&cache, &items, &cfg, Mode::Run);
    assert_eq!(failed, 1);

    // Same ingredients: it will run again, and the plan says why it is not cached.
    let (plan, _) = session(&cache, &items, &cfg, Mode::Plan);
    assert_eq!(
        line_of(&plan, "toy_scale[item_001]").trim(),
        "toy_scale[item_001]: failed last time: toy failure injected on item item_001",
        "{plan}"
    );
    // The node skipped because of it is not a failure of its own: it is new (never ran).
    assert!(line_of(&plan, "toy_sum").contains("new node"), "{plan}");

    // The record holds the error and the ingredients of the failed attempt.
    let store = Store::open(&cache).unwrap();
    let f: FailureRecord = record::load_failure(&store, "toy_scale[item_001]", "default").unwrap();
    assert_eq!(f.error, "toy failure injected on item item_001");
    assert_eq!(f.ran_with.key.len(), 64);
    assert_eq!(f.ran_with.stage_version, "1");
    assert_eq!(f.ran_with.params["faults"]["fail_item"], "item_001");
    assert!(record::load_failure(&store, "toy_scale[item_000]", "default").is_none());

    // The fix is a param change: the plan names the failure and what changed since.
    cfg.scale.faults.fail_item.clear();
    let (plan, _) = session(&cache, &items, &cfg, Mode::Plan);
    let line = line_of(&plan, "toy_scale[item_001]");
    assert!(
        line.contains("failed last time: toy failure injected on item item_001; param changed: faults.fail_item: \"item_001\" -> \"\""),
        "{plan}"
    );

    // It succeeds: the failure record is gone, and later plans give the ordinary reasons.
    let (_, failed) = session(&cache, &items, &cfg, Mode::Run);
    assert_eq!(failed, 0);
    assert!(record::load_failure(&store, "toy_scale[item_001]", "default").is_none());
    cfg.scale.factor = 3.0;
    let (plan, _) = session(&cache, &items, &cfg, Mode::Plan);
    assert_eq!(
        line_of(&plan, "toy_scale[item_001]").trim(),
        "toy_scale[item_001]: param changed: factor: 2.0 -> 3.0",
        "{plan}"
    );
    assert!(!plan.contains("failed last time"), "{plan}");
}

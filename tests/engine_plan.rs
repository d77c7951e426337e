//! `plan` says what will run and why; staged planning (a node whose output decides the next phase).

mod support;

use skytie::dag::{DagBuilder, Mode, NodeStatus, RawFile};
use skytie::testing::harness::SilentEngine;
use skytie::testing::toy::{
    item_label, list_items, ToyDir, ToyGen, ToyGenParams, ToyParse, ToySum,
};
use support::*;

fn reasons_of(o: &skytie::dag::Outcome, identity: &str) -> Vec<String> {
    match &o
        .reports
        .iter()
        .find(|r| r.identity == identity)
        .unwrap()
        .status
    {
        NodeStatus::WillRun { reasons } => reasons.clone(),
        s => panic!("{identity}: expected WillRun, got {s:?}"),
    }
}

#[test]
fn plan_names_the_reason_each_node_will_run() {
    let (_dir, cache, items) = toy_workspace(&[1.0, 2.0, 3.0]);
    let mut cfg = ToyConfig::default();
    let p = run(&cache, &toy_dag(&items, &cfg).0, Mode::Plan);
    assert_eq!((p.will_run(), p.executed()), (7, 0), "plan never executes");
    assert!(reasons_of(&p, "toy_parse[item_000]")[0].starts_with("new node"));
    run_toy(&cache, &items, &cfg);
    let p = run(&cache, &toy_dag(&items, &cfg).0, Mode::Plan);
    assert_eq!((p.will_run(), p.cached()), (0, 7));

    cfg.scale.factor = 5.0;
    let p = run(&cache, &toy_dag(&items, &cfg).0, Mode::Plan);
    assert_eq!(p.will_run(), 4);
    assert_eq!(
        reasons_of(&p, "toy_scale[item_001]"),
        vec!["param changed: factor: 2.0 -> 5.0"]
    );
    assert_eq!(
        reasons_of(&p, "toy_sum"),
        vec!["upstream will run: toy_scale[item_000], toy_scale[item_001], toy_scale[item_002]"]
    );

    cfg.scale.factor = 2.0;
    cfg.scale_v2 = true;
    let p = run(&cache, &toy_dag(&items, &cfg).0, Mode::Plan);
    assert_eq!(
        reasons_of(&p, "toy_scale[item_000]"),
        vec!["stage version changed: 1 -> 2"]
    );
    cfg.scale_v2 = false;

    // A changed input file.
    write_item_value(&items[2], 7.0);
    let p = run(&cache, &toy_dag(&items, &cfg).0, Mode::Plan);
    let why = reasons_of(&p, "toy_parse[item_002]");
    assert_eq!(why.len(), 1);
    assert!(
        why[0].starts_with("input changed: file ") && why[0].ends_with("item_002.txt"),
        "{why:?}"
    );
    assert_eq!(p.will_run(), 3, "parse, scale of item 2 and the sum");
}

fn write_item_value(path: &std::path::Path, v: f64) {
    // Different size than before so the stat cache sees the change immediately.
    skytie_util::fsutil::atomic_write(path, format!("{v}.000\n").as_bytes()).unwrap();
}

/// Phase 1 generates the campaign folder; phase 2 is built from it.
fn staged(cache: &std::path::Path, count: u32, mode: Mode) -> (Vec<(usize, usize)>, Option<f64>) {
    let engine = SilentEngine::open(cache).unwrap();
    let mut session = engine.session(mode);
    let mut b = DagBuilder::new();
    let gen = b
        .add(
            ToyGen,
            "tiny",
            ToyGenParams {
                count,
                seed: 3,
                ..Default::default()
            },
            (),
        )
        .unwrap();
    b.request(gen);
    let values = session.execute("campaign", b.build());
    let dir: std::sync::Arc<ToyDir> = match values.require(gen, "the toy campaign") {
        Ok(d) => d,
        Err(_) => {
            let counts = session
                .phases
                .iter()
                .map(|p| (p.reports.len(), 0))
                .collect();
            return (counts, None);
        }
    };
    let files = list_items(std::path::Path::new(&dir.path)).unwrap();
    assert_eq!(files.len(), count as usize);
    let mut b = DagBuilder::new();
    let hs: Vec<_> = files
        .iter()
        .map(|f| {
            b.add(
                ToyParse,
                &item_label(f),
                Default::default(),
                RawFile(f.clone()),
            )
            .unwrap()
        })
        .collect();
    let total = b.add(ToySum, "", Default::default(), hs).unwrap();
    b.request(total);
    let values = session.execute("items", b.build());
    let sum = values.get(total).map(|s| s.sum);
    let counts = session
        .phases
        .iter()
        .map(|p| {
            (
                p.reports.len(),
                p.reports
                    .iter()
                    .filter(|r| r.status == NodeStatus::Executed)
                    .count(),
            )
        })
        .collect();
    (counts, sum)
}

#[test]
fn staged_planning_builds_phase_two_from_a_generated_folder() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    // Plan before anything ran: phase 2 cannot be built yet.
    let (phases, sum) = staged(&cache, 3, Mode::Plan);
    assert_eq!((phases.len(), sum), (1, None));
    let (phases, sum) = staged(&cache, 3, Mode::Run);
    assert_eq!(phases, vec![(1, 1), (4, 4)]);
    // seed 3: values (3*31 + 7i) % 100 = 93, 0, 7
    assert_eq!(sum, Some(100.0));
    let (phases, _) = staged(&cache, 3, Mode::Run);
    assert_eq!(phases, vec![(1, 0), (4, 0)]);
    // One more generated item: the generator re-runs (new folder), but the existing items have the same
    // content, so only the new item's parse node and the sum run.
    let (phases, sum) = staged(&cache, 4, Mode::Run);
    assert_eq!(phases, vec![(1, 1), (5, 2)]);
    assert_eq!(sum, Some(100.0 + 14.0));
    // A deleted generated folder is detected on a cache hit and regenerated.
    let gen_dirs = std::fs::read_dir(cache.join("dirs")).unwrap().count();
    assert!(gen_dirs >= 2);
    std::fs::remove_dir_all(cache.join("dirs")).unwrap();
    let (phases, sum) = staged(&cache, 4, Mode::Run);
    assert_eq!(phases, vec![(1, 1), (5, 0)]);
    assert_eq!(sum, Some(114.0));
}

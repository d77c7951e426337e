//! The engine's shard partition (`skytie::dag::shard`) on a toy graph shaped like the pipeline: one seed per
//! item, windows of two neighbouring items and a node of a stage that is not per-item (as the campaign-wide
//! stages are not). Known
//! answers: which segment owns each node, what a shard executes (its nodes and what they read, renumbered), and
//! that running every shard and then the whole graph on one store executes each node exactly once.

use skytie::dag::shard::{owners, segment_of, segment_targets, segments};
use skytie::dag::{execute, Dag, DagBuilder, Env, Mode, NodeStatus, RawFile, Seeds, ShardSpec};
use skytie::hashing::StatCache;
use skytie::store::Store;
use skytie::testing::toy::{
    ToyParse, ToyParseParams, ToyScale, ToyScaleParams, ToySum, ToySumParams,
};
use std::path::Path;

const PER_ITEM: [&str; 2] = ["toy_parse", "toy_sum"];

/// Seeds `rec i` (files `dir/i.txt`), windows `w i` = sum(rec i, rec i+1), and a `toy_scale` node (a stage not
/// in [`PER_ITEM`]) of the last seed. Returns the graph and the seed ids.
fn graph(dir: &Path, n: usize) -> (Dag, Vec<usize>) {
    let mut b = DagBuilder::new();
    let seeds: Vec<_> = (0..n)
        .map(|i| {
            let f = dir.join(format!("{i}.txt"));
            std::fs::write(&f, format!("{i}")).unwrap();
            b.add(
                ToyParse,
                &format!("rec {i}"),
                ToyParseParams::default(),
                RawFile(f),
            )
            .unwrap()
        })
        .collect();
    for i in 0..n - 1 {
        b.add(
            ToySum,
            &format!("w {i}"),
            ToySumParams::default(),
            vec![seeds[i], seeds[i + 1]],
        )
        .unwrap();
    }
    let g = b
        .add(ToyScale, "", ToyScaleParams::default(), seeds[n - 1])
        .unwrap();
    b.request(g);
    let ids = (0..n).collect(); // seeds were added first
    (b.build(), ids)
}

#[test]
fn shard_specs_parse_and_refuse_nonsense() {
    let s: ShardSpec = "3/8".parse().unwrap();
    assert_eq!((s.index, s.count), (3, 8));
    assert_eq!(s.to_string(), "3/8");
    for bad in ["0/3", "4/3", "3", "a/b", "1/0", ""] {
        let e = bad.parse::<ShardSpec>().unwrap_err();
        assert!(e.contains("K/N"), "{bad}: {e}");
    }
}

#[test]
fn segments_are_contiguous_and_balanced() {
    assert_eq!(segments(10, 3), vec![0..3, 3..6, 6..10]);
    let segs = segments(10, 3);
    let of: Vec<usize> = (0..10).map(|o| segment_of(&segs, o)).collect();
    assert_eq!(of, vec![0, 0, 0, 1, 1, 1, 2, 2, 2, 2]);
    // More shards than items: some segments are empty, every item still has exactly one.
    let segs = segments(2, 4);
    assert_eq!(segs.iter().map(|r| r.len()).sum::<usize>(), 2);
    assert_eq!(segment_of(&segs, 0), 1);
    assert_eq!(segment_of(&segs, 1), 3);
}

#[test]
fn a_window_belongs_to_its_first_member_and_global_nodes_to_nobody() {
    let tmp = tempfile::tempdir().unwrap();
    let (dag, seeds) = graph(tmp.path(), 6);
    let o = owners(&dag, &seeds, &PER_ITEM);
    // Nodes: rec 0..5 (ids 0..5), w 0..4 (ids 6..10), the global scale (id 11).
    assert_eq!(
        &o[..6],
        &[Some(0), Some(1), Some(2), Some(3), Some(4), Some(5)]
    );
    assert_eq!(&o[6..11], &[Some(0), Some(1), Some(2), Some(3), Some(4)]);
    assert_eq!(o[11], None);
    // Shard 2/2 (recordings 3..6) owns rec 3..5, w 3, w 4; it also reads nothing else.
    let spec = ShardSpec { index: 2, count: 2 };
    let s = Seeds {
        nodes: &seeds,
        per_item_stages: &PER_ITEM,
    };
    let targets = segment_targets(&dag, &s, spec);
    let owned: Vec<usize> = (0..dag.len()).filter(|&i| targets[i]).collect();
    assert_eq!(owned, vec![3, 4, 5, 9, 10]);
    // Shard 1/2 owns w 2 = rec 2 + rec 3: it reads rec 3 (the overlap) without owning it.
    let t1 = segment_targets(&dag, &s, ShardSpec { index: 1, count: 2 });
    let (sub, old) = dag.into_subgraph(&t1);
    assert_eq!(old, vec![0, 1, 2, 3, 6, 7, 8]);
    assert_eq!(sub.nodes()[6].identity(), "toy_sum[w 2]");
    assert_eq!(sub.nodes()[6].upstream_ids(), vec![2, 3]);
}

#[test]
fn every_shard_then_the_whole_graph_executes_each_node_once() {
    let tmp = tempfile::tempdir().unwrap();
    let store = Store::open(&tmp.path().join("cache")).unwrap();
    let stat = StatCache::open(store.root());
    let progress = skytie::dag::progress::Progress::new(skytie::dag::progress::ProgressMode::Quiet);
    let env = Env {
        store: &store,
        stat_cache: &stat,
        progress: &progress,
    };
    let mut executed = 0;
    for k in 1..=3 {
        let (dag, seeds) = graph(tmp.path(), 7);
        let s = Seeds {
            nodes: &seeds,
            per_item_stages: &PER_ITEM,
        };
        let targets = segment_targets(&dag, &s, ShardSpec { index: k, count: 3 });
        let (sub, _) = dag.into_subgraph(&targets);
        let out = execute(&sub, &env, Mode::Run);
        assert_eq!(out.failed(), 0);
        assert!(
            out.reports.iter().all(|r| r.stage != "toy_scale"),
            "shards never run campaign-wide nodes"
        );
        executed += out.executed();
    }
    assert_eq!(
        executed,
        7 + 6,
        "the shards computed every per-item node once"
    );
    let (dag, _) = graph(tmp.path(), 7);
    let out = execute(&dag, &env, Mode::Run);
    let ran: Vec<&str> = out
        .reports
        .iter()
        .filter(|r| r.status == NodeStatus::Executed)
        .map(|r| r.stage)
        .collect();
    assert_eq!(
        ran,
        vec!["toy_scale"],
        "the merge runs only the global node"
    );
}

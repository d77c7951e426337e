//! Engine overhead benchmark (plain timing main, no criterion): build + plan and build + run of a
//! 10 001-node toy graph (5 000 items × parse → scale, one global sum) that is entirely cached.
//! Reports microseconds per cached node (wall and process CPU time), for 1 thread and for all threads.
//! Target: ≤ 20 µs per node.
//!
//! `cargo bench --bench engine` (SKYTIE_BENCH_ITEMS overrides the item count).

use skytie::dag::{Dag, DagBuilder, Mode, RawFile};
use skytie::testing::harness::{cpu_seconds, SilentEngine};
use skytie::testing::toy::{write_item, ToyParse, ToyScale, ToySum};
use std::path::PathBuf;
use std::time::Instant;

fn build(items: &[PathBuf]) -> Dag {
    let mut b = DagBuilder::new();
    let mut hs = Vec::with_capacity(items.len());
    for (i, f) in items.iter().enumerate() {
        let label = format!("item_{i:05}");
        let p = b
            .add(ToyParse, &label, Default::default(), RawFile(f.clone()))
            .expect("add parse");
        hs.push(
            b.add(ToyScale, &label, Default::default(), p)
                .expect("add scale"),
        );
    }
    let s = b.add(ToySum, "", Default::default(), hs).expect("add sum");
    b.request(s);
    b.build()
}

fn main() {
    let n: usize = std::env::var("SKYTIE_BENCH_ITEMS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5000);
    // SKYTIE_BENCH_DIR keeps the folder between invocations (for profiling the cached runs alone).
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = std::env::var_os("SKYTIE_BENCH_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| tmp.path().to_path_buf());
    let items_dir = dir.join("items");
    let reuse = items_dir.join(format!("item_{:05}.txt", n - 1)).is_file();
    let items: Vec<PathBuf> = (0..n)
        .map(|i| {
            let name = format!("item_{i:05}.txt");
            if reuse {
                items_dir.join(name)
            } else {
                write_item(&items_dir, &name, i as f64).expect("write item")
            }
        })
        .collect();
    let engine = SilentEngine::open(&dir.join("cache")).expect("store");

    let t = Instant::now();
    let dag = build(&items);
    let nodes = dag.len();
    let o = engine.execute(&dag, Mode::Run);
    if !reuse {
        assert_eq!(o.executed(), nodes, "first run executes everything");
        println!(
            "cold run (all {nodes} nodes execute and are stored): {:.3} s",
            t.elapsed().as_secs_f64()
        );
    }
    // Let the stat cache remember the files (entries younger than 2 s are not trusted).
    std::thread::sleep(std::time::Duration::from_millis(2100));
    engine.stat_cache.save().expect("save stat cache");
    let o = engine.execute(&build(&items), Mode::Run);
    assert_eq!(o.cached(), nodes);

    for threads in [1usize, 0] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let label = if threads == 0 {
            format!("{} threads", pool.current_num_threads())
        } else {
            "1 thread".into()
        };
        for (what, mode) in [("plan", Mode::Plan), ("run ", Mode::Run)] {
            let (mut best, mut best_cpu) = (f64::INFINITY, f64::INFINITY);
            for _ in 0..3 {
                let (t, c) = (Instant::now(), cpu_seconds());
                let o = pool.install(|| engine.execute(&build(&items), mode));
                let (secs, cpu) = (t.elapsed().as_secs_f64(), cpu_seconds() - c);
                assert_eq!(o.cached(), nodes, "all cached");
                best = best.min(secs);
                best_cpu = best_cpu.min(cpu);
            }
            println!(
                "{what} (build + {what}) of {nodes} cached nodes, {label}: wall {:.1} ms = {:.2} µs/node, \
                 process CPU {:.2} µs/node (best of 3)",
                best * 1e3,
                best * 1e6 / nodes as f64,
                best_cpu * 1e6 / nodes as f64
            );
        }
    }
}

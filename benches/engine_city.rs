//! The engine at city scale (plain timing main, no criterion): a synthetic DAG shaped like a city campaign
//! (`skytie::testing::city`, default 10⁶ nodes) of cheap toy stages, so the numbers are the engine's own.
//! Measures, each in a fresh child process so that its peak memory is its own:
//! * **cold**: build the DAG, execute every node and store its artifact (empty cache);
//! * **plan**: build the DAG, compute every key and decide what is cached (`Mode::Plan`);
//! * **no-op**: build and run again with everything cached (`Mode::Run`), including the store look-ups;
//! * **memory**: peak resident memory (VmHWM) minus the resident memory before building, per node.
//!
//! `cargo bench --bench engine_city` (`SKYTIE_BENCH_NODES` sets the size; `SKYTIE_BENCH_DIR` keeps the cache
//! folder, so a later invocation skips the cold run and only measures plan and no-op; `SKYTIE_CITY_ROLE` =
//! `cold`, `plan` or `noop` runs one measurement in this process, e.g. under `perf record`).
//! Targets: plan ≤ 10 µs/node, no-op ≤ 20 µs/node, ≤ 1 KB/node.

use skytie::dag::{DagBuilder, Mode};
use skytie::testing::city::{build_city, recordings_for_nodes};
use skytie::testing::harness::{cpu_seconds, status_bytes, SilentEngine};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// One measurement in this process: prints `RESULT role nodes wall_s cpu_s build_s bytes executed cached`.
fn measure(role: &str, dir: &Path, recordings: usize) {
    let engine = SilentEngine::open(&dir.join("cache")).expect("open the store");
    let _lease = engine.store.begin_run().expect("lease");
    let baseline = status_bytes("VmRSS");
    let (t, c) = (Instant::now(), cpu_seconds());
    let mut b = DagBuilder::new();
    let mut seeds = Vec::new();
    build_city(&mut b, recordings, 1, &mut seeds).expect("build the city DAG");
    let dag = b.build();
    let build_s = t.elapsed().as_secs_f64();
    let graph_bytes = status_bytes("VmRSS").saturating_sub(baseline);
    let mode = if role == "plan" {
        Mode::Plan
    } else {
        Mode::Run
    };
    let o = engine.execute(&dag, mode);
    let (wall, cpu) = (t.elapsed().as_secs_f64(), cpu_seconds() - c);
    let peak = status_bytes("VmHWM").saturating_sub(baseline);
    let nodes = dag.len();
    match role {
        "cold" => assert_eq!(o.executed(), nodes, "a cold run executes every node"),
        _ => assert_eq!(o.cached(), nodes, "every node is cached ({role})"),
    }
    assert!(o.warnings.is_empty(), "warnings: {:?}", o.warnings);
    println!(
        "RESULT {role} {nodes} {wall:.6} {cpu:.6} {build_s:.6} {peak} {graph_bytes} {} {}",
        o.executed(),
        o.cached()
    );
}

struct Row {
    role: String,
    nodes: usize,
    wall: f64,
    cpu: f64,
    build: f64,
    peak: u64,
    graph: u64,
}

fn child(role: &str, dir: &Path, recordings: usize) -> Row {
    let exe = std::env::current_exe().expect("own executable");
    let out = Command::new(exe)
        .env("SKYTIE_CITY_ROLE", role)
        .env("SKYTIE_CITY_DIR", dir)
        .env("SKYTIE_CITY_RECORDINGS", recordings.to_string())
        .output()
        .expect("run the measurement");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{role} failed:\n{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = text
        .lines()
        .find(|l| l.starts_with("RESULT "))
        .expect("a RESULT line");
    let f: Vec<&str> = line.split_whitespace().collect();
    Row {
        role: f[1].to_string(),
        nodes: f[2].parse().expect("nodes"),
        wall: f[3].parse().expect("wall"),
        cpu: f[4].parse().expect("cpu"),
        build: f[5].parse().expect("build"),
        peak: f[6].parse().expect("peak"),
        graph: f[7].parse().expect("graph"),
    }
}

fn main() {
    if let Ok(role) = std::env::var("SKYTIE_CITY_ROLE") {
        let dir = std::env::var_os("SKYTIE_CITY_DIR")
            .or_else(|| std::env::var_os("SKYTIE_BENCH_DIR"))
            .map(PathBuf::from)
            .expect("SKYTIE_CITY_DIR or SKYTIE_BENCH_DIR");
        let recordings = match std::env::var("SKYTIE_CITY_RECORDINGS") {
            Ok(r) => r.parse().expect("SKYTIE_CITY_RECORDINGS"),
            Err(_) => recordings_for_nodes(bench_nodes()),
        };
        measure(&role, &dir, recordings);
        return;
    }
    let nodes = bench_nodes();
    let recordings = recordings_for_nodes(nodes);
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = std::env::var_os("SKYTIE_BENCH_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| tmp.path().to_path_buf());
    std::fs::create_dir_all(&dir).expect("bench folder");
    let marker = dir.join(format!("city-{recordings}.done"));
    let mut rows = Vec::new();
    if !marker.is_file() {
        rows.push(child("cold", &dir, recordings));
        std::fs::write(&marker, b"").expect("marker");
    }
    for role in ["plan", "noop", "plan", "noop"] {
        rows.push(child(role, &dir, recordings));
    }
    println!(
        "city DAG: {recordings} recordings, {} nodes; {} thread(s)",
        rows[0].nodes,
        rayon::current_num_threads()
    );
    println!(
        "| measurement | wall s | µs/node (wall) | µs/node (CPU) | of which build µs/node (wall) | \
         peak bytes/node | of which graph bytes/node |"
    );
    println!("|---|---|---|---|---|---|---|");
    for r in &rows {
        let n = r.nodes as f64;
        println!(
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.0} | {:.0} |",
            r.role,
            r.wall,
            r.wall * 1e6 / n,
            r.cpu * 1e6 / n,
            r.build * 1e6 / n,
            r.peak as f64 / n,
            r.graph as f64 / n
        );
    }
}

fn bench_nodes() -> usize {
    std::env::var("SKYTIE_BENCH_NODES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000)
}

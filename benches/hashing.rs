//! Benchmark of content hashing: a 1 GiB file through `hash_file` (mmap + rayon), the same file on one thread,
//! an in-memory buffer through `hash_bytes`, and a stat-cache hit. Plain `main` timing harness; prints GB/s
//! (1 GB = 1e9 bytes), best of several runs, and GB/s per CPU-second of
//! this process (= per core, robust to other processes competing for the cores). Run: `cargo bench --bench hashing`.

use std::fs::File;
use std::io::Write;
use std::time::{Duration, Instant, SystemTime};

use skytie::hashing::{hash_bytes, hash_file, StatCache};
use skytie::testing::harness::cpu_time;

const FILE_BYTES: usize = 1 << 30;
const RUNS: usize = 5;

/// Best wall time and best CPU time (all threads) of `RUNS` calls of `f`, and the last result.
fn best<T>(mut f: impl FnMut() -> T) -> (Duration, Duration, T) {
    let mut best_wall = Duration::MAX;
    let mut best_cpu = Duration::MAX;
    let mut last = None;
    for _ in 0..RUNS {
        let (t, c) = (Instant::now(), cpu_time());
        let out = std::hint::black_box(f());
        best_wall = best_wall.min(t.elapsed());
        best_cpu = best_cpu.min(cpu_time().saturating_sub(c));
        last = Some(out);
    }
    (best_wall, best_cpu, last.expect("RUNS > 0"))
}

fn gbps(bytes: usize, t: Duration) -> f64 {
    bytes as f64 / t.as_secs_f64() / 1e9
}

fn main() {
    let threads = rayon::current_num_threads();
    if let Ok(load) = std::fs::read_to_string("/proc/loadavg") {
        println!(
            "machine load average (other processes compete for the cores): {}",
            load.trim()
        );
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("one-gib.bin");
    {
        let mut f = File::create(&path).expect("create bench file");
        let mut block = vec![0u8; 1 << 20];
        for i in 0..FILE_BYTES / block.len() {
            for (j, b) in block.iter_mut().enumerate() {
                *b = (i.wrapping_mul(131) ^ j.wrapping_mul(2654435761)) as u8;
            }
            f.write_all(&block).expect("write bench file");
        }
        f.sync_all().expect("sync bench file");
    }
    // Warm the page cache so we time hashing, not the disk.
    let _ = hash_file(&path);

    let (t, cpu, h) = best(|| hash_file(&path).expect("hash"));
    println!(
        "hash_file 1 GiB (mmap + rayon, {threads} threads): {:.2} GB/s wall, {:.2} GB/s per CPU-second (per core)  [{}]",
        gbps(FILE_BYTES, t),
        gbps(FILE_BYTES, cpu),
        &h.to_string()[..16]
    );

    let (t, cpu, _) = best(|| {
        let mut hasher = blake3::Hasher::new();
        hasher.update_mmap(&path).expect("hash");
        hasher.finalize()
    });
    println!(
        "hash 1 GiB file (mmap, 1 thread): {:.2} GB/s wall, {:.2} GB/s per CPU-second",
        gbps(FILE_BYTES, t),
        gbps(FILE_BYTES, cpu)
    );

    let buffer: Vec<u8> = (0..256usize << 20)
        .map(|i| (i.wrapping_mul(2654435761) >> 7) as u8)
        .collect();
    let (t, cpu, _) = best(|| hash_bytes(&buffer));
    println!(
        "hash_bytes 256 MiB in memory (rayon, {threads} threads): {:.2} GB/s wall, {:.2} GB/s per CPU-second",
        gbps(buffer.len(), t),
        gbps(buffer.len(), cpu)
    );

    // Stat-cache hit: the file is not read again (needs an mtime older than the racy window).
    File::options()
        .write(true)
        .open(&path)
        .and_then(|f| f.set_modified(SystemTime::now() - Duration::from_secs(3600)))
        .expect("set mtime");
    let cache = StatCache::open(dir.path());
    cache.hash_file(&path).expect("hash");
    let (t, _, _) = best(|| cache.hash_file(&path).expect("hash"));
    println!(
        "StatCache hit on the 1 GiB file: {:.1} µs (files actually read: {})",
        t.as_secs_f64() * 1e6,
        cache.files_hashed()
    );
}

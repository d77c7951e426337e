//! Several processes and threads saving and loading the same keys in one cache (with a concurrent `gc`
//! removing entries underneath them): every load is a `Miss` or exactly the right bytes, never corrupt.
//!
//! The test binary re-runs itself as the worker processes (env `SKYTIE_STORE_WORKER`).

use std::path::Path;
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};

use skytie::hashing::{KeyBuilder, NodeKey};
use skytie::store::{EntryMeta, Lookup, Store};

const KEYS: u32 = 24;
const ROUNDS: u32 = 6;
const WORKER_ENV: &str = "SKYTIE_STORE_WORKER";

fn key(n: u32) -> NodeKey {
    KeyBuilder::new("concurrency", 1)
        .params(&n.to_le_bytes())
        .finish()
}

/// The one correct payload of key `n`: sizes from a few bytes to ~3 MiB.
fn payload(n: u32) -> Vec<u8> {
    let len = match n % 4 {
        0 => 17,
        1 => 4096,
        2 => 300_000,
        _ => 3 << 20,
    } + n as usize;
    (0..len)
        .map(|i| ((i as u32).wrapping_mul(2654435761).wrapping_add(n) >> 13) as u8)
        .collect()
}

fn meta(n: u32) -> EntryMeta {
    EntryMeta::new("concurrency", "1", format!("item {n}"))
}

/// Saves and loads all keys for some rounds, in a worker-specific order; panics on any wrong or corrupt load.
/// Returns (hits, misses).
fn work(root: &Path, worker: u32) -> (u32, u32) {
    let store = Store::open(root).unwrap();
    let (mut hits, mut misses) = (0, 0);
    for round in 0..ROUNDS {
        for i in 0..KEYS {
            let n = (i * 7 + worker * 5 + round * 11) % KEYS;
            match store.load(&key(n)).unwrap() {
                Lookup::Hit(entry) => {
                    assert!(
                        entry.payload == payload(n),
                        "worker {worker}: wrong bytes for key {n}"
                    );
                    assert_eq!(entry.meta, meta(n));
                    hits += 1;
                }
                Lookup::Miss => {
                    store.save(&key(n), &meta(n), &payload(n)).unwrap();
                    misses += 1;
                }
                Lookup::Corrupt { message } => {
                    panic!("worker {worker}: corrupt entry under concurrency: {message}")
                }
            }
        }
    }
    (hits, misses)
}

#[test]
fn processes_and_threads_sharing_one_cache_only_ever_see_miss_or_correct_bytes() {
    if let Ok(spec) = std::env::var(WORKER_ENV) {
        // Worker process: "<worker id>:<cache root>".
        let (id, root) = spec.split_once(':').expect("worker spec");
        let (hits, misses) = work(Path::new(root), id.parse().unwrap());
        println!("worker {id}: {hits} hits, {misses} misses");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("cache");
    Store::open(&root).unwrap();
    let exe = std::env::current_exe().unwrap();
    let children: Vec<_> = (1..=2)
        .map(|id| {
            Command::new(&exe)
                .args([
                    "processes_and_threads_sharing_one_cache_only_ever_see_miss_or_correct_bytes",
                    "--exact",
                    "--nocapture",
                    "--test-threads=1",
                ])
                .env(WORKER_ENV, format!("{id}:{}", root.display()))
                .spawn()
                .unwrap()
        })
        .collect();
    let done = AtomicBool::new(false);
    let (local, gc_runs) = std::thread::scope(|s| {
        let threads: Vec<_> = (10..12)
            .map(|w| {
                s.spawn({
                    let root = root.clone();
                    move || work(&root, w)
                })
            })
            .collect();
        let gc = s.spawn(|| {
            // Trim everything now and then: loads must still be Miss or correct.
            let store = Store::open(&root).unwrap();
            let mut runs = 0;
            while !done.load(Ordering::Relaxed) {
                store.gc(0).unwrap();
                runs += 1;
                std::thread::sleep(std::time::Duration::from_millis(30));
            }
            runs
        });
        let results: Vec<_> = threads.into_iter().map(|t| t.join().unwrap()).collect();
        done.store(true, Ordering::Relaxed);
        (results, gc.join().unwrap())
    });
    for child in children {
        let out = child.wait_with_output().unwrap();
        assert!(
            out.status.success(),
            "worker process failed: {:?}",
            out.status
        );
    }
    assert!(gc_runs > 0);
    for (hits, misses) in local {
        assert_eq!(hits + misses, KEYS * ROUNDS);
    }
    // Afterwards every entry present is intact.
    let store = Store::open(&root).unwrap();
    let report = store.verify().unwrap();
    assert!(report.all_ok(), "{:?}", report.bad);
    for n in 0..KEYS {
        match store.load(&key(n)).unwrap() {
            Lookup::Hit(e) => assert!(e.payload == payload(n)),
            Lookup::Miss => {}
            Lookup::Corrupt { message } => panic!("{message}"),
        }
    }
}

#[test]
fn threads_sharing_one_store_handle() {
    if std::env::var(WORKER_ENV).is_ok() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    std::thread::scope(|s| {
        for w in 0..4u32 {
            let store = &store;
            s.spawn(move || {
                for i in 0..KEYS {
                    let n = (i + w * 3) % KEYS;
                    match store.load(&key(n)).unwrap() {
                        Lookup::Hit(e) => assert!(e.payload == payload(n)),
                        Lookup::Miss => {
                            store.save(&key(n), &meta(n), &payload(n)).unwrap();
                        }
                        Lookup::Corrupt { message } => panic!("{message}"),
                    }
                }
            });
        }
    });
    assert_eq!(store.stats().unwrap().entries, KEYS as u64);
}

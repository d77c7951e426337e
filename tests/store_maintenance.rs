//! Run leases, gc, stats and verify: a SIGKILLed run's lease does not block or protect anything; gc removes
//! least-recently-used entries first and never the entries a live run used; stats per stage are exact;
//! verify removes damaged entries; the `skytie cache` command bodies print them.
//!
//! The test binary re-runs itself as the run that gets killed (env `SKYTIE_LEASE_CHILD`).

use std::fs::{self, File};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, SystemTime};

use skytie::cache_cmd;
use skytie::hashing::{KeyBuilder, NodeKey};
use skytie::store::{EntryMeta, Lookup, Store};

const CHILD_ENV: &str = "SKYTIE_LEASE_CHILD";

fn key(n: u32) -> NodeKey {
    KeyBuilder::new("maintenance", 1)
        .params(&n.to_le_bytes())
        .finish()
}

/// Makes the entry of `key` look last used `ago` ago.
fn age(store: &Store, key: &NodeKey, ago: Duration) {
    let f = File::options()
        .write(true)
        .open(store.object_path(key))
        .unwrap();
    f.set_modified(SystemTime::now() - ago).unwrap();
}

fn file_len(store: &Store, key: &NodeKey) -> u64 {
    fs::metadata(store.object_path(key)).unwrap().len()
}

/// A store in a fresh temporary folder; `None` in the child process of
/// `a_sigkilled_runs_lease_neither_blocks_nor_protects`, where the other tests do nothing.
fn fresh_store() -> Option<(tempfile::TempDir, Store)> {
    if std::env::var(CHILD_ENV).is_ok() {
        return None;
    }
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    Some((dir, store))
}

/// Saves entries `key(0) … key(count − 1)` of stage `s` with payload `payload(n)`; returns their meta.
fn save_entries(store: &Store, count: u32, payload: impl Fn(u32) -> Vec<u8>) -> EntryMeta {
    let meta = EntryMeta::new("s", "1", "i");
    for n in 0..count {
        store.save(&key(n), &meta, &payload(n)).unwrap();
    }
    meta
}

#[test]
fn a_sigkilled_runs_lease_neither_blocks_nor_protects() {
    if let Ok(root) = std::env::var(CHILD_ENV) {
        // The run that will be killed: lease, save an entry, signal readiness, wait to die.
        let store = Store::open(Path::new(&root)).unwrap();
        let lease = store.begin_run().unwrap();
        store
            .save(
                &key(100),
                &EntryMeta::new("child", "1", "c"),
                b"child result",
            )
            .unwrap();
        fs::write(Path::new(&root).join("child-ready"), b"").unwrap();
        std::thread::sleep(Duration::from_secs(120));
        drop(lease);
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("cache");
    let store = Store::open(&root).unwrap();
    store
        .save(&key(1), &EntryMeta::new("old", "1", "o"), b"old result")
        .unwrap();
    age(&store, &key(1), Duration::from_secs(7200));

    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([
            "a_sigkilled_runs_lease_neither_blocks_nor_protects",
            "--exact",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD_ENV, &root)
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !root.join("child-ready").exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "child run did not start"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // While the child lives: its lease is seen, and gc keeps what it used.
    let live = store.live_runs().unwrap();
    assert_eq!(live.len(), 1);
    assert_eq!(live[0].pid, child.id());
    let report = store.gc(0).unwrap();
    assert_eq!(report.live_runs, 1);
    assert_eq!(report.removed_keys, vec![key(1)]);
    assert_eq!(report.protected_entries, 1);
    assert!(store.contains(&key(100)));

    child.kill().unwrap(); // SIGKILL: no destructor runs, the lease file stays behind.
    child.wait().unwrap();
    assert_eq!(
        fs::read_dir(root.join("runs")).unwrap().count(),
        1,
        "the killed run's lease file is still there"
    );

    // The stale lease is detected (its lock died with the process) and removed; it protects nothing.
    let report = store.gc(0).unwrap();
    assert_eq!(report.live_runs, 0);
    assert_eq!(report.stale_leases_removed, 1);
    assert_eq!(report.removed_keys, vec![key(100)]);
    assert_eq!(fs::read_dir(root.join("runs")).unwrap().count(), 0);
    // A new run starts normally.
    let lease = store.begin_run().unwrap();
    assert!(lease.path().exists());
    assert_eq!(store.live_runs().unwrap().len(), 1);
    drop(lease);
    assert_eq!(store.live_runs().unwrap().len(), 0);
    assert_eq!(
        fs::read_dir(root.join("runs")).unwrap().count(),
        0,
        "ended run left its lease"
    );
}

#[test]
fn gc_removes_least_recently_used_first_down_to_the_limit() {
    let Some((_dir, store)) = fresh_store() else {
        return;
    };
    save_entries(&store, 5, |n| vec![n as u8; 1000 * (n as usize + 1)]);
    // Last used: key 3 longest ago, then 0, 4, 1, 2.
    for (n, hours) in [(3, 50), (0, 40), (4, 30), (1, 20), (2, 10)] {
        age(&store, &key(n), Duration::from_secs(hours * 3600));
    }
    let sizes: Vec<u64> = (0..5).map(|n| file_len(&store, &key(n))).collect();
    let total: u64 = sizes.iter().sum();
    // Nothing to do under the limit.
    let report = store.gc(total).unwrap();
    assert_eq!(report.removed_entries, 0);
    assert_eq!(report.kept_bytes, total);
    // Just under the total: only the least recently used goes.
    let report = store.gc(total - 1).unwrap();
    assert_eq!(report.removed_keys, vec![key(3)]);
    assert_eq!(report.removed_bytes, sizes[3]);
    // Room for keys 1 and 2 only: 0 then 4 go, in that order.
    let report = store.gc(sizes[1] + sizes[2]).unwrap();
    assert_eq!(report.removed_keys, vec![key(0), key(4)]);
    assert_eq!(report.kept_bytes, sizes[1] + sizes[2]);
    // A load marks an entry as used now, so it becomes the most recent.
    assert!(matches!(store.load(&key(1)).unwrap(), Lookup::Hit(_)));
    let report = store.gc(sizes[1]).unwrap();
    assert_eq!(report.removed_keys, vec![key(2)]);
    assert!(store.contains(&key(1)));
    // Via the command body, with a size string.
    let text = cache_cmd::gc(&store, "0").unwrap();
    assert!(text.contains("removed (LRU first)"), "{text}");
    assert!(!store.contains(&key(1)));
    assert!(cache_cmd::gc(&store, "ten gigabytes")
        .unwrap_err()
        .contains("invalid size"));
}

#[test]
fn gc_to_zero_keeps_everything_a_live_run_used_and_removes_the_rest() {
    let Some((dir, store)) = fresh_store() else {
        return;
    };
    let meta = save_entries(&store, 6, |n| vec![n as u8; 100]);
    for n in 0..6 {
        age(&store, &key(n), Duration::from_secs(3600 * (n as u64 + 1)));
    }
    let lease = store.begin_run().unwrap();
    // The live run loads two old entries and saves a new one.
    assert!(matches!(store.load(&key(1)).unwrap(), Lookup::Hit(_)));
    assert!(matches!(store.load(&key(4)).unwrap(), Lookup::Hit(_)));
    store.save(&key(50), &meta, b"new").unwrap();
    // Another handle (e.g. `skytie cache gc` in another terminal) trims to zero.
    let other = Store::open(dir.path()).unwrap();
    let report = other.gc(0).unwrap();
    assert_eq!(report.live_runs, 1);
    // Unused ones go, least recently used (oldest) first.
    assert_eq!(report.removed_keys, vec![key(5), key(3), key(2), key(0)]);
    assert_eq!(report.protected_entries, 3);
    for n in [1, 4, 50] {
        assert!(
            other.contains(&key(n)),
            "entry {n} used by the live run was removed"
        );
    }
    let text = cache_cmd::gc(&other, "0").unwrap();
    assert!(text.contains("still above the limit"), "{text}");
    drop(lease);
    let report = other.gc(0).unwrap();
    assert_eq!(report.live_runs, 0);
    assert_eq!(report.removed_entries, 3);
    assert_eq!(other.stats().unwrap().entries, 0);
}

#[test]
fn stats_count_entries_and_bytes_per_stage() {
    let Some((_dir, store)) = fresh_store() else {
        return;
    };
    let empty = store.stats().unwrap();
    assert_eq!(
        (empty.entries, empty.bytes, empty.per_stage.len()),
        (0, 0, 0)
    );
    let plan = [
        ("ortho", 0, 10_000usize),
        ("ortho", 1, 20_000),
        ("ortho", 2, 5),
        ("match", 3, 700),
        ("match", 4, 0),
    ];
    for (stage, n, len) in plan {
        store
            .save(
                &key(n),
                &EntryMeta::new(stage, "1", format!("{stage}[{n}]")),
                &vec![1u8; len],
            )
            .unwrap();
    }
    store.put_record("last-key", "a", b"0123456789").unwrap();
    let stats = store.stats().unwrap();
    assert_eq!(stats.entries, 5);
    let bytes = |ns: &[u32]| ns.iter().map(|&n| file_len(&store, &key(n))).sum::<u64>();
    assert_eq!(stats.bytes, bytes(&[0, 1, 2, 3, 4]));
    assert_eq!(stats.per_stage.len(), 2);
    assert_eq!(stats.per_stage["ortho"].entries, 3);
    assert_eq!(stats.per_stage["ortho"].bytes, bytes(&[0, 1, 2]));
    assert_eq!(stats.per_stage["match"].entries, 2);
    assert_eq!(stats.per_stage["match"].bytes, bytes(&[3, 4]));
    assert_eq!(stats.records.entries, 1);
    assert_eq!(stats.unreadable.entries, 0);
    // A damaged header is counted as unreadable, not under a stage.
    fs::write(store.object_path(&key(4)), b"garbage").unwrap();
    let stats = store.stats().unwrap();
    assert_eq!(stats.per_stage["match"].entries, 1);
    assert_eq!(stats.unreadable.entries, 1);
    assert_eq!(stats.entries, 5);
    let text = cache_cmd::stats(&store);
    assert!(
        text.contains("ortho") && text.contains("match") && text.contains("total"),
        "{text}"
    );
    assert!(text.contains("unreadable"), "{text}");
}

#[test]
fn verify_rehashes_everything_and_removes_bad_entries() {
    let Some((_dir, store)) = fresh_store() else {
        return;
    };
    save_entries(&store, 8, |n| vec![n as u8; 2000 + n as usize]);
    let (text, ok) = cache_cmd::verify(&store);
    assert!(ok, "{text}");
    assert!(text.contains("checked 8 entries"), "{text}");
    // Flip one payload byte of key 5 (header intact: only a re-hash finds it) and truncate key 2.
    let p5 = store.object_path(&key(5));
    let mut b = fs::read(&p5).unwrap();
    let i = b.len() - 10;
    b[i] ^= 0x01;
    fs::write(&p5, b).unwrap();
    let p2 = store.object_path(&key(2));
    let b = fs::read(&p2).unwrap();
    fs::write(&p2, &b[..b.len() / 2]).unwrap();
    // A left-over temporary of a write that crashed long ago is cleaned up.
    let tmp = p5.parent().unwrap().join(".leftover.123.0.tmp");
    fs::write(&tmp, b"partial").unwrap();
    File::options()
        .write(true)
        .open(&tmp)
        .unwrap()
        .set_modified(SystemTime::now() - Duration::from_secs(7200))
        .unwrap();

    let report = store.verify().unwrap();
    assert_eq!(report.checked, 8);
    assert_eq!(report.ok, 6);
    let mut bad: Vec<_> = report.bad.iter().map(|b| b.key).collect();
    bad.sort();
    let mut expected = vec![key(2), key(5)];
    expected.sort();
    assert_eq!(bad, expected);
    assert!(report.bad.iter().all(|b| b.removed));
    assert!(report
        .bad
        .iter()
        .any(|b| b.reason.contains("payload hash mismatch")));
    assert!(report.bad.iter().any(|b| b.reason.contains("truncated")));
    assert_eq!(report.temp_files_removed, 1);
    assert!(!p5.exists() && !p2.exists() && !tmp.exists());
    assert_eq!(store.load(&key(5)).unwrap(), Lookup::Miss);
    // A second pass is clean; the command body reports failure only when something was bad.
    let (text, ok) = cache_cmd::verify(&store);
    assert!(ok && text.contains("6 ok, 0 bad"), "{text}");
    fs::write(store.object_path(&key(0)), b"").unwrap();
    let (text, ok) = cache_cmd::verify(&store);
    assert!(
        !ok && text.contains("empty file") && text.contains("removed"),
        "{text}"
    );
}

#[test]
fn contains_marks_entries_used_only_while_this_handle_runs() {
    let Some((_dir, store)) = fresh_store() else {
        return;
    };
    save_entries(&store, 3, |_| b"x".to_vec());
    for n in 0..3 {
        age(&store, &key(n), Duration::from_secs(3600));
    }
    let mtime = |n| {
        fs::metadata(store.object_path(&key(n)))
            .unwrap()
            .modified()
            .unwrap()
    };
    let old = mtime(0);
    // Planning (no lease): contains changes nothing.
    assert!(store.contains(&key(0)));
    assert_eq!(mtime(0), old);
    // A run that finds key 0 cached without loading it still uses it: gc keeps it.
    let lease = store.begin_run().unwrap();
    assert!(store.contains(&key(0)));
    assert!(!store.contains(&key(99)));
    assert!(mtime(0) > old);
    assert!(store.mark_used(&key(1)));
    assert!(!store.mark_used(&key(98)));
    let report = store.gc(0).unwrap();
    assert_eq!(report.removed_keys, vec![key(2)]);
    drop(lease);
    // After the run ended, contains is read-only again.
    age(&store, &key(0), Duration::from_secs(60));
    let before = mtime(0);
    assert!(store.contains(&key(0)));
    assert_eq!(mtime(0), before);
}

//! Node keys (every ingredient matters, boundaries are unambiguous, the layout has a known answer), file
//! hashing and the stat cache (unchanged files are not re-read; touched, modified or freshly written ones are).

use std::fs::{self, File};
use std::time::{Duration, SystemTime};

use skytie::hashing::{hash_bytes, hash_file, ContentHash, KeyBuilder, NodeKey, StatCache};

fn h(s: &str) -> ContentHash {
    hash_bytes(s.as_bytes())
}

/// A key from its ingredients: stage, version, params (`None`: not given) and named inputs (hashes of strings).
fn key(stage: &str, version: &str, params: Option<&[u8]>, inputs: &[(&str, &str)]) -> NodeKey {
    let mut k = KeyBuilder::new(stage, version);
    if let Some(p) = params {
        k = k.params(p);
    }
    for (name, content) in inputs {
        k = k.input(name, &h(content));
    }
    k.finish()
}

#[test]
fn changing_any_ingredient_changes_the_key() {
    let p = Some(&b"p"[..]);
    let inputs = [("pano", "a"), ("dsm", "b")];
    let k = key("ortho", "2", p, &inputs);
    assert_eq!(k, key("ortho", "2", p, &inputs), "keys are deterministic");
    let variants = [
        key("orthO", "2", p, &inputs),
        key("ortho", "3", p, &inputs),
        key("ortho", "2", Some(b"q"), &inputs),
        key("ortho", "2", p, &[("pane", "a"), ("dsm", "b")]),
        key("ortho", "2", p, &[("pano", "A"), ("dsm", "b")]),
        key("ortho", "2", p, &[("dsm", "b"), ("pano", "a")]),
        key("ortho", "2", p, &[("pano", "a")]),
        key("ortho", "2", p, &[("pano", "a"), ("dsm", "b"), ("x", "c")]),
        key("ortho", "2", None, &inputs),
        key("ortho", "2", Some(b""), &inputs),
    ];
    let mut all = vec![k];
    all.extend(variants);
    for i in 0..all.len() {
        for j in i + 1..all.len() {
            assert_ne!(all[i], all[j], "variants {i} and {j} collide");
        }
    }
    // The version may be given as a number or a string with the same meaning.
    assert_eq!(
        KeyBuilder::new("s", 2u32).finish(),
        KeyBuilder::new("s", "2").finish()
    );
}

#[test]
fn ingredient_boundaries_are_unambiguous() {
    let x = h("x");
    let a = KeyBuilder::new("s", "1")
        .params(b"ab")
        .input("c", &x)
        .finish();
    let b = KeyBuilder::new("s", "1")
        .params(b"a")
        .input("bc", &x)
        .finish();
    assert_ne!(a, b);
    assert_ne!(
        KeyBuilder::new("ab", "c").finish(),
        KeyBuilder::new("a", "bc").finish()
    );
    assert_ne!(
        KeyBuilder::new("s", "1").input("ab", &x).finish(),
        KeyBuilder::new("s", "1").input("a", &x).finish()
    );
    // Params that spell out another ingredient's encoding do not alias it.
    let mut fake = b"p".to_vec();
    fake.push(4); // input tag
    fake.extend_from_slice(&1u64.to_le_bytes());
    fake.extend_from_slice(b"i");
    fake.extend_from_slice(&x.0);
    let real = KeyBuilder::new("s", "1")
        .params(b"p")
        .input("i", &x)
        .finish();
    assert_ne!(KeyBuilder::new("s", "1").params(&fake).finish(), real);
}

#[test]
fn key_layout_known_answer() {
    // Documented layout: blake3 derive-key mode, each field = tag, u64-LE length, bytes; inputs add 32 hash bytes.
    let x = h("x");
    let mut expected = blake3::Hasher::new_derive_key("skytie 2026-11 node key v1");
    for (tag, bytes) in [(1u8, &b"ortho"[..]), (2, b"2"), (3, b"pp")] {
        expected.update(&[tag]);
        expected.update(&(bytes.len() as u64).to_le_bytes());
        expected.update(bytes);
    }
    expected.update(&[4]);
    expected.update(&4u64.to_le_bytes());
    expected.update(b"pano");
    expected.update(&x.0);
    expected.update(&[0xFF]);
    let key = KeyBuilder::new("ortho", "2")
        .params(b"pp")
        .input("pano", &x)
        .finish();
    assert_eq!(key.0, *expected.finalize().as_bytes());
}

#[test]
fn file_hash_equals_byte_hash_for_small_and_large_files() {
    let dir = tempfile::tempdir().unwrap();
    for len in [0usize, 1, 1000, (3 << 20) + 5] {
        let data: Vec<u8> = (0..len).map(|i| (i * 7 % 256) as u8).collect();
        let p = dir.path().join(format!("f{len}"));
        fs::write(&p, &data).unwrap();
        assert_eq!(hash_file(&p).unwrap(), hash_bytes(&data));
        assert_eq!(hash_file(&p).unwrap().0, *blake3::hash(&data).as_bytes());
    }
    assert!(hash_file(&dir.path().join("missing")).is_err());
}

fn set_mtime(path: &std::path::Path, ago: Duration) {
    File::options()
        .write(true)
        .open(path)
        .unwrap()
        .set_modified(SystemTime::now() - ago)
        .unwrap();
}

#[test]
fn stat_cache_does_not_reread_unchanged_files_and_rehashes_changed_ones() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("cache");
    fs::create_dir_all(&root).unwrap();
    let file = dir.path().join("input.tif");
    fs::write(&file, b"first content").unwrap();
    set_mtime(&file, Duration::from_secs(3600));

    let cache = StatCache::open(&root);
    assert!(cache.is_empty());
    let first = cache.hash_file(&file).unwrap();
    assert_eq!(first, hash_bytes(b"first content"));
    assert_eq!(cache.files_hashed(), 1);
    assert_eq!(cache.hash_file(&file).unwrap(), first);
    assert_eq!(cache.files_hashed(), 1, "unchanged file was read again");
    // The same file through another path spelling shares the entry.
    let other_spelling = dir.path().join(".").join("input.tif");
    assert_eq!(cache.hash_file(&other_spelling).unwrap(), first);
    assert_eq!(cache.files_hashed(), 1);
    cache.save().unwrap();
    assert!(root.join("stat-cache.bin").is_file());

    // A new process: the persisted cache answers without reading.
    let cache = StatCache::open(&root);
    assert_eq!(cache.len(), 1);
    assert_eq!(cache.hash_file(&file).unwrap(), first);
    assert_eq!(cache.files_hashed(), 0);

    // Same size, different content, different (old) mtime: re-hashed.
    fs::write(&file, b"other content").unwrap();
    set_mtime(&file, Duration::from_secs(1800));
    assert_eq!(
        cache.hash_file(&file).unwrap(),
        hash_bytes(b"other content")
    );
    assert_eq!(cache.files_hashed(), 1);
    assert_eq!(
        cache.hash_file(&file).unwrap(),
        hash_bytes(b"other content")
    );
    assert_eq!(cache.files_hashed(), 1);

    // Touched (mtime changed, content the same): re-hashed, same hash.
    set_mtime(&file, Duration::from_secs(900));
    assert_eq!(
        cache.hash_file(&file).unwrap(),
        hash_bytes(b"other content")
    );
    assert_eq!(cache.files_hashed(), 2);

    // Replaced by another file (new inode) with identical size and mtime: re-hashed.
    let replacement = dir.path().join("replacement");
    fs::write(&replacement, b"third content").unwrap();
    let mtime = fs::metadata(&file).unwrap().modified().unwrap();
    File::options()
        .write(true)
        .open(&replacement)
        .unwrap()
        .set_modified(mtime)
        .unwrap();
    fs::rename(&replacement, &file).unwrap();
    assert_eq!(
        cache.hash_file(&file).unwrap(),
        hash_bytes(b"third content")
    );
    assert_eq!(cache.files_hashed(), 3);
}

#[test]
fn stat_cache_does_not_remember_files_written_just_now() {
    // A file modified within the last 2 s could change again within the same timestamp tick: always re-read.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("fresh");
    fs::write(&file, b"fresh").unwrap();
    let cache = StatCache::open(dir.path());
    cache.hash_file(&file).unwrap();
    cache.hash_file(&file).unwrap();
    assert_eq!(cache.files_hashed(), 2);
    assert!(cache.is_empty());
}

#[test]
fn corrupt_or_foreign_stat_cache_files_start_empty_and_are_rebuilt() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("input");
    fs::write(&file, b"content").unwrap();
    set_mtime(&file, Duration::from_secs(3600));
    let cache = StatCache::open(dir.path());
    cache.hash_file(&file).unwrap();
    cache.save().unwrap();
    let bin = dir.path().join("stat-cache.bin");
    let good = fs::read(&bin).unwrap();
    for damaged in [
        Vec::new(),
        b"garbage".to_vec(),
        good[..good.len() - 1].to_vec(),
        {
            let mut b = good.clone();
            b[12] ^= 1;
            b
        },
    ] {
        fs::write(&bin, &damaged).unwrap();
        let cache = StatCache::open(dir.path());
        assert!(cache.is_empty());
        assert_eq!(cache.hash_file(&file).unwrap(), hash_bytes(b"content"));
        assert_eq!(cache.files_hashed(), 1);
        cache.save().unwrap();
        assert_eq!(fs::read(&bin).unwrap(), good, "rebuilt file differs");
    }
}

#[test]
fn stat_cache_forgets_deleted_files_on_save() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    for p in [&a, &b] {
        fs::write(p, p.to_string_lossy().as_bytes()).unwrap();
        set_mtime(p, Duration::from_secs(3600));
    }
    let cache = StatCache::open(dir.path());
    cache.hash_file(&a).unwrap();
    cache.hash_file(&b).unwrap();
    assert_eq!(cache.len(), 2);
    fs::remove_file(&a).unwrap();
    cache.save().unwrap();
    assert_eq!(cache.len(), 1);
    assert_eq!(StatCache::open(dir.path()).len(), 1);
}

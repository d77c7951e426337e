//! Store entries: save/load round trips, and every kind of damage (flipped payload byte, truncation, other
//! format version, garbage, empty file, misplaced file) is reported once as `Corrupt`, deleted, then a `Miss`.

use std::fs;

use skytie::codec::Artifact;
use skytie::hashing::{hash_bytes, KeyBuilder, NodeKey};
use skytie::store::{EntryMeta, Lookup, Store, StoreError, STORE_FORMAT_VERSION};
use skytie_stages::imaging::GrayImage;

fn key(n: u32) -> NodeKey {
    KeyBuilder::new("test", 1).params(&n.to_le_bytes()).finish()
}

fn meta(item: &str) -> EntryMeta {
    EntryMeta::new("ortho", "2", item)
}

fn hit(lookup: Lookup) -> skytie::store::Entry {
    match lookup {
        Lookup::Hit(e) => e,
        other => panic!("expected a hit, got {other:?}"),
    }
}

fn corrupt_message(lookup: Lookup) -> String {
    match lookup {
        Lookup::Corrupt { message } => message,
        other => panic!("expected Corrupt, got {other:?}"),
    }
}

#[test]
fn save_then_load_returns_the_same_bytes_meta_and_hash() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(&dir.path().join("cache")).unwrap();
    assert!(store.root().join("objects").is_dir() && store.root().join("runs").is_dir());
    let k = key(1);
    assert_eq!(store.load(&k).unwrap(), Lookup::Miss);
    assert!(!store.contains(&k));
    let payload: Vec<u8> = (0..100_000u32).map(|i| (i % 251) as u8).collect();
    let h = store.save(&k, &meta("ortho[rec 0012]"), &payload).unwrap();
    assert_eq!(h, hash_bytes(&payload));
    assert!(store.contains(&k));
    let hex = k.to_string();
    assert!(store
        .root()
        .join("objects")
        .join(&hex[..2])
        .join(&hex[2..])
        .is_file());
    let e = hit(store.load(&k).unwrap());
    assert_eq!(e.payload, payload);
    assert_eq!(e.meta, meta("ortho[rec 0012]"));
    assert_eq!(e.content_hash, h);
    // Empty payloads are fine, and saving again replaces atomically.
    store.save(&k, &meta("x"), b"").unwrap();
    let e = hit(store.load(&k).unwrap());
    assert!(e.payload.is_empty());
    assert_eq!(e.meta.item, "x");
    // No temporaries left behind.
    let shard: Vec<_> = fs::read_dir(store.object_path(&k).parent().unwrap())
        .unwrap()
        .collect();
    assert_eq!(shard.len(), 1);
}

#[test]
fn a_large_image_artifact_round_trips_through_the_store() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let data: Vec<f32> = (0..1000 * 700).map(|i| (i as f32 * 0.001).sin()).collect();
    let img = GrayImage::from_vec(1000, 700, data).unwrap();
    let mut bytes = Vec::new();
    img.encode(&mut bytes);
    store.save(&key(9), &meta("img"), &bytes).unwrap();
    let back = GrayImage::decode(&hit(store.load(&key(9)).unwrap()).payload).unwrap();
    assert_eq!(back, img);
}

/// Damages the entry of `k` with `damage`, then checks Corrupt once (message names key, path, reason), file
/// deleted, next load Miss.
fn check_damage(damage: impl FnOnce(&std::path::Path), reason_part: &str) {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let k = key(7);
    let payload = vec![42u8; 5000];
    store.save(&k, &meta("m"), &payload).unwrap();
    let path = store.object_path(&k);
    damage(&path);
    let message = corrupt_message(store.load(&k).unwrap());
    assert!(message.contains(&k.to_string()), "{message}");
    assert!(message.contains(&path.display().to_string()), "{message}");
    assert!(
        message.contains(reason_part),
        "expected `{reason_part}` in: {message}"
    );
    assert!(!path.exists(), "corrupt entry not deleted");
    assert_eq!(store.load(&k).unwrap(), Lookup::Miss);
    assert!(!store.contains(&k));
    // Recomputing and saving works again.
    store.save(&k, &meta("m"), &payload).unwrap();
    assert_eq!(hit(store.load(&k).unwrap()).payload, payload);
}

#[test]
fn one_flipped_payload_byte_is_detected() {
    check_damage(
        |p| {
            let mut b = fs::read(p).unwrap();
            let last = b.len() - 1;
            b[last - 100] ^= 1;
            fs::write(p, b).unwrap();
        },
        "payload hash mismatch",
    );
}

#[test]
fn truncated_files_are_detected_at_every_length() {
    for cut in [1usize, 7, 8, 20, 50, 60, 120, 4000] {
        check_damage(
            |p| {
                let b = fs::read(p).unwrap();
                let keep = b.len().saturating_sub(cut).max(1);
                fs::write(p, &b[..keep]).unwrap();
            },
            "",
        );
    }
    check_damage(
        |p| {
            let b = fs::read(p).unwrap();
            fs::write(p, &b[..b.len() - 1]).unwrap();
        },
        "truncated",
    );
}

#[test]
fn garbage_and_empty_files_are_detected() {
    check_damage(|p| fs::write(p, vec![0xA5u8; 3000]).unwrap(), "bad magic");
    check_damage(|p| fs::write(p, b"").unwrap(), "empty file");
    check_damage(|p| fs::write(p, b"SKY").unwrap(), "truncated");
}

#[test]
fn an_entry_filed_under_the_wrong_key_is_detected() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    store.save(&key(1), &meta("a"), b"one").unwrap();
    store.save(&key(2), &meta("b"), b"two").unwrap();
    fs::copy(store.object_path(&key(1)), store.object_path(&key(2))).unwrap();
    let message = corrupt_message(store.load(&key(2)).unwrap());
    assert!(message.contains("misplaced"), "{message}");
    assert_eq!(store.load(&key(2)).unwrap(), Lookup::Miss);
    assert_eq!(hit(store.load(&key(1)).unwrap()).payload, b"one");
}

#[test]
fn another_store_format_version_is_reported_once_per_handle_then_silent() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    for n in 0..3 {
        store.save(&key(n), &meta("m"), b"old bytes").unwrap();
        let p = store.object_path(&key(n));
        let mut b = fs::read(&p).unwrap();
        assert_eq!(&b[..7], b"SKYTIE\0");
        assert_eq!(b[7], STORE_FORMAT_VERSION);
        b[7] = STORE_FORMAT_VERSION + 1;
        fs::write(&p, b).unwrap();
    }
    let message = corrupt_message(store.load(&key(0)).unwrap());
    assert!(
        message.contains(&format!(
            "store format version {}",
            STORE_FORMAT_VERSION + 1
        )),
        "{message}"
    );
    assert!(!store.object_path(&key(0)).exists());
    assert_eq!(store.load(&key(0)).unwrap(), Lookup::Miss);
    // Further old entries: silently discarded (one notice is enough), never misread.
    assert_eq!(store.load(&key(1)).unwrap(), Lookup::Miss);
    assert!(!store.object_path(&key(1)).exists());
    // A new handle (a new run) gives the notice again, once.
    let store2 = Store::open(dir.path()).unwrap();
    assert!(matches!(
        store2.load(&key(2)).unwrap(),
        Lookup::Corrupt { .. }
    ));
    assert_eq!(store2.load(&key(2)).unwrap(), Lookup::Miss);
}

#[test]
fn records_round_trip_and_damaged_records_read_as_absent() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    // The record `name` of the namespace "last-key", and writing it.
    let get = |name: &str| store.get_record("last-key", name);
    let put = |name: &str, bytes: &[u8]| store.put_record("last-key", name, bytes).unwrap();
    assert_eq!(get("ortho[rec 0012]"), None);
    put("ortho[rec 0012]", b"abc");
    put("ortho[rec 0013]", b"");
    assert_eq!(get("ortho[rec 0012]").as_deref(), Some(&b"abc"[..]));
    assert_eq!(get("ortho[rec 0013]").as_deref(), Some(&b""[..]));
    assert_eq!(store.get_record("provenance", "ortho[rec 0012]"), None);
    put("ortho[rec 0012]", b"replaced");
    assert_eq!(get("ortho[rec 0012]").as_deref(), Some(&b"replaced"[..]));
    // Damage the record file: it reads as absent; a new put heals it.
    let ns = dir.path().join("records/last-key");
    let name_hash = blake3::hash(b"ortho[rec 0012]").to_hex().to_string();
    let p = ns.join(name_hash);
    let mut b = fs::read(&p).unwrap();
    let last = b.len() - 1;
    b[last] ^= 0xFF;
    fs::write(&p, &b).unwrap();
    assert_eq!(get("ortho[rec 0012]"), None);
    fs::write(&p, &b[..10]).unwrap();
    assert_eq!(get("ortho[rec 0012]"), None);
    put("ortho[rec 0012]", b"again");
    assert_eq!(get("ortho[rec 0012]").as_deref(), Some(&b"again"[..]));
    // Namespaces are plain folder names.
    for bad in ["", "../x", "a/b", ".hidden", "sp ace"] {
        assert!(
            matches!(
                store.put_record(bad, "n", b"x"),
                Err(StoreError::InvalidNamespace(_))
            ),
            "{bad}"
        );
        assert_eq!(store.get_record(bad, "n"), None);
    }
}

#[test]
fn oversized_metadata_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let err = store
        .save(&key(1), &meta(&"x".repeat(100_000)), b"p")
        .unwrap_err();
    assert!(err.to_string().contains("metadata"), "{err}");
    assert!(!store.contains(&key(1)));
}

#[test]
fn opening_a_store_on_a_file_names_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("not-a-dir");
    fs::write(&file, b"x").unwrap();
    let err = Store::open(&file)
        .err()
        .expect("opening a file as cache must fail");
    assert!(err.to_string().contains("not-a-dir"), "{err}");
}

#[test]
fn store_and_keys_can_be_shared_across_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Store>();
    assert_send_sync::<skytie::hashing::StatCache>();
    assert_send_sync::<skytie::store::RunLease>();
    assert_send_sync::<NodeKey>();
}

#[test]
fn an_unreadable_entry_is_reported_once_and_never_panics() {
    // A folder where the entry file should be: cannot be read (nor deleted as a file).
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).unwrap();
    let k = key(3);
    fs::create_dir_all(store.object_path(&k)).unwrap();
    let message = corrupt_message(store.load(&k).unwrap());
    assert!(message.contains(&k.to_string()), "{message}");
    assert_eq!(store.load(&k).unwrap(), Lookup::Miss, "reported twice");
    // Saving over it fails with an error naming the file, not a panic.
    let err = store.save(&k, &meta("m"), b"x").unwrap_err();
    assert!(err.to_string().contains(&k.to_string()[2..]), "{err}");
    // verify and stats look at entry files only.
    let report = store.verify().unwrap();
    assert_eq!(report.checked, 0, "a folder is not an entry file");
}

#[test]
fn entry_files_are_byte_identical_for_identical_saves() {
    // Two processes saving one key write the same bytes, so whichever rename wins, the entry is the same.
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let payload: Vec<u8> = (0..2_000_000u32).map(|i| (i % 253) as u8).collect();
    let (sa, sb) = (
        Store::open(a.path()).unwrap(),
        Store::open(b.path()).unwrap(),
    );
    sa.save(&key(5), &meta("same"), &payload).unwrap();
    sb.save(&key(5), &meta("same"), &payload).unwrap();
    let (fa, fb) = (
        fs::read(sa.object_path(&key(5))).unwrap(),
        fs::read(sb.object_path(&key(5))).unwrap(),
    );
    assert!(fa == fb);
    assert!(fa.ends_with(&payload));
}

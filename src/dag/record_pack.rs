//! Node records in packs: one pair of files per run that recorded anything, instead of one file per node, so
//! that a graph of a million nodes costs a few large reads and writes, not millions of small ones.
//!
//! A pack is `<cache>/records/packs/<stem>.rec` (the node records, JSON, one after the other) and
//! `<stem>.idx`, written last, which commits the pack: `"SKYPACK\0"` · format (u8) · count (u64) · `count`
//! entries of [`ENTRY_BYTES`] (name hash u64, node key, output hash, offset u64 and length u32 of the record
//! in `.rec`, first 16 bytes of the record's blake3) · blake3 of everything before (32). Stems sort in the
//! order packs were written (time in ns, process id, counter), and later packs win.
//!
//! The index is a hint, never trusted blindly: a damaged `.idx` is ignored as a whole (its nodes read their
//! artifacts, which are verified, and are recorded again); a record is only returned if its bytes match their
//! check and name the node asked for; an output hash from the index is only used for an entry that exists,
//! and any artifact that is read is verified against it. When more than [`MAX_PACKS`] packs exist, loading
//! merges them into one.

use crate::hashing::{ContentHash, NodeKey};
use crate::store::Store;
use std::collections::HashMap;
use std::fs::{self, File};
use std::hash::{BuildHasherDefault, Hasher};
use std::io::{self, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

const MAGIC: &[u8; 8] = b"SKYPACK\0";
const FORMAT: u8 = 1;
/// Bytes of one index entry.
pub const ENTRY_BYTES: usize = 8 + 32 + 32 + 8 + 4 + 16;
const HEAD_BYTES: usize = 8 + 1 + 8;
/// Loading merges the packs into one when there are more than this many.
pub const MAX_PACKS: usize = 16;
/// A `.rec` file without its `.idx` this old is the remains of a killed run.
const ORPHAN_AGE: Duration = Duration::from_secs(3600);

static PACK_COUNTER: AtomicU64 = AtomicU64::new(0);

/// A hasher for keys that are already uniformly distributed hashes: takes their first 8 bytes.
#[derive(Default)]
pub struct PreHashed(u64);

impl Hasher for PreHashed {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8).take(1) {
            let mut b = [0u8; 8];
            b[..chunk.len()].copy_from_slice(chunk);
            self.0 ^= u64::from_le_bytes(b);
        }
    }
    fn write_u64(&mut self, n: u64) {
        self.0 ^= n;
    }
    fn write_usize(&mut self, n: usize) {
        self.0 ^= n as u64;
    }
}

/// A `HashMap` keyed by hashes.
pub type HashKeyed<K, V> = HashMap<K, V, BuildHasherDefault<PreHashed>>;

/// The 64-bit name hash of a record name `stage[item]@variant` (`stage@variant` for a global node), computed
/// from its parts without building the string (FNV-1a, then a 64-bit finaliser).
pub fn name_hash(stage: &str, item: &str, variant: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |bytes: &[u8]| {
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    feed(stage.as_bytes());
    if !item.is_empty() {
        feed(b"[");
        feed(item.as_bytes());
        feed(b"]");
    }
    feed(b"@");
    feed(variant.as_bytes());
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    h
}

/// One index entry.
#[derive(Clone, Copy, Debug)]
struct Entry {
    name: u64,
    key: NodeKey,
    output: ContentHash,
    pack: u32,
    offset: u64,
    len: u32,
    check: [u8; 16],
}

impl Entry {
    fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.name.to_le_bytes());
        out.extend_from_slice(&self.key.0);
        out.extend_from_slice(&self.output.0);
        out.extend_from_slice(&self.offset.to_le_bytes());
        out.extend_from_slice(&self.len.to_le_bytes());
        out.extend_from_slice(&self.check);
    }
    fn decode(b: &[u8], pack: u32) -> Entry {
        let arr = |r: std::ops::Range<usize>| -> [u8; 32] { b[r].try_into().expect("32 bytes") };
        Entry {
            name: u64::from_le_bytes(b[0..8].try_into().expect("8 bytes")),
            key: ContentHash(arr(8..40)),
            output: ContentHash(arr(40..72)),
            pack,
            offset: u64::from_le_bytes(b[72..80].try_into().expect("8 bytes")),
            len: u32::from_le_bytes(b[80..84].try_into().expect("4 bytes")),
            check: b[84..100].try_into().expect("16 bytes"),
        }
    }
}

fn packs_dir(store: &Store) -> PathBuf {
    store.root().join("records").join("packs")
}

/// The loaded index of every pack: the latest record of each node name, and the output hash of each key. Only
/// each entry's key and output hash stay in memory (64 bytes), found by two maps of 8-byte hashes to entry
/// ordinals; where a record lies in its pack is read again from the index file when a record is wanted.
#[derive(Default)]
pub struct RecordIndex {
    /// Key and output hash of every entry, by ordinal.
    outputs: Vec<(NodeKey, ContentHash)>,
    /// Ordinal of each pack's first entry.
    bases: Vec<u32>,
    /// Name hash → ordinal of its latest entry.
    by_name: HashKeyed<u64, u32>,
    /// First 8 bytes of a key → ordinal of an entry of that key (checked against the whole key on use).
    by_key: HashKeyed<u64, u32>,
    /// Index file (stem) of each pack.
    packs: Vec<PathBuf>,
}

fn key_prefix(key: &NodeKey) -> u64 {
    u64::from_le_bytes(key.0[..8].try_into().expect("8 bytes"))
}

impl RecordIndex {
    /// Loads the index of every pack in `store` (merging them first when there are too many). Unreadable or
    /// damaged packs are skipped.
    pub fn load(store: &Store) -> RecordIndex {
        let dir = packs_dir(store);
        let stems = list_stems(&dir);
        let mut index = RecordIndex::default();
        for stem in &stems {
            index.add_pack(&dir, stem);
        }
        if stems.len() > MAX_PACKS {
            // Best effort: a failed merge leaves the packs as they are.
            if let Ok(merged) = index.merge_into_one(&dir, &stems) {
                return merged;
            }
        }
        index
    }

    fn add_pack(&mut self, dir: &Path, stem: &str) {
        let path = dir.join(format!("{stem}.idx"));
        let Ok(bytes) = fs::read(&path) else {
            return;
        };
        let Some(range) = verified_body(&bytes) else {
            return;
        };
        let body = &bytes[range];
        let count = body.len() / ENTRY_BYTES;
        let base = self.outputs.len();
        if u32::try_from(base + count).is_err() {
            return;
        }
        self.outputs.reserve_exact(count);
        self.by_name.reserve(count);
        self.by_key.reserve(count);
        for (i, chunk) in body.chunks_exact(ENTRY_BYTES).enumerate() {
            let e = Entry::decode(chunk, 0);
            let at = (base + i) as u32;
            self.by_name.insert(e.name, at);
            self.by_key.insert(key_prefix(&e.key), at);
            self.outputs.push((e.key, e.output));
        }
        self.bases.push(base as u32);
        self.packs.push(path);
    }

    /// The whole entry of ordinal `at`, read again from its pack's index file (and checked against memory).
    fn entry(&self, at: u32) -> Option<Entry> {
        let pack = self.bases.partition_point(|&b| b <= at).checked_sub(1)?;
        let i = (at - self.bases[pack]) as u64;
        let mut f = File::open(&self.packs[pack]).ok()?;
        f.seek(SeekFrom::Start(HEAD_BYTES as u64 + i * ENTRY_BYTES as u64))
            .ok()?;
        let mut b = [0u8; ENTRY_BYTES];
        f.read_exact(&mut b).ok()?;
        let e = Entry::decode(&b, pack as u32);
        (self.outputs.get(at as usize) == Some(&(e.key, e.output))).then_some(e)
    }

    /// The `.rec` file of pack `pack`.
    fn rec_file(&self, pack: u32) -> PathBuf {
        self.packs[pack as usize].with_extension("rec")
    }

    /// Number of entries loaded.
    pub fn len(&self) -> usize {
        self.outputs.len()
    }

    /// True when no pack was loaded.
    pub fn is_empty(&self) -> bool {
        self.outputs.is_empty()
    }

    /// The key and output hash of the latest record of node name hash `name`.
    pub fn latest(&self, name: u64) -> Option<(NodeKey, ContentHash)> {
        self.outputs
            .get(*self.by_name.get(&name)? as usize)
            .copied()
    }

    /// The ordinal of an entry of `key` (see [`crate::dag::objects_listing`]).
    pub fn position_of(&self, key: &NodeKey) -> Option<u32> {
        let at = *self.by_key.get(&key_prefix(key))?;
        (self.outputs.get(at as usize)?.0 == *key).then_some(at)
    }

    /// The output hash recorded for `key` by any node.
    pub fn output_of(&self, key: &NodeKey) -> Option<ContentHash> {
        Some(self.outputs[self.position_of(key)? as usize].1)
    }

    /// The bytes of the latest record of node `stage_item` (`stage[item]`) in `variant`, read from its pack
    /// and checked against the index (the caller checks that they name this node: the name hash is 64 bits).
    pub fn record_bytes(&self, stage_item: &str, variant: &str) -> Option<Vec<u8>> {
        let (stage, item) = split_identity(stage_item);
        let e = self.entry(*self.by_name.get(&name_hash(stage, item, variant))?)?;
        read_record(&self.rec_file(e.pack), &e)
    }

    /// Writes one pack holding the latest entry of every name, then removes the packs `stems`.
    fn merge_into_one(&self, dir: &Path, stems: &[String]) -> io::Result<RecordIndex> {
        let mut latest: Vec<u32> = self.by_name.values().copied().collect();
        latest.sort_unstable();
        let mut writer = PackWriter::create(dir)?;
        for &at in &latest {
            let Some(e) = self.entry(at) else { continue };
            if let Some(bytes) = read_record(&self.rec_file(e.pack), &e) {
                writer.push(e.name, e.key, e.output, &bytes)?;
            }
        }
        writer.finish()?;
        for stem in stems {
            let _ = fs::remove_file(dir.join(format!("{stem}.idx")));
            let _ = fs::remove_file(dir.join(format!("{stem}.rec")));
        }
        let mut merged = RecordIndex::default();
        for stem in list_stems(dir) {
            merged.add_pack(dir, &stem);
        }
        Ok(merged)
    }
}

/// `stage[item]` → (`stage`, `item`); a global node's identity is its stage.
fn split_identity(identity: &str) -> (&str, &str) {
    match identity.split_once('[') {
        Some((stage, rest)) if rest.ends_with(']') => (stage, &rest[..rest.len() - 1]),
        _ => (identity, ""),
    }
}

/// Where the entries of a pack's index file are, after checking its magic, format, length and checksum.
fn verified_body(bytes: &[u8]) -> Option<std::ops::Range<usize>> {
    if bytes.len() < HEAD_BYTES + 32 || &bytes[..8] != MAGIC || bytes[8] != FORMAT {
        return None;
    }
    let count = u64::from_le_bytes(bytes[9..17].try_into().ok()?) as usize;
    let end = HEAD_BYTES.checked_add(count.checked_mul(ENTRY_BYTES)?)?;
    if bytes.len() != end + 32 || blake3::hash(&bytes[..end]).as_bytes() != &bytes[end..] {
        return None;
    }
    Some(HEAD_BYTES..end)
}

fn read_record(rec_file: &Path, e: &Entry) -> Option<Vec<u8>> {
    let mut f = File::open(rec_file).ok()?;
    f.seek(SeekFrom::Start(e.offset)).ok()?;
    let mut bytes = vec![0u8; e.len as usize];
    f.read_exact(&mut bytes).ok()?;
    (blake3::hash(&bytes).as_bytes()[..16] == e.check).then_some(bytes)
}

/// Stems of the committed packs (those with an `.idx`), oldest first; removes `.rec` files of killed runs.
fn list_stems(dir: &Path) -> Vec<String> {
    let Ok(read) = fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut idx = Vec::new();
    let mut rec = Vec::new();
    for e in read.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if let Some(stem) = name.strip_suffix(".idx") {
            idx.push(stem.to_string());
        } else if let Some(stem) = name.strip_suffix(".rec") {
            rec.push((stem.to_string(), e.path()));
        }
    }
    idx.sort();
    for (stem, path) in rec {
        let old = fs::metadata(&path)
            .and_then(|m| m.modified())
            .is_ok_and(|t| t.elapsed().is_ok_and(|age| age > ORPHAN_AGE));
        if old && idx.binary_search(&stem).is_err() {
            let _ = fs::remove_file(path);
        }
    }
    idx
}

/// Writes one pack: records are streamed to `.rec` as they come, the index is written (and the pack
/// committed) by [`PackWriter::finish`].
pub struct PackWriter {
    dir: PathBuf,
    stem: String,
    rec: BufWriter<File>,
    offset: u64,
    index: Vec<u8>,
    count: u64,
}

impl PackWriter {
    /// Starts a new pack in `dir`.
    fn create(dir: &Path) -> io::Result<PackWriter> {
        fs::create_dir_all(dir)?;
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0);
        let stem = format!(
            "{now:024}-{}-{}",
            std::process::id(),
            PACK_COUNTER.fetch_add(1, Ordering::Relaxed)
        );
        let rec = BufWriter::with_capacity(1 << 20, File::create(dir.join(format!("{stem}.rec")))?);
        Ok(PackWriter {
            dir: dir.to_path_buf(),
            stem,
            rec,
            offset: 0,
            index: Vec::new(),
            count: 0,
        })
    }

    /// Starts a new pack in `store`.
    pub fn open(store: &Store) -> io::Result<PackWriter> {
        PackWriter::create(&packs_dir(store))
    }

    /// Adds the record `bytes` of the node of name hash `name`, which computed `output` under `key`.
    pub fn push(
        &mut self,
        name: u64,
        key: NodeKey,
        output: ContentHash,
        bytes: &[u8],
    ) -> io::Result<()> {
        let len =
            u32::try_from(bytes.len()).map_err(|_| io::Error::other("node record over 4 GiB"))?;
        self.rec.write_all(bytes)?;
        let e = Entry {
            name,
            key,
            output,
            pack: 0,
            offset: self.offset,
            len,
            check: blake3::hash(bytes).as_bytes()[..16]
                .try_into()
                .expect("16 bytes"),
        };
        e.encode(&mut self.index);
        self.offset += bytes.len() as u64;
        self.count += 1;
        Ok(())
    }

    /// Number of records pushed.
    pub fn len(&self) -> u64 {
        self.count
    }

    /// True when nothing was pushed.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Writes the index and so commits the pack; an empty pack is removed instead.
    pub fn finish(mut self) -> io::Result<()> {
        self.rec.flush()?;
        let rec_path = self.dir.join(format!("{}.rec", self.stem));
        if self.count == 0 {
            return fs::remove_file(rec_path);
        }
        self.rec.get_ref().sync_all()?;
        let mut head = Vec::with_capacity(HEAD_BYTES);
        head.extend_from_slice(MAGIC);
        head.push(FORMAT);
        head.extend_from_slice(&self.count.to_le_bytes());
        let mut hasher = blake3::Hasher::new();
        hasher.update(&head);
        hasher.update(&self.index);
        let check = hasher.finalize();
        let idx_path = self.dir.join(format!("{}.idx", self.stem));
        skytie_util::fsutil::atomic_write_with(&idx_path, |w| {
            w.write_all(&head)?;
            w.write_all(&self.index)?;
            w.write_all(check.as_bytes())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hashing::hash_bytes;

    fn record(identity: &str, key: NodeKey) -> Vec<u8> {
        format!("{identity} {key}").into_bytes()
    }

    #[test]
    fn later_packs_win_damaged_index_is_ignored_and_many_packs_merge() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let name = name_hash("s", "a", "default");
        let (k1, k2, o1, o2) = (
            hash_bytes(b"k1"),
            hash_bytes(b"k2"),
            hash_bytes(b"o1"),
            hash_bytes(b"o2"),
        );
        for (k, o) in [(k1, o1), (k2, o2)] {
            let mut w = PackWriter::open(&store).unwrap();
            w.push(name, k, o, &record("s[a]", k)).unwrap();
            w.finish().unwrap();
        }
        let index = RecordIndex::load(&store);
        assert_eq!(index.latest(name), Some((k2, o2)));
        assert_eq!(index.output_of(&k1), Some(o1));
        assert_eq!(
            index.record_bytes("s[a]", "default").unwrap(),
            record("s[a]", k2)
        );
        assert!(index.record_bytes("s[b]", "default").is_none());
        // Damage the newest index: its entries are ignored, the older pack still answers.
        let dir_p = packs_dir(&store);
        let newest = list_stems(&dir_p).pop().unwrap();
        let idx = dir_p.join(format!("{newest}.idx"));
        let mut bytes = fs::read(&idx).unwrap();
        bytes[HEAD_BYTES + 3] ^= 1;
        fs::write(&idx, bytes).unwrap();
        assert_eq!(RecordIndex::load(&store).latest(name), Some((k1, o1)));
        // More than MAX_PACKS packs are merged into one, keeping the latest record of each name.
        for i in 0..MAX_PACKS + 1 {
            let mut w = PackWriter::open(&store).unwrap();
            let k = hash_bytes(&[i as u8]);
            w.push(name, k, o1, &record("s[a]", k)).unwrap();
            w.finish().unwrap();
        }
        let merged = RecordIndex::load(&store);
        assert_eq!(list_stems(&dir_p).len(), 1);
        let last = hash_bytes(&[MAX_PACKS as u8]);
        assert_eq!(merged.latest(name), Some((last, o1)));
        assert_eq!(
            merged.record_bytes("s[a]", "default").unwrap(),
            record("s[a]", last)
        );
    }
}

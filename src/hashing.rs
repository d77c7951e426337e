//! Content hashing for the engine: [`ContentHash`] (blake3), hashing of byte buffers and files, the node-key
//! builder [`KeyBuilder`] and the persisted [`StatCache`] that avoids re-reading unchanged input files.
//!
//! A node's key is blake3 over its stage name, stage version, canonical parameter bytes and the labelled keys or
//! content hashes of its inputs. Every ingredient is tagged and length-prefixed, so two different splits of the
//! same bytes into ingredients can never produce the same key.

use std::collections::HashMap;
use std::fmt;
use std::fs;
use std::io;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

/// Inputs at least this large are hashed with blake3's multi-threaded (rayon) tree hashing.
pub const RAYON_THRESHOLD_BYTES: usize = 1 << 20;

/// A 32-byte blake3 digest of some content. Displayed (and serialised in human-readable formats such as JSON)
/// as 64 lowercase hex characters; serialised as 32 raw bytes in binary formats.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct ContentHash(pub [u8; 32]);

/// A DAG node's cache key (the hash of everything that determines the node's result).
pub type NodeKey = ContentHash;

/// Why a string is not a valid [`ContentHash`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{text}` is not a content hash: expected 64 hex characters ({reason})")]
pub struct ParseHashError {
    pub text: String,
    pub reason: &'static str,
}

impl ContentHash {
    /// The hash as 64 lowercase hex characters (same as `Display`).
    pub fn to_hex(&self) -> String {
        self.to_string()
    }

    /// Parses 64 hex characters (either case).
    pub fn from_hex(text: &str) -> Result<ContentHash, ParseHashError> {
        let err = |reason| ParseHashError {
            text: text.chars().take(80).collect(),
            reason,
        };
        let bytes = text.as_bytes();
        if bytes.len() != 64 {
            return Err(err("wrong length"));
        }
        let mut out = [0u8; 32];
        for (i, pair) in bytes.chunks_exact(2).enumerate() {
            let hi = hex_value(pair[0]).ok_or_else(|| err("non-hex character"))?;
            let lo = hex_value(pair[1]).ok_or_else(|| err("non-hex character"))?;
            out[i] = (hi << 4) | lo;
        }
        Ok(ContentHash(out))
    }

    /// The raw digest bytes.
    pub fn as_bytes(&self) -> &[u8; 32] {
        &self.0
    }
}

fn hex_value(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'a'..=b'f' => Some(c - b'a' + 10),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    }
}

impl fmt::Display for ContentHash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const HEX: &[u8; 16] = b"0123456789abcdef";
        let mut buf = [0u8; 64];
        for (i, b) in self.0.iter().enumerate() {
            buf[2 * i] = HEX[(b >> 4) as usize];
            buf[2 * i + 1] = HEX[(b & 15) as usize];
        }
        // The buffer holds only ASCII hex digits.
        f.write_str(std::str::from_utf8(&buf).map_err(|_| fmt::Error)?)
    }
}

impl fmt::Debug for ContentHash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ContentHash({self})")
    }
}

impl FromStr for ContentHash {
    type Err = ParseHashError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ContentHash::from_hex(s)
    }
}

impl From<blake3::Hash> for ContentHash {
    fn from(h: blake3::Hash) -> Self {
        ContentHash(*h.as_bytes())
    }
}

impl Serialize for ContentHash {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        if serializer.is_human_readable() {
            serializer.collect_str(self)
        } else {
            self.0.serialize(serializer)
        }
    }
}

impl<'de> Deserialize<'de> for ContentHash {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        if deserializer.is_human_readable() {
            let text = String::deserialize(deserializer)?;
            ContentHash::from_hex(&text).map_err(serde::de::Error::custom)
        } else {
            <[u8; 32]>::deserialize(deserializer).map(ContentHash)
        }
    }
}

/// blake3 of `bytes`; inputs of 1 MiB or more are hashed on the rayon pool (same digest, just faster).
pub fn hash_bytes(bytes: &[u8]) -> ContentHash {
    if bytes.len() >= RAYON_THRESHOLD_BYTES {
        let mut hasher = blake3::Hasher::new();
        hasher.update_rayon(bytes);
        hasher.finalize().into()
    } else {
        blake3::hash(bytes).into()
    }
}

/// blake3 of the content of the file at `path`, memory-mapped and hashed on the rayon pool (small files and
/// files that cannot be mapped are read normally). The file must not be truncated while it is being hashed.
pub fn hash_file(path: &Path) -> io::Result<ContentHash> {
    let mut hasher = blake3::Hasher::new();
    hasher.update_mmap_rayon(path)?;
    Ok(hasher.finalize().into())
}

/// Domain-separation context of node keys (blake3 key-derivation mode); bump the suffix to invalidate all keys.
const KEY_CONTEXT: &str = "skytie 2026-11 node key v1";

const TAG_STAGE: u8 = 1;
const TAG_VERSION: u8 = 2;
const TAG_PARAMS: u8 = 3;
const TAG_INPUT: u8 = 4;
const TAG_END: u8 = 0xFF;

/// Builds a [`NodeKey`] from a node's ingredients:
/// `KeyBuilder::new(stage, version).params(&bytes).input("label", &hash).finish()`.
///
/// Each ingredient is written as a tag byte followed by length-prefixed fields (u64 little-endian lengths), so
/// the encoding is prefix-free: params `"ab"` + input label `"c"` and params `"a"` + input label `"bc"` differ.
/// Ingredients are hashed in call order (callers add inputs in a fixed order).
#[derive(Clone)]
pub struct KeyBuilder {
    hasher: blake3::Hasher,
}

impl KeyBuilder {
    /// Starts a key for `stage_name` at `stage_version` (anything displayable: `"2"`, `2u32`, `"2.1"`).
    pub fn new(stage_name: &str, stage_version: impl fmt::Display) -> KeyBuilder {
        let mut builder = KeyBuilder {
            hasher: blake3::Hasher::new_derive_key(KEY_CONTEXT),
        };
        builder.field(TAG_STAGE, stage_name.as_bytes());
        builder.field(TAG_VERSION, stage_version.to_string().as_bytes());
        builder
    }

    fn field(&mut self, tag: u8, bytes: &[u8]) {
        self.hasher.update(&[tag]);
        self.hasher.update(&(bytes.len() as u64).to_le_bytes());
        self.hasher.update(bytes);
    }

    /// Adds the canonical parameter bytes (from [`crate::codec::encode_params`]).
    pub fn params(mut self, canonical_param_bytes: &[u8]) -> KeyBuilder {
        self.field(TAG_PARAMS, canonical_param_bytes);
        self
    }

    /// Adds an input: its label (e.g. the input port name) and its node key or content hash.
    pub fn input(mut self, label: &str, hash: &ContentHash) -> KeyBuilder {
        self.field(TAG_INPUT, label.as_bytes());
        self.hasher.update(&hash.0);
        self
    }

    /// The key.
    pub fn finish(mut self) -> NodeKey {
        self.hasher.update(&[TAG_END]);
        self.hasher.finalize().into()
    }
}

/// Identity of a file's current version as seen by `stat`: if any of these changed the file is re-hashed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
struct FileStamp {
    size: u64,
    mtime_ns: i128,
    ctime_ns: i128,
    inode: u64,
    device: u64,
}

impl FileStamp {
    fn of(meta: &fs::Metadata) -> FileStamp {
        let mtime_ns = meta.modified().map(system_time_ns).unwrap_or(0);
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            FileStamp {
                size: meta.len(),
                mtime_ns,
                ctime_ns: meta.ctime() as i128 * 1_000_000_000 + meta.ctime_nsec() as i128,
                inode: meta.ino(),
                device: meta.dev(),
            }
        }
        #[cfg(not(unix))]
        {
            FileStamp {
                size: meta.len(),
                mtime_ns,
                ctime_ns: 0,
                inode: 0,
                device: 0,
            }
        }
    }
}

/// Nanoseconds since the Unix epoch (negative before it).
pub(crate) fn system_time_ns(t: SystemTime) -> i128 {
    match t.duration_since(UNIX_EPOCH) {
        Ok(d) => d.as_nanos() as i128,
        Err(e) => -(e.duration().as_nanos() as i128),
    }
}

/// A file modified less than this before it was hashed is not remembered: a later write within the file
/// system's timestamp granularity could leave size and mtime unchanged ("racy" entries, as in git's index).
const RACY_WINDOW: Duration = Duration::from_secs(2);

const STAT_CACHE_FILE: &str = "stat-cache.bin";
const STAT_CACHE_MAGIC: &[u8; 8] = b"SKYSTAT\0";
const STAT_CACHE_VERSION: u8 = 1;

#[derive(Serialize, Deserialize)]
struct StatRecord {
    path: Vec<u8>,
    stamp: FileStamp,
    hash: ContentHash,
}

/// Remembers `(path, size, mtime, ctime, inode, device) → content hash` of raw input files so an unchanged
/// file is not read again; persisted at `<cache root>/stat-cache.bin`. A missing or corrupt file just starts an
/// empty cache. Files modified within 2 s before hashing are not remembered (their stamp could be ambiguous).
pub struct StatCache {
    file: PathBuf,
    entries: Mutex<HashMap<PathBuf, (FileStamp, ContentHash)>>,
    files_hashed: AtomicU64,
}

impl StatCache {
    /// Loads `<root>/stat-cache.bin` (an unreadable or corrupt file gives an empty cache, rebuilt on `save`).
    pub fn open(root: &Path) -> StatCache {
        let file = root.join(STAT_CACHE_FILE);
        let entries = fs::read(&file)
            .ok()
            .and_then(|bytes| decode_stat_cache(&bytes))
            .unwrap_or_default();
        StatCache {
            file,
            entries: Mutex::new(entries),
            files_hashed: AtomicU64::new(0),
        }
    }

    /// Content hash of the file at `path`; reads the file only if its stat stamp differs from the remembered one.
    pub fn hash_file(&self, path: &Path) -> io::Result<ContentHash> {
        let key = fs::canonicalize(path)?;
        let before = FileStamp::of(&fs::metadata(&key)?);
        if let Some((stamp, hash)) = self.lock().get(&key) {
            if *stamp == before {
                return Ok(*hash);
            }
        }
        let started_ns = system_time_ns(SystemTime::now());
        let hash = hash_file(&key)?;
        self.files_hashed.fetch_add(1, Ordering::Relaxed);
        let after = FileStamp::of(&fs::metadata(&key)?);
        let settled = before.mtime_ns <= started_ns - RACY_WINDOW.as_nanos() as i128;
        let mut entries = self.lock();
        if after == before && settled {
            entries.insert(key, (before, hash));
        } else {
            entries.remove(&key);
        }
        Ok(hash)
    }

    /// How many files this instance actually read and hashed (cache misses) since it was opened.
    pub fn files_hashed(&self) -> u64 {
        self.files_hashed.load(Ordering::Relaxed)
    }

    /// Number of remembered files.
    pub fn len(&self) -> usize {
        self.lock().len()
    }

    /// True when no file is remembered.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Writes the cache atomically to `<root>/stat-cache.bin` (entries in path order, so the file is
    /// deterministic), forgetting files that no longer exist.
    pub fn save(&self) -> io::Result<()> {
        let bytes = {
            let mut entries = self.lock();
            // Forget files that no longer exist, so the cache does not grow forever.
            entries.retain(|path, _| fs::symlink_metadata(path).is_ok());
            let mut records: Vec<StatRecord> = entries
                .iter()
                .map(|(path, (stamp, hash))| StatRecord {
                    path: path_bytes(path),
                    stamp: *stamp,
                    hash: *hash,
                })
                .collect();
            records.sort_by(|a, b| a.path.cmp(&b.path));
            encode_stat_cache(&records)?
        };
        skytie_util::fsutil::atomic_write(&self.file, &bytes)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<PathBuf, (FileStamp, ContentHash)>> {
        // A panic while holding the lock cannot leave the map inconsistent (single insert/remove), so recover.
        self.entries
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

#[cfg(unix)]
fn path_bytes(path: &Path) -> Vec<u8> {
    use std::os::unix::ffi::OsStrExt;
    path.as_os_str().as_bytes().to_vec()
}

#[cfg(unix)]
fn path_from_bytes(bytes: Vec<u8>) -> Option<PathBuf> {
    use std::os::unix::ffi::OsStringExt;
    Some(PathBuf::from(std::ffi::OsString::from_vec(bytes)))
}

#[cfg(not(unix))]
fn path_bytes(path: &Path) -> Vec<u8> {
    path.to_string_lossy().into_owned().into_bytes()
}

#[cfg(not(unix))]
fn path_from_bytes(bytes: Vec<u8>) -> Option<PathBuf> {
    String::from_utf8(bytes).ok().map(PathBuf::from)
}

/// Layout: magic, version byte, bincode(records), blake3 of everything before it.
fn encode_stat_cache(records: &[StatRecord]) -> io::Result<Vec<u8>> {
    let mut out = Vec::new();
    out.extend_from_slice(STAT_CACHE_MAGIC);
    out.push(STAT_CACHE_VERSION);
    crate::codec::encode_serde_into(&records, &mut out).map_err(io::Error::other)?;
    let check = blake3::hash(&out);
    out.extend_from_slice(check.as_bytes());
    Ok(out)
}

fn decode_stat_cache(bytes: &[u8]) -> Option<HashMap<PathBuf, (FileStamp, ContentHash)>> {
    let head = STAT_CACHE_MAGIC.len() + 1;
    if bytes.len() < head + 32 || &bytes[..STAT_CACHE_MAGIC.len()] != STAT_CACHE_MAGIC {
        return None;
    }
    if bytes[STAT_CACHE_MAGIC.len()] != STAT_CACHE_VERSION {
        return None;
    }
    let (body, check) = bytes.split_at(bytes.len() - 32);
    if blake3::hash(body).as_bytes() != check {
        return None;
    }
    let records: Vec<StatRecord> = crate::codec::decode_serde_exact(&body[head..]).ok()?;
    let mut map = HashMap::with_capacity(records.len());
    for r in records {
        map.insert(path_from_bytes(r.path)?, (r.stamp, r.hash));
    }
    Some(map)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_round_trip_and_errors() {
        let h = hash_bytes(b"abc");
        // blake3("abc") known answer (official test vector).
        assert_eq!(
            h.to_string(),
            "6437b3ac38465133ffb63b75273a8db548c558465d79db03fd359c6cd5bd9d85"
        );
        assert_eq!(ContentHash::from_hex(&h.to_string()).unwrap(), h);
        assert_eq!(
            ContentHash::from_hex(&h.to_string().to_uppercase()).unwrap(),
            h
        );
        assert!(ContentHash::from_hex("abc").is_err());
        assert!(ContentHash::from_hex(&"g".repeat(64)).is_err());
    }

    #[test]
    fn rayon_and_serial_hashing_agree() {
        let data: Vec<u8> = (0..(3 << 20) + 17)
            .map(|i: usize| (i * 31 % 251) as u8)
            .collect();
        assert_eq!(hash_bytes(&data), ContentHash::from(blake3::hash(&data)));
    }

    #[test]
    fn json_uses_hex_and_binary_uses_raw_bytes() {
        let h = hash_bytes(b"x");
        let json = serde_json::to_string(&h).unwrap();
        assert_eq!(json, format!("\"{h}\""));
        assert_eq!(serde_json::from_str::<ContentHash>(&json).unwrap(), h);
        let mut bin = Vec::new();
        crate::codec::encode_serde_into(&h, &mut bin).unwrap();
        assert_eq!(bin.len(), 32, "binary encoding is the raw digest");
        assert_eq!(
            crate::codec::decode_serde_exact::<ContentHash>(&bin).unwrap(),
            h
        );
    }
}

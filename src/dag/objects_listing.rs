//! Which of the keys the record index knows have an entry in the store, from one listing of the store's
//! entry folders instead of one `stat` per node: a plan of a million cached nodes reads a few thousand
//! directory blocks, not a million inodes. Nothing is read or trusted beyond the entry's existence: a node
//! whose output is needed still reads its entry, verified.
//!
//! A listing costs in proportion to the whole store, a `stat` per node in proportion to the graph: when the
//! store holds far more entries than the graph has nodes (a shared cache of many campaigns), no listing is
//! made and each node checks its own entry.

use crate::dag::record_pack::RecordIndex;
use crate::hashing::{ContentHash, NodeKey};
use crate::store::Store;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// A listing is made only while the store's estimated entry count is at most this many times the graph's
/// node count.
const MAX_STORE_TO_GRAPH: usize = 4;

/// The index entries whose store entry exists.
pub struct Present {
    present: Vec<bool>,
}

impl Present {
    /// Lists the store's entries when that is cheaper than checking `nodes` entries one by one; `None` when it
    /// is not (or the store cannot be listed).
    pub fn list(store: &Store, index: &RecordIndex, nodes: usize) -> Option<Present> {
        if index.is_empty() {
            return None;
        }
        let objects = objects_dir(store)?;
        // Entries spread evenly over the 256 folders (keys are hashes): one folder tells the store's size.
        let sample = std::fs::read_dir(objects.join("00")).map_or(0, |d| d.count());
        if sample * 256 > MAX_STORE_TO_GRAPH * nodes.max(index.len()) {
            return None;
        }
        let found: Vec<Vec<u32>> = (0..=255u8)
            .into_par_iter()
            .map(|shard| list_shard(&objects, shard, index))
            .collect();
        let mut present = vec![false; index.len()];
        for at in found.into_iter().flatten() {
            present[at as usize] = true;
        }
        Some(Present { present })
    }

    /// Whether the entry of `key` exists (false for a key the index does not know).
    pub fn contains(&self, index: &RecordIndex, key: &NodeKey) -> bool {
        index
            .position_of(key)
            .is_some_and(|at| self.present.get(at as usize).copied().unwrap_or(false))
    }
}

/// Marks entries used in a run (their modification time, which `cache gc` reads as last use) through open
/// handles on the store's 256 entry folders: one `utimensat` that resolves a single name inside an open folder
/// instead of the whole path from the root, and that tells at the same time whether the entry exists.
pub struct EntryMarker {
    objects: Option<PathBuf>,
    #[cfg(unix)]
    dirs: Vec<std::sync::OnceLock<Option<std::fs::File>>>,
}

impl EntryMarker {
    /// A marker for the entries of `store` (folders are opened on first use).
    pub fn new(store: &Store) -> EntryMarker {
        EntryMarker {
            objects: objects_dir(store),
            #[cfg(unix)]
            dirs: (0..256).map(|_| std::sync::OnceLock::new()).collect(),
        }
    }

    /// Whether the entry of `key` exists, marking it used now if so; `None` when this cannot tell (no such
    /// folder handle, or the entry may not be modified, e.g. a read-only shared cache): ask another way.
    pub fn mark(&self, key: &NodeKey) -> Option<bool> {
        #[cfg(unix)]
        {
            use std::os::unix::io::AsRawFd;
            let objects = self.objects.as_ref()?;
            let dir = self.dirs[key.0[0] as usize].get_or_init(|| {
                std::fs::File::open(objects.join(format!("{:02x}", key.0[0]))).ok()
            });
            let Some(dir) = dir else {
                // No folder: no entry of this prefix (yet).
                return Some(false);
            };
            let hex = key.to_string();
            let mut name = [0u8; 63];
            name[..62].copy_from_slice(&hex.as_bytes()[2..]);
            // SAFETY: `dir` is an open folder, `name` a NUL-terminated file name inside it; a null `times`
            // pointer means "now" for both access and modification time (POSIX utimensat).
            let rc = unsafe {
                libc::utimensat(dir.as_raw_fd(), name.as_ptr().cast(), std::ptr::null(), 0)
            };
            if rc == 0 {
                return Some(true);
            }
            match std::io::Error::last_os_error().kind() {
                std::io::ErrorKind::NotFound => Some(false),
                _ => None,
            }
        }
        #[cfg(not(unix))]
        {
            let _ = (key, &self.objects);
            None
        }
    }
}

/// The store's `objects/` folder (the grandparent of an entry path).
fn objects_dir(store: &Store) -> Option<PathBuf> {
    let sample = store.object_path(&ContentHash::default());
    Some(sample.parent()?.parent()?.to_path_buf())
}

/// Index positions of the keys with an entry in folder `shard` (2 hex digits).
fn list_shard(objects: &Path, shard: u8, index: &RecordIndex) -> Vec<u32> {
    let Ok(dir) = std::fs::read_dir(objects.join(format!("{shard:02x}"))) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for e in dir.flatten() {
        let name = e.file_name();
        let Some(key) = key_of(shard, name.as_encoded_bytes()) else {
            continue;
        };
        if let Some(at) = index.position_of(&key) {
            // A directory of that name is no entry (rare: not worth a stat for every file).
            if e.file_type().is_ok_and(|t| t.is_file()) {
                out.push(at);
            }
        }
    }
    out
}

/// The key of entry file `name` (62 lowercase hex digits) in folder `shard`.
fn key_of(shard: u8, name: &[u8]) -> Option<NodeKey> {
    if name.len() != 62 {
        return None;
    }
    let digit = |c: u8| match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'a'..=b'f' => Some(c - b'a' + 10),
        _ => None,
    };
    let mut key = [0u8; 32];
    key[0] = shard;
    for (i, pair) in name.chunks_exact(2).enumerate() {
        key[i + 1] = (digit(pair[0])? << 4) | digit(pair[1])?;
    }
    Some(ContentHash(key))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entry_names_parse_back_to_their_keys() {
        let key = crate::hashing::hash_bytes(b"k");
        let hex = key.to_string();
        assert_eq!(key_of(key.0[0], &hex.as_bytes()[2..]), Some(key));
        assert_eq!(key_of(key.0[0], b"zz"), None);
        assert_eq!(key_of(key.0[0], &hex.as_bytes()[1..]), None);
    }
}

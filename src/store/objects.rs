//! The `objects/` folder: entry paths from keys, listing of entry files, cleanup of left-over temporaries and
//! careful removal (only the file that was examined, not one a concurrent save just renamed into place).

use std::fs::{self, File};
use std::io;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use super::error::StoreError;
use super::lease::STALE_TEMP_AGE;
use crate::hashing::{ContentHash, NodeKey};

/// `<objects>/<first 2 hex>/<remaining 62 hex>`.
pub(crate) fn object_path(objects: &Path, key: &NodeKey) -> PathBuf {
    let hex = key.to_string();
    objects.join(&hex[..2]).join(&hex[2..])
}

/// One entry file found on disk.
#[derive(Clone, Debug)]
pub(crate) struct ObjectFile {
    pub key: NodeKey,
    pub path: PathBuf,
    pub bytes: u64,
    pub last_used: SystemTime,
}

/// Result of listing `objects/`.
pub(crate) struct Listing {
    /// Entry files, sorted by key.
    pub objects: Vec<ObjectFile>,
    /// Left-over temporaries older than an hour that were removed.
    pub temp_files_removed: usize,
}

/// Lists all entry files (sorted by key). Files with other names are ignored; temporaries of writes that died
/// more than an hour ago are removed.
pub(crate) fn list(objects: &Path) -> Result<Listing, StoreError> {
    let mut out = Vec::new();
    let mut temp_files_removed = 0;
    let shards = match fs::read_dir(objects) {
        Ok(d) => d,
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            return Ok(Listing {
                objects: out,
                temp_files_removed,
            });
        }
        Err(e) => return Err(StoreError::io("list", objects)(e)),
    };
    for shard in shards {
        let shard = shard.map_err(StoreError::io("list", objects))?;
        let shard_name = shard.file_name().to_string_lossy().into_owned();
        if shard_name.len() != 2 || !shard.path().is_dir() {
            continue;
        }
        let shard_path = shard.path();
        let files = match fs::read_dir(&shard_path) {
            Ok(d) => d,
            Err(e) if e.kind() == io::ErrorKind::NotFound => continue,
            Err(e) => return Err(StoreError::io("list", &shard_path)(e)),
        };
        for file in files {
            let file = file.map_err(StoreError::io("list", &shard_path))?;
            let name = file.file_name().to_string_lossy().into_owned();
            let Ok(meta) = file.metadata() else { continue }; // vanished meanwhile
            let modified = meta.modified().unwrap_or(SystemTime::UNIX_EPOCH);
            if name.starts_with('.') && name.ends_with(".tmp") {
                if modified.elapsed().is_ok_and(|age| age > STALE_TEMP_AGE)
                    && fs::remove_file(file.path()).is_ok()
                {
                    temp_files_removed += 1;
                }
                continue;
            }
            let Ok(key) = ContentHash::from_hex(&format!("{shard_name}{name}")) else {
                continue;
            };
            if !meta.is_file() {
                continue;
            }
            out.push(ObjectFile {
                key,
                path: file.path(),
                bytes: meta.len(),
                last_used: modified,
            });
        }
    }
    out.sort_by_key(|o| o.key);
    Ok(Listing {
        objects: out,
        temp_files_removed,
    })
}

/// Removes `path` if it is still the file `opened` (same device and inode); returns whether it is gone.
pub(crate) fn remove_if_same(path: &Path, opened: &File) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let same = match (opened.metadata(), fs::symlink_metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            (_, Err(e)) if e.kind() == io::ErrorKind::NotFound => return true,
            _ => false,
        };
        if !same {
            // A concurrent save replaced it with a fresh entry: keep that one.
            return true;
        }
    }
    #[cfg(not(unix))]
    let _ = opened;
    match fs::remove_file(path) {
        Ok(()) => true,
        Err(e) => e.kind() == io::ErrorKind::NotFound,
    }
}

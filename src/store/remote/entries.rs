//! Cache entries on the remote: `objects/<2 hex>/<62 hex>` holds the same bytes as the local entry file (header
//! with key and payload blake3, then the payload), so a downloaded entry is verified exactly like a local one —
//! header check, key, and blake3 of the whole payload against the hash in the header — before it is renamed
//! into the local cache. A generated folder of the key travels with it ([`super::dirs`]): uploaded before the
//! entry, downloaded and checked before the entry is installed, so a local entry always has its folder.

use std::fs::{self, File};
use std::io::{Seek, SeekFrom};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use super::backend::Remote;
use super::dirs;
use crate::hashing::NodeKey;
use crate::store::entry::{self, EntryFault, STORE_FORMAT_VERSION};
use crate::store::error::StoreError;

static FETCH_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Remote name of the entry of `key`.
pub(crate) fn entry_name(key: &NodeKey) -> String {
    let hex = key.to_string();
    format!("objects/{}/{}", &hex[..2], &hex[2..])
}

/// The key an entry name stands for, if it is one.
pub(crate) fn key_of(name: &str) -> Option<NodeKey> {
    let rest = name.strip_prefix("objects/")?;
    let (shard, tail) = rest.split_once('/')?;
    if shard.len() != 2 || tail.contains('/') {
        return None;
    }
    NodeKey::from_hex(&format!("{shard}{tail}")).ok()
}

/// Outcome of [`fetch`].
#[derive(Debug)]
pub(crate) enum Fetched {
    /// Downloaded, verified and installed at the local path.
    Installed,
    /// The remote has no entry of this key.
    Absent,
    /// The remote copy was damaged (the reason); it has been deleted from the remote, nothing was installed.
    Damaged(String),
}

/// Why a downloaded entry file cannot be used, or `None` if it is intact.
pub(crate) fn check_file(file: &mut File, key: &NodeKey) -> Result<Option<String>, std::io::Error> {
    file.seek(SeekFrom::Start(0))?;
    Ok(match entry::read_entry_with(file, key, |_, _| Ok(())) {
        Ok(_) => None,
        Err(EntryFault::Damaged(reason)) => Some(reason),
        Err(EntryFault::OtherFormat(v)) => Some(format!(
            "written by store format version {v}, this skytie uses {STORE_FORMAT_VERSION}"
        )),
        Err(EntryFault::Unreadable(e)) => return Err(e),
    })
}

/// Downloads the entry of `key` (and its generated folder, if it has one) into the local cache at
/// `local_path` (`dirs_root` for the folder). A damaged remote copy is deleted from the remote so the
/// recomputed result can take its place.
pub(crate) fn fetch(
    remote: &Remote,
    key: &NodeKey,
    local_path: &Path,
    dirs_root: &Path,
) -> Result<Fetched, StoreError> {
    let dir = local_path.parent().unwrap_or(Path::new("."));
    fs::create_dir_all(dir).map_err(StoreError::io("create cache folder", dir))?;
    let file_name = local_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(
        ".{file_name}.{}.{}.fetch.tmp",
        std::process::id(),
        FETCH_COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = fetch_into(remote, key, &tmp, local_path, dirs_root);
    let _ = fs::remove_file(&tmp);
    result
}

fn fetch_into(
    remote: &Remote,
    key: &NodeKey,
    tmp: &Path,
    local_path: &Path,
    dirs_root: &Path,
) -> Result<Fetched, StoreError> {
    let mut file = File::options()
        .read(true)
        .write(true)
        .create_new(true)
        .open(tmp)
        .map_err(StoreError::io("create", tmp))?;
    let name = entry_name(key);
    if !remote.get_to(&name, &mut file)? {
        return Ok(Fetched::Absent);
    }
    let damage = check_file(&mut file, key).map_err(StoreError::io("read the download", tmp))?;
    if let Some(reason) = damage {
        discard(remote, key)?;
        return Ok(Fetched::Damaged(reason));
    }
    if let Some(manifest) = remote.get_bytes(&dirs::manifest_name(key))? {
        if let Err(reason) = dirs::download(remote, key, &manifest, dirs_root)? {
            discard(remote, key)?;
            return Ok(Fetched::Damaged(format!("its generated folder: {reason}")));
        }
    }
    file.sync_all().map_err(StoreError::io("write", tmp))?;
    drop(file);
    fs::rename(tmp, local_path).map_err(StoreError::io("install the download at", local_path))?;
    Ok(Fetched::Installed)
}

/// Deletes the remote entry of `key` and its folder.
pub(crate) fn discard(remote: &Remote, key: &NodeKey) -> Result<(), StoreError> {
    remote.delete(&entry_name(key))?;
    dirs::delete(remote, key)?;
    Ok(())
}

/// Uploads the local entry of `key` at `local_path`, after its generated folder `<dirs_root>/<key>` if there
/// is one. The entry goes up with a conditional PUT: when another writer stored it first, that copy (the same
/// bytes: the name is the key of a deterministic result) is kept.
pub(crate) fn upload(
    remote: &Remote,
    key: &NodeKey,
    local_path: &Path,
    dirs_root: &Path,
) -> Result<(), StoreError> {
    let dir = dirs_root.join(key.to_string());
    if dir.is_dir() {
        dirs::upload(remote, key, &dir)?;
    }
    remote.put_file(&entry_name(key), local_path, true)?;
    Ok(())
}

//! Small side records (node identity → last key, provenance, run logs): atomic put/get of bytes by name under
//! `<root>/records/<namespace>/<blake3(name) hex>`.
//!
//! Layout: `"SKYREC\0"` · version (u8) · name length (u32) · name · payload length (u64) · payload blake3 (32)
//! · payload. A record that fails any check reads as absent (and is replaced by the next `put`). Records can
//! be removed (`remove`).

use std::fs;
use std::path::{Path, PathBuf};

use super::error::StoreError;
use crate::hashing::hash_bytes;

const MAGIC: &[u8; 7] = b"SKYREC\0";
const VERSION: u8 = 1;

fn valid_namespace(namespace: &str) -> bool {
    !namespace.is_empty()
        && namespace.len() <= 64
        && !namespace.starts_with('.')
        && namespace
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-' || b == b'.')
}

/// `<namespace>/<blake3(name) hex>`: the record's file below `records/` (locally and on a remote).
pub(crate) fn file_name(namespace: &str, name: &str) -> Result<String, StoreError> {
    if !valid_namespace(namespace) {
        return Err(StoreError::InvalidNamespace(namespace.to_string()));
    }
    Ok(format!(
        "{namespace}/{}",
        blake3::hash(name.as_bytes()).to_hex()
    ))
}

fn record_path(records: &Path, namespace: &str, name: &str) -> Result<PathBuf, StoreError> {
    Ok(records.join(file_name(namespace, name)?))
}

/// Writes a record; returns the file's bytes (what a remote stores too).
pub(crate) fn put(
    records: &Path,
    namespace: &str,
    name: &str,
    bytes: &[u8],
) -> Result<Vec<u8>, StoreError> {
    let path = record_path(records, namespace, name)?;
    let out = encode(name, bytes);
    skytie_util::fsutil::atomic_write(&path, &out)
        .map_err(StoreError::io("write record", &path))?;
    Ok(out)
}

/// The bytes of the record file of (`name`, `bytes`).
fn encode(name: &str, bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(MAGIC.len() + 1 + 4 + name.len() + 8 + 32 + bytes.len());
    out.extend_from_slice(MAGIC);
    out.push(VERSION);
    out.extend_from_slice(&(name.len() as u32).to_le_bytes());
    out.extend_from_slice(name.as_bytes());
    out.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    out.extend_from_slice(hash_bytes(bytes).as_bytes());
    out.extend_from_slice(bytes);
    out
}

/// The payload of the record file `file` if it is intact and holds the record `name`.
pub(crate) fn parse<'a>(file: &'a [u8], name: &str) -> Option<&'a [u8]> {
    parse_any(file).and_then(|(n, payload)| (n == name.as_bytes()).then_some(payload))
}

/// The name and payload of the record file `file` if it is intact.
pub(crate) fn parse_any(file: &[u8]) -> Option<(&[u8], &[u8])> {
    let rest = file.strip_prefix(MAGIC.as_slice())?;
    let (&version, rest) = rest.split_first()?;
    if version != VERSION {
        return None;
    }
    let name_len = u32::from_le_bytes(rest.get(..4)?.try_into().ok()?) as usize;
    let rest = &rest[4..];
    let name = rest.get(..name_len)?;
    let rest = &rest[name_len..];
    let payload_len = u64::from_le_bytes(rest.get(..8)?.try_into().ok()?);
    let hash = rest.get(8..40)?;
    let payload = &rest[40..];
    (payload.len() as u64 == payload_len && hash_bytes(payload).as_bytes() == hash)
        .then_some((name, payload))
}

/// Installs the record file `file` (checked to hold record `name`) fetched from a remote; returns its payload.
pub(crate) fn install(
    records: &Path,
    namespace: &str,
    name: &str,
    file: &[u8],
) -> Result<Option<Vec<u8>>, StoreError> {
    let Some(payload) = parse(file, name) else {
        return Ok(None);
    };
    let path = record_path(records, namespace, name)?;
    skytie_util::fsutil::atomic_write(&path, file)
        .map_err(StoreError::io("write record", &path))?;
    Ok(Some(payload.to_vec()))
}

pub(crate) fn get(records: &Path, namespace: &str, name: &str) -> Option<Vec<u8>> {
    let path = record_path(records, namespace, name).ok()?;
    let file = fs::read(&path).ok()?;
    // A corrupt record is left in place (a concurrent `put` may be replacing it right now); the next `put`
    // overwrites it.
    parse(&file, name).map(<[u8]>::to_vec)
}

/// Removes the record (`namespace`, `name`); returns whether there was one.
pub(crate) fn remove(records: &Path, namespace: &str, name: &str) -> Result<bool, StoreError> {
    let path = record_path(records, namespace, name)?;
    match fs::remove_file(&path) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(StoreError::io("remove record", &path)(e)),
    }
}

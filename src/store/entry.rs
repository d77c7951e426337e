//! The on-disk layout of one cache entry (`<root>/objects/<2 hex>/<62 hex>`), its writing and its verified
//! reading.
//!
//! Layout (integers little-endian):
//! `"SKYTIE\0"` (7 bytes) · store format version (u8) · node key (32) · meta length (u32) · meta (stage,
//! stage version, item: each u32 length + UTF-8) · payload length (u64) · payload blake3 (32) · header check
//! (first 8 bytes of blake3 of all preceding header bytes) · payload.
//!
//! The version byte sits right after the magic, so an entry of another store format is recognised before any
//! of the rest is interpreted.

use std::fs::File;
use std::io::{self, Read};

use serde::{Deserialize, Serialize};

use super::stream::HashingReader;
use crate::codec::CodecError;
use crate::hashing::{ContentHash, NodeKey};

/// Version of the entry layout above; bump it when the layout changes (old entries are then discarded).
pub const STORE_FORMAT_VERSION: u8 = 1;

pub(crate) const MAGIC: &[u8; 7] = b"SKYTIE\0";
/// Largest accepted metadata block.
pub(crate) const MAX_META_BYTES: usize = 64 * 1024;
/// magic + version + key + meta length.
const FIXED_HEAD: usize = 7 + 1 + 32 + 4;
/// payload length + payload hash + header check.
const TAIL_HEAD: usize = 8 + 32 + 8;

/// What produced an entry: shown by `skytie cache stats` and kept with the payload.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct EntryMeta {
    /// Stage name, e.g. `"ortho"`.
    pub stage: String,
    /// Stage version, e.g. `"3"`.
    pub stage_version: String,
    /// Node identity, e.g. `"ortho[rec 0012]"`.
    pub item: String,
}

impl EntryMeta {
    pub fn new(
        stage: impl Into<String>,
        stage_version: impl Into<String>,
        item: impl Into<String>,
    ) -> EntryMeta {
        EntryMeta {
            stage: stage.into(),
            stage_version: stage_version.into(),
            item: item.into(),
        }
    }
}

/// A parsed, self-consistent entry header.
#[derive(Clone, Debug)]
pub(crate) struct Header {
    pub key: NodeKey,
    pub meta: EntryMeta,
    pub payload_len: u64,
    pub payload_hash: ContentHash,
}

/// Why an entry file cannot be used.
#[derive(Debug)]
pub(crate) enum EntryFault {
    /// Written by another store format version.
    OtherFormat(u8),
    /// Damaged, truncated, not an entry, or holding the wrong key.
    Damaged(String),
    /// Reading failed.
    Unreadable(io::Error),
}

fn put_str(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(&(s.len() as u32).to_le_bytes());
    out.extend_from_slice(s.as_bytes());
}

/// Encodes the metadata block; `None` if it exceeds [`MAX_META_BYTES`] (the returned length says how big).
pub(crate) fn encode_meta(meta: &EntryMeta) -> Result<Vec<u8>, usize> {
    let mut out =
        Vec::with_capacity(12 + meta.stage.len() + meta.stage_version.len() + meta.item.len());
    put_str(&mut out, &meta.stage);
    put_str(&mut out, &meta.stage_version);
    put_str(&mut out, &meta.item);
    if out.len() > MAX_META_BYTES {
        Err(out.len())
    } else {
        Ok(out)
    }
}

/// The header bytes of an entry (everything before the payload).
pub(crate) fn encode_header(
    key: &NodeKey,
    meta_block: &[u8],
    payload_len: u64,
    payload_hash: &ContentHash,
) -> Vec<u8> {
    let mut out = Vec::with_capacity(FIXED_HEAD + meta_block.len() + TAIL_HEAD);
    out.extend_from_slice(MAGIC);
    out.push(STORE_FORMAT_VERSION);
    out.extend_from_slice(&key.0);
    out.extend_from_slice(&(meta_block.len() as u32).to_le_bytes());
    out.extend_from_slice(meta_block);
    out.extend_from_slice(&payload_len.to_le_bytes());
    out.extend_from_slice(&payload_hash.0);
    let check = blake3::hash(&out);
    out.extend_from_slice(&check.as_bytes()[..8]);
    out
}

fn take_str(block: &[u8], pos: &mut usize) -> Option<String> {
    let len = u32::from_le_bytes(block.get(*pos..*pos + 4)?.try_into().ok()?) as usize;
    let bytes = block.get(*pos + 4..(*pos + 4).checked_add(len)?)?;
    *pos += 4 + len;
    String::from_utf8(bytes.to_vec()).ok()
}

fn decode_meta(block: &[u8]) -> Option<EntryMeta> {
    let mut pos = 0;
    let meta = EntryMeta {
        stage: take_str(block, &mut pos)?,
        stage_version: take_str(block, &mut pos)?,
        item: take_str(block, &mut pos)?,
    };
    (pos == block.len()).then_some(meta)
}

fn read_exact_or_fault(
    file: &mut File,
    buf: &mut [u8],
    what: &str,
    file_len: u64,
) -> Result<(), EntryFault> {
    file.read_exact(buf).map_err(|e| {
        if e.kind() == io::ErrorKind::UnexpectedEof {
            EntryFault::Damaged(format!(
                "truncated: file of {file_len} bytes ends inside the {what}"
            ))
        } else {
            EntryFault::Unreadable(e)
        }
    })
}

/// Reads and checks the header of the open entry `file` of `file_len` bytes; the file position is left at the
/// start of the payload. Checks magic, version, header check and that the payload length matches the file size.
pub(crate) fn read_header(file: &mut File, file_len: u64) -> Result<Header, EntryFault> {
    if file_len == 0 {
        return Err(EntryFault::Damaged("empty file (0 bytes)".into()));
    }
    let mut fixed = [0u8; FIXED_HEAD];
    let magic_len = MAGIC.len() + 1;
    if file_len < magic_len as u64 {
        let mut short = vec![0u8; file_len as usize];
        read_exact_or_fault(file, &mut short, "header", file_len)?;
        return Err(EntryFault::Damaged(if MAGIC.starts_with(&short) {
            format!("truncated: only {file_len} bytes")
        } else {
            "not a skytie cache entry (bad magic)".into()
        }));
    }
    read_exact_or_fault(file, &mut fixed[..magic_len], "header", file_len)?;
    if &fixed[..MAGIC.len()] != MAGIC {
        return Err(EntryFault::Damaged(
            "not a skytie cache entry (bad magic)".into(),
        ));
    }
    if fixed[MAGIC.len()] != STORE_FORMAT_VERSION {
        return Err(EntryFault::OtherFormat(fixed[MAGIC.len()]));
    }
    read_exact_or_fault(file, &mut fixed[magic_len..], "header", file_len)?;
    let meta_len =
        u32::from_le_bytes(fixed[FIXED_HEAD - 4..].try_into().expect("4 bytes")) as usize;
    if meta_len > MAX_META_BYTES || (FIXED_HEAD + meta_len + TAIL_HEAD) as u64 > file_len {
        return Err(EntryFault::Damaged(format!(
            "header announces {meta_len} bytes of metadata, impossible in a file of {file_len} bytes (truncated or damaged)"
        )));
    }
    let mut rest = vec![0u8; meta_len + TAIL_HEAD];
    read_exact_or_fault(file, &mut rest, "header", file_len)?;
    let check_at = meta_len + TAIL_HEAD - 8;
    let mut hasher = blake3::Hasher::new();
    hasher.update(&fixed);
    hasher.update(&rest[..check_at]);
    if hasher.finalize().as_bytes()[..8] != rest[check_at..] {
        return Err(EntryFault::Damaged(
            "header check mismatch (header bytes damaged)".into(),
        ));
    }
    let meta = decode_meta(&rest[..meta_len])
        .ok_or_else(|| EntryFault::Damaged("metadata block is malformed".into()))?;
    let payload_len = u64::from_le_bytes(rest[meta_len..meta_len + 8].try_into().expect("8 bytes"));
    let payload_hash = ContentHash(
        rest[meta_len + 8..meta_len + 40]
            .try_into()
            .expect("32 bytes"),
    );
    let header_len = (FIXED_HEAD + meta_len + TAIL_HEAD) as u64;
    if header_len.checked_add(payload_len) != Some(file_len) {
        return Err(EntryFault::Damaged(format!(
            "payload should be {payload_len} bytes but the file holds {} after its header (truncated or damaged)",
            file_len - header_len
        )));
    }
    let key = NodeKey::from(blake3::Hash::from_bytes(
        fixed[8..40].try_into().expect("32 bytes"),
    ));
    Ok(Header {
        key,
        meta,
        payload_len,
        payload_hash,
    })
}

/// Reads the header of the open entry `file` (see [`read_header`]) and checks that the entry belongs to
/// `expected_key`; the file position is left at the start of the payload.
pub(crate) fn read_checked_header(
    file: &mut File,
    expected_key: &NodeKey,
) -> Result<Header, EntryFault> {
    let file_len = file.metadata().map_err(EntryFault::Unreadable)?.len();
    let header = read_header(file, file_len)?;
    if header.key != *expected_key {
        return Err(EntryFault::Damaged(format!(
            "entry holds key {} (misplaced file)",
            header.key
        )));
    }
    Ok(header)
}

/// Reads the entry in `file`: header (checked, see [`read_checked_header`]), then the payload through
/// `decode(source, payload_len)`, each byte read once and hashed on the way. The value is returned only if
/// the payload's hash matches the header. Bytes `decode` leaves unread are still read and hashed, so damage
/// (reported as such) is told apart from a decoder that rejects intact bytes.
pub(crate) fn read_entry_with<T>(
    file: &mut File,
    expected_key: &NodeKey,
    decode: impl FnOnce(&mut dyn Read, u64) -> Result<T, CodecError>,
) -> Result<(Header, T), EntryFault> {
    let header = read_checked_header(file, expected_key)?;
    let mut source = HashingReader::new(&mut *file, header.payload_len);
    let decoded = decode(&mut source, header.payload_len);
    if decoded.is_err() || source.remaining() > 0 {
        source.drain();
    }
    if let Some(e) = source.error() {
        return Err(EntryFault::Unreadable(io::Error::new(
            e.kind(),
            e.to_string(),
        )));
    }
    if source.remaining() > 0 {
        return Err(EntryFault::Damaged(format!(
            "truncated while reading: {} payload bytes missing",
            source.remaining()
        )));
    }
    let actual = source.finish();
    if actual != header.payload_hash {
        return Err(EntryFault::Damaged(format!(
            "payload hash mismatch (recorded {}, content {actual}): bytes damaged",
            header.payload_hash
        )));
    }
    match decoded {
        Ok(value) => Ok((header, value)),
        Err(e) => Err(EntryFault::Damaged(format!(
            "intact but cannot be decoded: {e}"
        ))),
    }
}

/// Reads the whole entry from the open `file` into memory and verifies it (see [`read_entry_with`]).
#[cfg(test)]
pub(crate) fn read_entry(
    file: &mut File,
    expected_key: &NodeKey,
) -> Result<(Header, Vec<u8>), EntryFault> {
    read_entry_with(file, expected_key, |source, len| {
        let mut payload = vec![0u8; len as usize];
        source
            .read_exact(&mut payload)
            .map_err(|e| CodecError(e.to_string()))?;
        Ok(payload)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hashing::hash_bytes;
    use std::io::Write;

    fn write_entry(dir: &std::path::Path, key: &NodeKey, payload: &[u8]) -> std::path::PathBuf {
        let meta = encode_meta(&EntryMeta::new("ortho", "2", "ortho[rec 0012]")).unwrap();
        let path = dir.join("e");
        let mut f = File::create(&path).unwrap();
        f.write_all(&encode_header(
            key,
            &meta,
            payload.len() as u64,
            &hash_bytes(payload),
        ))
        .unwrap();
        f.write_all(payload).unwrap();
        path
    }

    #[test]
    fn header_round_trip_and_every_single_byte_flip_is_detected() {
        let dir = tempfile::tempdir().unwrap();
        let key = hash_bytes(b"key");
        let path = write_entry(dir.path(), &key, b"payload bytes");
        let (h, payload) = read_entry(&mut File::open(&path).unwrap(), &key).unwrap();
        assert_eq!(payload, b"payload bytes");
        assert_eq!(h.meta, EntryMeta::new("ortho", "2", "ortho[rec 0012]"));
        let good = std::fs::read(&path).unwrap();
        for i in 0..good.len() {
            let mut bad = good.clone();
            bad[i] ^= 0x10;
            std::fs::write(&path, &bad).unwrap();
            let r = read_entry(&mut File::open(&path).unwrap(), &key);
            assert!(r.is_err(), "flip of byte {i} undetected");
        }
    }
}

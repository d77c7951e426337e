//! Generated folders (`<cache>/dirs/<key>/`, e.g. a synthetic campaign) on the remote: every file as its own
//! object `dirs/<key>/<relative path>`, then a manifest `dirs/<key>.manifest` listing relative path, size and
//! blake3 of each file. The manifest is uploaded last, with a conditional PUT, so a folder is visible on the
//! remote only once all its files are there; a download checks every file against it before the folder is
//! renamed into place, so a local folder is always complete and verified.
//!
//! Manifest (UTF-8 text): `skytie-dir 1` · one line `<blake3 hex> <bytes> <relative path>` per file, sorted by
//! path · `end <blake3 hex of all preceding bytes>`.

use std::fs::{self, File};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use super::backend::Remote;
use crate::hashing::{hash_bytes, hash_file, ContentHash, NodeKey};
use crate::store::error::StoreError;
use crate::store::stream::HashingWriter;

const HEADER: &str = "skytie-dir 1";

/// Remote name of the manifest of the folder of `key`.
pub(crate) fn manifest_name(key: &NodeKey) -> String {
    format!("dirs/{key}.manifest")
}

fn file_name(key: &NodeKey, rel: &str) -> String {
    format!("dirs/{key}/{rel}")
}

/// One file of a manifest.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct ManifestFile {
    pub rel: String,
    pub bytes: u64,
    pub hash: ContentHash,
}

/// Every file below `root` as (relative path with '/', absolute path), sorted by relative path.
fn walk(root: &Path) -> io::Result<Vec<(String, PathBuf)>> {
    fn go(root: &Path, dir: &Path, out: &mut Vec<(String, PathBuf)>) -> io::Result<()> {
        for entry in fs::read_dir(dir)? {
            let entry = entry?;
            let path = entry.path();
            if entry.file_type()?.is_dir() {
                go(root, &path, out)?;
            } else {
                let rel = path.strip_prefix(root).unwrap_or(&path);
                let parts: Option<Vec<&str>> =
                    rel.components().map(|c| c.as_os_str().to_str()).collect();
                let rel = parts
                    .ok_or_else(|| {
                        io::Error::new(
                            io::ErrorKind::InvalidData,
                            format!("{}: file name is not UTF-8", path.display()),
                        )
                    })?
                    .join("/");
                if rel.contains('\n') {
                    return Err(io::Error::new(
                        io::ErrorKind::InvalidData,
                        format!("{}: file name holds a line break", path.display()),
                    ));
                }
                out.push((rel, path));
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    go(root, root, &mut out)?;
    out.sort();
    Ok(out)
}

fn encode_manifest(files: &[ManifestFile]) -> Vec<u8> {
    let mut text = format!("{HEADER}\n");
    for f in files {
        text.push_str(&format!("{} {} {}\n", f.hash, f.bytes, f.rel));
    }
    let check = hash_bytes(text.as_bytes());
    text.push_str(&format!("end {check}\n"));
    text.into_bytes()
}

/// Parses and checks a manifest; the error says what is wrong with it.
pub(crate) fn parse_manifest(bytes: &[u8]) -> Result<Vec<ManifestFile>, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "manifest is not UTF-8".to_string())?;
    let body_end = text
        .trim_end_matches('\n')
        .rfind('\n')
        .map(|i| i + 1)
        .ok_or("manifest has no end line")?;
    let (body, end) = text.split_at(body_end);
    let recorded = end
        .trim_end()
        .strip_prefix("end ")
        .and_then(|h| ContentHash::from_hex(h).ok())
        .ok_or("manifest has no valid end line (truncated?)")?;
    if hash_bytes(body.as_bytes()) != recorded {
        return Err("manifest check mismatch (damaged)".into());
    }
    let mut lines = body.lines();
    if lines.next() != Some(HEADER) {
        return Err(format!("manifest does not start with `{HEADER}`"));
    }
    lines
        .map(|line| {
            let mut it = line.splitn(3, ' ');
            let (Some(h), Some(n), Some(rel)) = (it.next(), it.next(), it.next()) else {
                return Err(format!("malformed manifest line `{line}`"));
            };
            let safe = !rel.is_empty()
                && rel
                    .split('/')
                    .all(|p| !p.is_empty() && p != "." && p != "..");
            if !safe {
                return Err(format!("manifest names an unsafe path `{rel}`"));
            }
            Ok(ManifestFile {
                rel: rel.to_string(),
                bytes: n.parse().map_err(|_| format!("bad size in `{line}`"))?,
                hash: ContentHash::from_hex(h).map_err(|_| format!("bad hash in `{line}`"))?,
            })
        })
        .collect()
}

/// Uploads the folder `dir` of `key` unless the remote has its manifest already.
pub(crate) fn upload(remote: &Remote, key: &NodeKey, dir: &Path) -> Result<(), StoreError> {
    let manifest = manifest_name(key);
    if remote.exists(&manifest)? {
        return Ok(());
    }
    let files = walk(dir).map_err(StoreError::io("list the generated folder", dir))?;
    let mut listed = Vec::with_capacity(files.len());
    for (rel, path) in files {
        let hash = hash_file(&path).map_err(StoreError::io("hash for upload", &path))?;
        let bytes = fs::metadata(&path)
            .map_err(StoreError::io("hash for upload", &path))?
            .len();
        remote.put_file(&file_name(key, &rel), &path, false)?;
        listed.push(ManifestFile { rel, bytes, hash });
    }
    remote.put_bytes(&manifest, encode_manifest(&listed), true)?;
    Ok(())
}

/// Downloads the folder of `key` described by `manifest` into `<dirs_root>/<key>` (a temporary folder first,
/// renamed into place when every file matches). `Ok(Err(reason))` when the remote copy is damaged.
pub(crate) fn download(
    remote: &Remote,
    key: &NodeKey,
    manifest: &[u8],
    dirs_root: &Path,
) -> Result<Result<(), String>, StoreError> {
    let target = dirs_root.join(key.to_string());
    if target.is_dir() {
        return Ok(Ok(()));
    }
    let (tmp, result) = match fill_scratch(remote, key, manifest, dirs_root, "fetch") {
        Ok(filled) => filled,
        Err(reason) => return Ok(Err(reason)),
    };
    match result {
        Ok(Ok(())) => {
            if fs::rename(&tmp, &target).is_err() {
                // A concurrent download or run put the folder in place first: keep that one.
                let _ = fs::remove_dir_all(&tmp);
                if !target.is_dir() {
                    return Err(StoreError::io("move the downloaded folder to", &target)(
                        io::Error::other("rename failed"),
                    ));
                }
            }
            Ok(Ok(()))
        }
        other => {
            let _ = fs::remove_dir_all(&tmp);
            other
        }
    }
}

/// The outcome of downloading a folder's files: `Ok(Err(reason))` when the remote copy is damaged.
type Filled = Result<Result<(), String>, StoreError>;

/// The files of `manifest` downloaded into the fresh scratch folder `<root>/.<tag>-<key>-<pid>`: that folder
/// and the download's outcome, or why the manifest cannot be used.
fn fill_scratch(
    remote: &Remote,
    key: &NodeKey,
    manifest: &[u8],
    root: &Path,
    tag: &str,
) -> Result<(PathBuf, Filled), String> {
    let files = parse_manifest(manifest)?;
    let tmp = root.join(format!(".{tag}-{key}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&tmp);
    let result = fill(remote, key, &files, &tmp);
    Ok((tmp, result))
}

fn fill(remote: &Remote, key: &NodeKey, files: &[ManifestFile], tmp: &Path) -> Filled {
    for f in files {
        let path = tmp.join(&f.rel);
        if let Some(parent) = path.parent() {
            fs::create_dir_all(parent).map_err(StoreError::io("create folder", parent))?;
        }
        let file = File::create(&path).map_err(StoreError::io("create", &path))?;
        let mut sink = HashingWriter::new(file);
        if !remote.get_to(&file_name(key, &f.rel), &mut sink)? {
            return Ok(Err(format!("file {} of the folder is missing", f.rel)));
        }
        sink.flush().map_err(StoreError::io("write", &path))?;
        let (bytes, hash) = sink.finish();
        if bytes != f.bytes || hash != f.hash {
            return Ok(Err(format!(
                "file {} of the folder does not match its manifest ({bytes} bytes, blake3 {hash}; recorded {} bytes, {})",
                f.rel, f.bytes, f.hash
            )));
        }
    }
    Ok(Ok(()))
}

/// Downloads the folder of `key` described by `manifest` into a scratch folder below `scratch_root` and
/// checks every file, then removes the scratch copy. `Ok(Some(reason))` when the remote copy is damaged.
pub(crate) fn check(
    remote: &Remote,
    key: &NodeKey,
    manifest: &[u8],
    scratch_root: &Path,
) -> Result<Option<String>, StoreError> {
    let (tmp, result) = match fill_scratch(remote, key, manifest, scratch_root, "verify") {
        Ok(filled) => filled,
        Err(reason) => return Ok(Some(reason)),
    };
    let _ = fs::remove_dir_all(&tmp);
    Ok(result?.err())
}

/// Deletes the remote folder of `key`: its manifest first (so it is never seen incomplete), then its files.
/// Returns the number of objects deleted.
pub(crate) fn delete(remote: &Remote, key: &NodeKey) -> Result<usize, StoreError> {
    let mut n = usize::from(remote.delete(&manifest_name(key))?);
    for object in remote.list(&format!("dirs/{key}"))? {
        n += usize::from(remote.delete(&object.name)?);
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manifest_round_trip_and_damage() {
        let files = vec![
            ManifestFile {
                rel: "campaign/a b.csv".into(),
                bytes: 12,
                hash: hash_bytes(b"x"),
            },
            ManifestFile {
                rel: "items/item_000.txt".into(),
                bytes: 3,
                hash: hash_bytes(b"y"),
            },
        ];
        let bytes = encode_manifest(&files);
        assert_eq!(parse_manifest(&bytes).unwrap(), files);
        let mut bad = bytes.clone();
        bad[20] ^= 1;
        assert!(parse_manifest(&bad).is_err());
        assert!(parse_manifest(&bytes[..bytes.len() - 10]).is_err());
        let unsafe_path = encode_manifest(&[ManifestFile {
            rel: "../x".into(),
            bytes: 1,
            hash: hash_bytes(b""),
        }]);
        assert!(parse_manifest(&unsafe_path).unwrap_err().contains("unsafe"));
    }
}

//! Verification of the remote: downloads every remote entry and checks it like a local one (header, key,
//! blake3 of the payload), and every generated folder against its manifest; damaged ones are deleted from the
//! remote (the next run that needs them recomputes and uploads them). This reads the whole remote once.

use std::fs::{self, File};
use std::path::Path;

use rayon::prelude::*;

use super::backend::Remote;
use super::{dirs, entries};
use crate::hashing::NodeKey;
use crate::store::error::StoreError;

/// A remote object that failed verification.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BadRemoteObject {
    pub key: NodeKey,
    /// Remote name (relative to the URL's prefix).
    pub name: String,
    pub reason: String,
    /// Whether it was deleted from the remote.
    pub removed: bool,
}

/// Outcome of a remote verification (`Store::verify_remote`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RemoteVerifyReport {
    pub url: String,
    pub entries_checked: u64,
    pub folders_checked: u64,
    pub bytes_checked: u64,
    /// Entries and folders that failed, in name order.
    pub bad: Vec<BadRemoteObject>,
}

fn check_entry(
    remote: &Remote,
    key: &NodeKey,
    name: &str,
    scratch: &Path,
) -> Result<Option<String>, StoreError> {
    let tmp = scratch.join(format!(".verify-{key}-{}.tmp", std::process::id()));
    let result = (|| {
        let mut file = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&tmp)
            .map_err(StoreError::io("create", &tmp))?;
        if !remote.get_to(name, &mut file)? {
            return Ok(None); // removed meanwhile
        }
        entries::check_file(&mut file, key).map_err(StoreError::io("read the download", &tmp))
    })();
    let _ = fs::remove_file(&tmp);
    result
}

/// Verifies the remote (see the module documentation); `scratch` is a local folder for the downloads.
pub(crate) fn run(remote: &Remote, scratch: &Path) -> Result<RemoteVerifyReport, StoreError> {
    fs::create_dir_all(scratch).map_err(StoreError::io("create folder", scratch))?;
    let objects = remote.list("objects")?;
    let manifests: Vec<_> = remote
        .list("dirs")?
        .into_iter()
        .filter(|o| o.name.ends_with(".manifest") && o.name.matches('/').count() == 1)
        .collect();
    let entry_results: Vec<Result<Option<BadRemoteObject>, StoreError>> = objects
        .par_iter()
        .filter_map(|o| entries::key_of(&o.name).map(|k| (k, o)))
        .map(|(key, o)| {
            Ok(
                check_entry(remote, &key, &o.name, scratch)?.map(|reason| BadRemoteObject {
                    key,
                    name: o.name.clone(),
                    reason,
                    removed: false,
                }),
            )
        })
        .collect();
    let folder_results: Vec<Result<Option<BadRemoteObject>, StoreError>> = manifests
        .par_iter()
        .filter_map(|o| {
            let hex = o.name.strip_prefix("dirs/")?.strip_suffix(".manifest")?;
            NodeKey::from_hex(hex).ok().map(|k| (k, o))
        })
        .map(|(key, o)| {
            let Some(manifest) = remote.get_bytes(&o.name)? else {
                return Ok(None);
            };
            Ok(
                dirs::check(remote, &key, &manifest, scratch)?.map(|reason| BadRemoteObject {
                    key,
                    name: o.name.clone(),
                    reason: format!("generated folder: {reason}"),
                    removed: false,
                }),
            )
        })
        .collect();
    let mut report = RemoteVerifyReport {
        url: remote.url().to_string(),
        entries_checked: objects
            .iter()
            .filter(|o| entries::key_of(&o.name).is_some())
            .count() as u64,
        folders_checked: manifests.len() as u64,
        bytes_checked: objects.iter().map(|o| o.bytes).sum(),
        bad: Vec::new(),
    };
    for result in entry_results.into_iter().chain(folder_results) {
        if let Some(mut bad) = result? {
            bad.removed = entries::discard(remote, &bad.key).is_ok();
            report.bad.push(bad);
        }
    }
    report.bad.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(report)
}

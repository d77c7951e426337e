//! Collection of the remote: removes every remote entry (with its generated folder and its output record)
//! that no node record on the remote points to — results superseded by a newer stage version, other
//! parameters or changed inputs. The node records are the roots: each names the key of the last successful
//! run of one node identity in one variant, so every variant of a sweep stays. Objects younger than a minimum
//! age are kept whatever they are: a run on another host uploads an entry a moment before its node record,
//! and must not lose it in between. Leases are per host and play no part here.

use std::collections::HashSet;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use super::backend::Remote;
use super::{dirs, entries};
use crate::hashing::NodeKey;
use crate::store::error::StoreError;
use crate::store::records;

/// Outcome of a remote collection (`Store::gc_remote`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RemoteGcReport {
    pub url: String,
    /// Unreachable objects younger than this were kept.
    pub min_age: Duration,
    /// Node records read (the roots) and how many could not be read (damaged; their keys are unknown).
    pub roots: u64,
    pub unreadable_roots: u64,
    pub entries_before: u64,
    pub bytes_before: u64,
    /// Keys of the entries removed, sorted.
    pub removed_keys: Vec<NodeKey>,
    pub removed_bytes: u64,
    /// Unreachable entries kept because they are younger than `min_age`.
    pub young_entries: u64,
    pub kept_entries: u64,
    pub kept_bytes: u64,
    /// Generated folders and output records removed (with the entries, or left over without one).
    pub removed_folders: u64,
    pub removed_records: u64,
}

fn now_unix_s() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() as i64)
}

/// The folder key of a name below `dirs/` (`dirs/<key>.manifest` or `dirs/<key>/…`).
fn folder_key(name: &str) -> Option<NodeKey> {
    let rest = name.strip_prefix("dirs/")?;
    let first = rest.split('/').next()?;
    NodeKey::from_hex(first.strip_suffix(".manifest").unwrap_or(first)).ok()
}

/// Collects the remote (see the module documentation). `roots_namespace` is the record namespace of the node
/// records, `root_key` extracts the key a record's payload names.
pub(crate) fn run(
    remote: &Remote,
    roots_namespace: &str,
    root_key: &dyn Fn(&[u8]) -> Option<NodeKey>,
    outputs_namespace: &str,
    min_age: Duration,
) -> Result<RemoteGcReport, StoreError> {
    let mut report = RemoteGcReport {
        url: remote.url().to_string(),
        min_age,
        ..RemoteGcReport::default()
    };
    let mut reachable: HashSet<NodeKey> = HashSet::new();
    for object in remote.list(&format!("records/{roots_namespace}"))? {
        report.roots += 1;
        let key = remote
            .get_bytes(&object.name)?
            .and_then(|bytes| records::parse_any(&bytes).map(|(_, p)| p.to_vec()))
            .and_then(|payload| root_key(&payload));
        match key {
            Some(k) => {
                reachable.insert(k);
            }
            None => report.unreadable_roots += 1,
        }
    }
    let newest_removable = now_unix_s() - min_age.as_secs() as i64;
    let mut kept: HashSet<NodeKey> = reachable.clone();
    for object in remote.list("objects")? {
        let Some(key) = entries::key_of(&object.name) else {
            continue;
        };
        report.entries_before += 1;
        report.bytes_before += object.bytes;
        if reachable.contains(&key) {
            report.kept_entries += 1;
            report.kept_bytes += object.bytes;
        } else if object.modified_unix_s > newest_removable {
            report.young_entries += 1;
            report.kept_entries += 1;
            report.kept_bytes += object.bytes;
            kept.insert(key);
        } else {
            remote.delete(&object.name)?;
            report.removed_keys.push(key);
            report.removed_bytes += object.bytes;
        }
    }
    // Folders whose entry is gone or unreachable (a folder is uploaded before its entry: keep young ones).
    let mut folders_seen: HashSet<NodeKey> = HashSet::new();
    for object in remote.list("dirs")? {
        let Some(key) = folder_key(&object.name) else {
            continue;
        };
        if kept.contains(&key) || object.modified_unix_s > newest_removable {
            kept.insert(key);
            continue;
        }
        folders_seen.insert(key);
    }
    for key in folders_seen.iter().filter(|k| !kept.contains(k)) {
        if dirs::delete(remote, key)? > 0 {
            report.removed_folders += 1;
        }
    }
    let kept_outputs: HashSet<String> = kept
        .iter()
        .filter_map(|k| records::file_name(outputs_namespace, &k.to_string()).ok())
        .collect();
    for object in remote.list(&format!("records/{outputs_namespace}"))? {
        let file = object.name.trim_start_matches("records/");
        if !kept_outputs.contains(file)
            && object.modified_unix_s <= newest_removable
            && remote.delete(&object.name)?
        {
            report.removed_records += 1;
        }
    }
    report.removed_keys.sort();
    Ok(report)
}

//! `Store::gc`: trims the store to a size budget, least-recently-used entries first (last use = the entry
//! file's modification time, set on every load hit and save). Entries used since the start of any live run
//! (minus a safety margin for coarse file-system clocks) are never removed; stale leases of dead runs are
//! cleared first.

use std::fs;
use std::time::{Duration, SystemTime};

use super::error::StoreError;
use super::{lease, objects, Store};
use crate::hashing::NodeKey;

/// Entries used this long before a live run started are protected too: file systems stamp writes with a
/// coarse clock that may lag the run's start time slightly.
const PROTECTION_MARGIN: Duration = Duration::from_secs(2);

/// Outcome of [`Store::gc`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GcReport {
    pub max_bytes: u64,
    pub entries_before: u64,
    pub bytes_before: u64,
    pub removed_entries: u64,
    pub removed_bytes: u64,
    /// Keys removed, in removal (least-recently-used first) order.
    pub removed_keys: Vec<NodeKey>,
    pub kept_entries: u64,
    pub kept_bytes: u64,
    /// Entries that would have been removed but were used by a live run.
    pub protected_entries: u64,
    pub protected_bytes: u64,
    pub live_runs: usize,
    pub stale_leases_removed: usize,
    pub temp_files_removed: usize,
    /// Entries that could not be removed (file and reason); gc went on with the others.
    pub failures: Vec<String>,
}

pub(crate) fn run(store: &Store, max_bytes: u64) -> Result<GcReport, StoreError> {
    let (live, stale_leases_removed) = lease::scan(&store.runs)?;
    let protect_since: Option<SystemTime> = live
        .iter()
        .map(|r| r.started)
        .min()
        .map(|t| t.checked_sub(PROTECTION_MARGIN).unwrap_or(t));
    let listing = objects::list(&store.objects)?;
    let mut candidates = listing.objects;
    // Least recently used first; ties by key so the order is deterministic.
    candidates.sort_by_key(|o| (o.last_used, o.key));

    let mut report = GcReport {
        max_bytes,
        entries_before: candidates.len() as u64,
        bytes_before: candidates.iter().map(|o| o.bytes).sum(),
        live_runs: live.len(),
        stale_leases_removed,
        temp_files_removed: listing.temp_files_removed,
        ..GcReport::default()
    };
    let mut total = report.bytes_before;
    for object in &candidates {
        if total <= max_bytes {
            break;
        }
        if protect_since.is_some_and(|since| object.last_used >= since) {
            report.protected_entries += 1;
            report.protected_bytes += object.bytes;
            continue;
        }
        // A live run may have used it since the listing: look again right before removing.
        let used_now = fs::metadata(&object.path).and_then(|m| m.modified());
        if let (Some(since), Ok(used)) = (protect_since, &used_now) {
            if *used >= since {
                report.protected_entries += 1;
                report.protected_bytes += object.bytes;
                continue;
            }
        }
        match fs::remove_file(&object.path) {
            Ok(()) => {
                report.removed_entries += 1;
                report.removed_bytes += object.bytes;
                report.removed_keys.push(object.key);
                total -= object.bytes;
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => total -= object.bytes,
            Err(e) => report
                .failures
                .push(format!("cannot remove {}: {e}", object.path.display())),
        }
    }
    report.kept_entries = report.entries_before - report.removed_entries;
    report.kept_bytes = report.bytes_before - report.removed_bytes;
    Ok(report)
}

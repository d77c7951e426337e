//! `Store::stats`: entry and byte counts in total and per stage, read from entry headers (no payload reads).

use std::collections::BTreeMap;
use std::fs::File;

use super::entry::{self, EntryFault};
use super::error::StoreError;
use super::{lease, objects, Store};

/// Counts of one stage's entries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StageStats {
    pub entries: u64,
    /// On-disk bytes (headers included).
    pub bytes: u64,
}

/// What the store holds.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StoreStats {
    /// All entry files, including unreadable ones.
    pub entries: u64,
    /// On-disk bytes of all entry files.
    pub bytes: u64,
    /// Per stage name (from entry headers), sorted by name.
    pub per_stage: BTreeMap<String, StageStats>,
    /// Entries whose header is damaged or of another store format (counted in `entries`/`bytes`, not per stage).
    pub unreadable: StageStats,
    /// Side records (`records/`).
    pub records: StageStats,
    /// Runs currently holding a lease.
    pub live_runs: usize,
}

pub(crate) fn collect(store: &Store) -> Result<StoreStats, StoreError> {
    let listing = objects::list(&store.objects)?;
    let mut stats = StoreStats::default();
    for object in &listing.objects {
        stats.entries += 1;
        stats.bytes += object.bytes;
        let header = File::open(&object.path)
            .map_err(EntryFault::Unreadable)
            .and_then(|mut f| entry::read_header(&mut f, object.bytes));
        let slot = match header {
            Ok(h) => stats.per_stage.entry(h.meta.stage).or_default(),
            Err(_) => &mut stats.unreadable,
        };
        slot.entries += 1;
        slot.bytes += object.bytes;
    }
    stats.records = count_records(&store.records);
    stats.live_runs = lease::scan(&store.runs)?.0.len();
    Ok(stats)
}

fn count_records(records: &std::path::Path) -> StageStats {
    let mut out = StageStats::default();
    let Ok(namespaces) = std::fs::read_dir(records) else {
        return out;
    };
    for ns in namespaces.flatten() {
        let Ok(files) = std::fs::read_dir(ns.path()) else {
            continue;
        };
        for f in files.flatten() {
            if f.file_name().to_string_lossy().starts_with('.') {
                continue;
            }
            if let Ok(m) = f.metadata() {
                out.entries += 1;
                out.bytes += m.len();
            }
        }
    }
    out
}

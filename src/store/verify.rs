//! `Store::verify`: re-reads and re-hashes every entry (in parallel, results in key order, streaming each
//! payload through the hash so memory stays small), removes the bad ones and lists them.

use std::fs::File;
use std::path::PathBuf;

use rayon::prelude::*;

use super::entry::{self, EntryFault, STORE_FORMAT_VERSION};
use super::error::StoreError;
use super::{objects, Store};
use crate::hashing::NodeKey;

/// An entry that failed verification.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BadEntry {
    pub key: NodeKey,
    pub path: PathBuf,
    pub reason: String,
    /// Whether the file was deleted.
    pub removed: bool,
}

/// Outcome of [`Store::verify`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct VerifyReport {
    /// Entries examined.
    pub checked: u64,
    /// Entries that passed.
    pub ok: u64,
    /// On-disk bytes examined.
    pub bytes_checked: u64,
    /// Entries that failed, in key order.
    pub bad: Vec<BadEntry>,
    /// Left-over temporaries of crashed writes that were removed.
    pub temp_files_removed: usize,
}

impl VerifyReport {
    /// True when every entry passed.
    pub fn all_ok(&self) -> bool {
        self.bad.is_empty()
    }
}

pub(crate) fn run(store: &Store) -> Result<VerifyReport, StoreError> {
    let listing = objects::list(&store.objects)?;
    let outcomes: Vec<Option<BadEntry>> = listing
        .objects
        .par_iter()
        .map(|object| {
            let mut file = match File::open(&object.path) {
                Ok(f) => f,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => return None, // removed meanwhile
                Err(e) => {
                    let removed = std::fs::remove_file(&object.path).is_ok();
                    let reason = format!("cannot open: {e}");
                    return Some(BadEntry { key: object.key, path: object.path.clone(), reason, removed });
                }
            };
            // Streamed: every payload byte is read and hashed in blocks, nothing is kept in memory.
            let reason = match entry::read_entry_with(&mut file, &object.key, |_, _| Ok(())) {
                Ok(_) => return None,
                Err(EntryFault::Damaged(reason)) => reason,
                Err(EntryFault::Unreadable(e)) => format!("read error: {e}"),
                Err(EntryFault::OtherFormat(v)) => {
                    format!("written by store format version {v}, this skytie uses {STORE_FORMAT_VERSION}")
                }
            };
            let removed = objects::remove_if_same(&object.path, &file);
            Some(BadEntry { key: object.key, path: object.path.clone(), reason, removed })
        })
        .collect();
    let bad: Vec<BadEntry> = outcomes.into_iter().flatten().collect();
    let checked = listing.objects.len() as u64;
    Ok(VerifyReport {
        checked,
        ok: checked - bad.len() as u64,
        bytes_checked: listing.objects.iter().map(|o| o.bytes).sum(),
        bad,
        temp_files_removed: listing.temp_files_removed,
    })
}

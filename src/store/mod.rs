//! The content-addressed artifact store: one file per DAG node result under `<root>/objects/`, named by the
//! node key, written atomically and verified on every read.
//!
//! Safe for many threads (`&self` methods, `Store: Send + Sync`) and many processes sharing one folder: entries
//! are immutable once renamed into place, and two processes saving the same key write identical bytes. A
//! damaged entry is reported once, deleted and recomputed by the caller — never trusted. Last use of an entry
//! is its file modification time (set on every load hit and save, and by `contains` during a run), which
//! `gc` sorts by; live runs hold a [`RunLease`] so `gc` never removes what they used.
//!
//! Optionally a remote object store stands behind the folder ([`Store::open_with_remote`], [`remote`]): the
//! folder is then the local cache in front of it — loads that miss locally download, verify and install the
//! remote entry; saves and side records are uploaded too. Without a remote nothing of this costs anything.

mod entry;
mod error;
mod gc;
mod lease;
mod objects;
mod records;
pub mod remote;
mod stats;
mod stream;
mod verify;

use std::collections::HashSet;
use std::fs::{self, File};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::SystemTime;

pub use entry::{EntryMeta, STORE_FORMAT_VERSION};
pub use error::StoreError;
pub use gc::GcReport;
pub use lease::{LiveRun, RunLease};
pub use remote::{Remote, RemoteGcReport, RemoteVerifyReport};
pub use stats::{StageStats, StoreStats};
pub use verify::{BadEntry, VerifyReport};

use crate::codec::CodecError;
use crate::hashing::{ContentHash, NodeKey};
use entry::EntryFault;
use stream::HashingWriter;

/// A verified cache entry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry {
    pub meta: EntryMeta,
    pub payload: Vec<u8>,
    /// blake3 of `payload` (verified).
    pub content_hash: ContentHash,
}

/// Result of [`Store::load`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Lookup {
    /// A verified entry.
    Hit(Entry),
    /// No entry: compute the node.
    Miss,
    /// The entry was damaged or unreadable: it has been deleted; show `message` once and compute the node.
    Corrupt { message: String },
}

/// Result of [`Store::load_with`]: like [`Lookup`], with the payload decoded while it was read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Loaded<T> {
    /// A verified entry, decoded.
    Hit {
        value: T,
        meta: EntryMeta,
        /// blake3 of the payload (verified).
        content_hash: ContentHash,
    },
    /// No entry: compute the node.
    Miss,
    /// The entry was damaged, unreadable or undecodable: it has been deleted; show `message` once and
    /// compute the node.
    Corrupt { message: String },
}

/// Handle on a cache folder.
pub struct Store {
    root: PathBuf,
    objects: PathBuf,
    records: PathBuf,
    runs: PathBuf,
    /// An entry of another store format has been reported by this handle (later ones are silent misses).
    other_format_noticed: AtomicBool,
    /// Keys already reported as corrupt whose file could not be deleted (reported only once).
    reported: Mutex<HashSet<NodeKey>>,
    /// Leases taken through this handle and not yet dropped.
    active_leases: Arc<AtomicUsize>,
    /// The remote object store behind this folder, if any.
    remote: Option<Remote>,
}

impl Store {
    /// Opens (creating as needed) the store at `root`, with its `objects/`, `records/` and `runs/` folders.
    pub fn open(root: &Path) -> Result<Store, StoreError> {
        Store::open_with_remote(root, None)
    }

    /// Opens the store at `root` as the local cache in front of the remote at `remote_url` (see [`remote`]
    /// for the URL forms); `None` is [`Store::open`].
    /// A relative `root` is taken from the current folder and kept absolute: the paths of generated folders
    /// recorded in results (a rendered campaign's folder, `provenance.json`) then name the same folder from
    /// any working folder, and a run started elsewhere reuses them instead of regenerating them.
    pub fn open_with_remote(root: &Path, remote_url: Option<&str>) -> Result<Store, StoreError> {
        let remote = remote_url.map(Remote::open).transpose()?;
        let root =
            std::path::absolute(root).map_err(StoreError::io("locate cache folder", root))?;
        let store = Store {
            root: root.clone(),
            objects: root.join("objects"),
            records: root.join("records"),
            runs: root.join("runs"),
            other_format_noticed: AtomicBool::new(false),
            reported: Mutex::new(HashSet::new()),
            active_leases: Arc::new(AtomicUsize::new(0)),
            remote,
        };
        for dir in [&store.root, &store.objects, &store.records, &store.runs] {
            fs::create_dir_all(dir).map_err(StoreError::io("create cache folder", dir))?;
        }
        Ok(store)
    }

    /// The cache folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The URL of the remote behind this cache, if any.
    pub fn remote_url(&self) -> Option<&str> {
        self.remote.as_ref().map(Remote::url)
    }

    /// `<root>/dirs`: where nodes' generated folders live (`<root>/dirs/<key>/`); they travel to and from the
    /// remote with their entries.
    fn dirs_root(&self) -> PathBuf {
        self.root.join("dirs")
    }

    /// Path of the entry file of `key`.
    pub fn object_path(&self, key: &NodeKey) -> PathBuf {
        objects::object_path(&self.objects, key)
    }

    /// Looks up the artifact of `key`, verifying header, format version and payload hash. A damaged, truncated
    /// or unreadable entry is returned once as [`Lookup::Corrupt`] (message names key, path and reason) and
    /// deleted; the next load is a [`Lookup::Miss`]. An entry of another store format is deleted too; the first
    /// one per handle is reported, later ones are plain misses. A hit marks the entry as used now. `Err` only
    /// when the entry cannot even be opened for a reason that is not its own (e.g. too many open files).
    pub fn load(&self, key: &NodeKey) -> Result<Lookup, StoreError> {
        let loaded = self.load_with(key, |source, len| {
            let len = usize::try_from(len).map_err(|_| {
                CodecError(format!("a payload of {len} bytes does not fit in memory"))
            })?;
            let mut payload = vec![0u8; len];
            source
                .read_exact(&mut payload)
                .map_err(|e| CodecError(format!("cannot read the payload: {e}")))?;
            Ok(payload)
        })?;
        Ok(match loaded {
            Loaded::Hit {
                value,
                meta,
                content_hash,
            } => Lookup::Hit(Entry {
                meta,
                payload: value,
                content_hash,
            }),
            Loaded::Miss => Lookup::Miss,
            Loaded::Corrupt { message } => Lookup::Corrupt { message },
        })
    }

    /// Looks up the artifact of `key` and decodes it while reading: `decode(source, len)` receives the payload
    /// as a stream of `len` bytes (e.g. [`Artifact::decode_from`](crate::codec::Artifact::decode_from)); each
    /// byte is read from the file once and hashed on the way. The value is returned only if the whole payload
    /// matches its recorded hash; a damaged, truncated or unreadable entry, or one `decode` rejects, is
    /// reported once as [`Loaded::Corrupt`] and deleted, exactly as in [`Store::load`] (whose checks this
    /// shares). A hit marks the entry as used now.
    pub fn load_with<T>(
        &self,
        key: &NodeKey,
        decode: impl FnOnce(&mut dyn Read, u64) -> Result<T, CodecError>,
    ) -> Result<Loaded<T>, StoreError> {
        let path = self.object_path(key);
        let mut file = match File::open(&path) {
            Ok(f) => f,
            Err(e) if e.kind() == io::ErrorKind::NotFound => match self.fetch_remote(key, &path)? {
                Ok(f) => f,
                Err(outcome) => return Ok(outcome),
            },
            // The entry itself is unusable: report and remove it.
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::PermissionDenied | io::ErrorKind::IsADirectory
                ) =>
            {
                return Ok(self.corrupt(key, &path, None, &format!("cannot open: {e}")));
            }
            // Not the entry's fault (e.g. too many open files): keep it, report the failure.
            Err(e) => return Err(StoreError::io("open cache entry", &path)(e)),
        };
        match entry::read_entry_with(&mut file, key, decode) {
            Ok((header, value)) => {
                // Last-use time for LRU gc and live-run protection; failure only weakens gc ordering.
                let _ = file.set_modified(SystemTime::now());
                Ok(Loaded::Hit {
                    value,
                    meta: header.meta,
                    content_hash: header.payload_hash,
                })
            }
            Err(EntryFault::OtherFormat(version)) => {
                objects::remove_if_same(&path, &file);
                if self.other_format_noticed.swap(true, Ordering::Relaxed) {
                    Ok(Loaded::Miss)
                } else {
                    Ok(Loaded::Corrupt {
                        message: format!(
                            "cache entry {key} ({}) was written by store format version {version}, this skytie uses \
                             version {STORE_FORMAT_VERSION}: entries of other formats are discarded and recomputed \
                             (reported once; `skytie cache gc --max-size 0` clears them all)",
                            path.display()
                        ),
                    })
                }
            }
            Err(EntryFault::Damaged(reason)) => Ok(self.corrupt(key, &path, Some(&file), &reason)),
            Err(EntryFault::Unreadable(e)) => {
                Ok(self.corrupt(key, &path, Some(&file), &format!("read error: {e}")))
            }
        }
    }

    /// On a local miss: the entry downloaded from the remote, verified and installed at `path`, opened; or
    /// what the load returns instead (a miss, or the report of a damaged remote copy).
    fn fetch_remote<T>(
        &self,
        key: &NodeKey,
        path: &Path,
    ) -> Result<Result<File, Loaded<T>>, StoreError> {
        let Some(remote) = &self.remote else {
            return Ok(Err(Loaded::Miss));
        };
        match remote::entries::fetch(remote, key, path, &self.dirs_root())? {
            remote::entries::Fetched::Installed => match File::open(path) {
                Ok(f) => Ok(Ok(f)),
                // Removed meanwhile (a concurrent gc): a miss like any other.
                Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(Err(Loaded::Miss)),
                Err(e) => Err(StoreError::io("open cache entry", path)(e)),
            },
            remote::entries::Fetched::Absent => Ok(Err(Loaded::Miss)),
            remote::entries::Fetched::Damaged(reason) => Ok(Err(Loaded::Corrupt {
                message: format!(
                    "cache entry {key} on the remote {} is corrupt: {reason}; deleted from the remote, the node will \
                     be recomputed",
                    remote.url()
                ),
            })),
        }
    }

    fn corrupt<T>(
        &self,
        key: &NodeKey,
        path: &Path,
        opened: Option<&File>,
        reason: &str,
    ) -> Loaded<T> {
        let removed = match opened {
            Some(file) => objects::remove_if_same(path, file),
            None => fs::remove_file(path).is_ok(),
        };
        let mut reported = self.reported.lock().unwrap_or_else(|p| p.into_inner());
        if !removed && !reported.insert(*key) {
            return Loaded::Miss;
        }
        let action = if removed {
            "deleted"
        } else {
            "could not be deleted, ignored"
        };
        Loaded::Corrupt {
            message: format!(
                "cache entry {key} ({}) is corrupt: {reason}; {action}, the node will be recomputed",
                path.display()
            ),
        }
    }

    /// Atomically stores `payload` as the entry of `key` (temporary file in the same folder, rename; durable
    /// after [`Store::sync`]).
    /// Returns the payload's content hash. Concurrent saves of one key are safe (identical bytes, atomic rename).
    pub fn save(
        &self,
        key: &NodeKey,
        meta: &EntryMeta,
        payload: &[u8],
    ) -> Result<ContentHash, StoreError> {
        self.save_with(key, meta, |sink| sink.write_all(payload))
    }

    /// Atomically stores the payload that `encode` writes to its sink (e.g.
    /// [`Artifact::encode_to`](crate::codec::Artifact::encode_to)) as the entry of `key`, without building it
    /// in memory first: the bytes go straight to a temporary file and are hashed on the way; the header
    /// (length and hash) is written over its placeholder at the end, then the file is renamed into place
    /// (durable after [`Store::sync`]). Returns the payload's content hash. An error of `encode` leaves no entry.
    pub fn save_with(
        &self,
        key: &NodeKey,
        meta: &EntryMeta,
        encode: impl FnOnce(&mut dyn Write) -> io::Result<()>,
    ) -> Result<ContentHash, StoreError> {
        let meta_block = entry::encode_meta(meta).map_err(|len| StoreError::MetaTooLarge {
            key: key.to_string(),
            len,
            max: entry::MAX_META_BYTES,
        })?;
        // Same length as the final header: only the length, hash and check fields change.
        let placeholder = entry::encode_header(key, &meta_block, 0, &ContentHash::default());
        let path = self.object_path(key);
        let mut content_hash = ContentHash::default();
        // No fsync per entry: an entry is verified on every read, so one damaged by a machine crash is found,
        // deleted and recomputed; [`Store::sync`] makes a run's entries durable at once.
        skytie_util::fsutil::atomic_write_unsynced_with(&path, |w| {
            w.write_all(&placeholder)?;
            let mut sink = HashingWriter::new(&mut *w);
            encode(&mut sink)?;
            let (payload_len, hash) = sink.finish();
            content_hash = hash;
            w.flush()?;
            let header = entry::encode_header(key, &meta_block, payload_len, &hash);
            let file = w.get_mut();
            file.seek(SeekFrom::Start(0))?;
            file.write_all(&header)?;
            file.seek(SeekFrom::End(0)).map(|_| ())
        })
        .map_err(StoreError::io("write cache entry", &path))?;
        if let Some(remote) = &self.remote {
            if let Err(e) = remote::entries::upload(remote, key, &path, &self.dirs_root()) {
                // Not kept locally either: a later run finds it missing, computes and uploads it again.
                let _ = fs::remove_file(&path);
                return Err(e);
            }
        }
        Ok(content_hash)
    }

    /// Flushes the entries written so far to disk (one `syncfs` of the cache's file system instead of an fsync
    /// per entry); a run calls it when it has stored its results.
    pub fn sync(&self) -> Result<(), StoreError> {
        skytie_util::fsutil::sync_file_system(&self.objects)
            .map_err(StoreError::io("flush cache entries", &self.objects))
    }

    /// Whether an entry file for `key` exists (no verification). While a run holds a lease from this handle,
    /// an existing entry is also marked used (a run that finds a node cached uses its entry even if it never
    /// loads it); without a lease (e.g. `skytie plan`) nothing is modified.
    pub fn contains(&self, key: &NodeKey) -> bool {
        if self.active_leases.load(Ordering::Relaxed) > 0 {
            self.mark_used(key)
        } else {
            self.object_path(key).is_file()
        }
    }

    /// Marks the entry of `key` as used now (for LRU `gc` and live-run protection); returns whether it exists.
    pub fn mark_used(&self, key: &NodeKey) -> bool {
        match File::open(self.object_path(key)) {
            Ok(file) => {
                // Failure (e.g. a cache folder owned by another user) only weakens gc ordering.
                let _ = file.set_modified(SystemTime::now());
                file.metadata().is_ok_and(|m| m.is_file())
            }
            Err(_) => false,
        }
    }

    /// Atomically stores a small side record `bytes` under `<root>/records/<namespace>/<blake3(name)>`.
    /// With a remote, the record is uploaded too (replacing the remote one: records are mutable, the last
    /// writer wins).
    pub fn put_record(&self, namespace: &str, name: &str, bytes: &[u8]) -> Result<(), StoreError> {
        let file = records::put(&self.records, namespace, name, bytes)?;
        if let Some(remote) = &self.remote {
            let remote_name = format!("records/{}", records::file_name(namespace, name)?);
            remote.put_bytes(&remote_name, file, false)?;
        }
        Ok(())
    }

    /// The record stored under (`namespace`, `name`); `None` if absent, unreadable or corrupt. The local copy
    /// is preferred; with a remote, a record absent locally is downloaded, checked and kept locally. A remote
    /// that cannot be reached reads as absent.
    pub fn get_record(&self, namespace: &str, name: &str) -> Option<Vec<u8>> {
        if let Some(payload) = records::get(&self.records, namespace, name) {
            return Some(payload);
        }
        let remote = self.remote.as_ref()?;
        let remote_name = format!("records/{}", records::file_name(namespace, name).ok()?);
        let file = remote.get_bytes(&remote_name).ok()??;
        records::install(&self.records, namespace, name, &file).ok()?
    }

    /// Removes the record (`namespace`, `name`) if there is one (locally and on the remote); returns whether
    /// there was one locally.
    pub fn remove_record(&self, namespace: &str, name: &str) -> Result<bool, StoreError> {
        let removed = records::remove(&self.records, namespace, name)?;
        if let Some(remote) = &self.remote {
            remote.delete(&format!("records/{}", records::file_name(namespace, name)?))?;
        }
        Ok(removed)
    }

    /// Registers this process as a live run until the returned lease is dropped. Entries it loads or saves are
    /// protected from `gc` meanwhile; a crashed run's lease is detected as stale and never blocks anything.
    pub fn begin_run(&self) -> Result<RunLease, StoreError> {
        lease::acquire(&self.runs, Arc::clone(&self.active_leases))
    }

    /// Live runs using this cache (leases of dead runs are removed on the way).
    pub fn live_runs(&self) -> Result<Vec<LiveRun>, StoreError> {
        Ok(lease::scan(&self.runs)?.0)
    }

    /// Entry and byte counts, in total and per stage.
    pub fn stats(&self) -> Result<StoreStats, StoreError> {
        stats::collect(self)
    }

    /// Re-reads and re-hashes every entry; removes and lists the bad ones.
    pub fn verify(&self) -> Result<VerifyReport, StoreError> {
        verify::run(self)
    }

    /// Removes least-recently-used entries until the entries total at most `max_bytes`, never removing an entry
    /// used since the start of a live run.
    pub fn gc(&self, max_bytes: u64) -> Result<GcReport, StoreError> {
        gc::run(self, max_bytes)
    }

    /// With a remote: removes the remote entries no record of `roots_namespace` points to (`root_key` reads
    /// the key a record names), with their generated folders and their records in `outputs_namespace`;
    /// unreachable objects younger than `min_age` are kept (see [`remote::gc`]). `None` without a remote.
    pub fn gc_remote(
        &self,
        roots_namespace: &str,
        root_key: &dyn Fn(&[u8]) -> Option<NodeKey>,
        outputs_namespace: &str,
        min_age: std::time::Duration,
    ) -> Option<Result<RemoteGcReport, StoreError>> {
        let remote = self.remote.as_ref()?;
        Some(remote::gc::run(
            remote,
            roots_namespace,
            root_key,
            outputs_namespace,
            min_age,
        ))
    }

    /// With a remote: downloads and verifies every remote entry and generated folder, deleting damaged ones
    /// from the remote (see [`remote::verify`]). `None` without a remote.
    pub fn verify_remote(&self) -> Option<Result<RemoteVerifyReport, StoreError>> {
        let remote = self.remote.as_ref()?;
        Some(remote::verify::run(remote, &self.objects))
    }
}

//! Run leases: a file per live `skytie run` under `<root>/runs/`, held with an exclusive OS file lock
//! (`File::lock`, flock on Unix). The lock dies with the process, so the lease of a crashed or killed run is
//! recognised as stale (its lock can be taken) and removed; it never blocks anything.
//!
//! A lease records when its run started; `gc` protects every entry used (loaded or saved, which sets the entry
//! file's modification time) since the earliest start of a live run.

use std::fs::{self, File, TryLockError};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use super::error::StoreError;
use crate::hashing::system_time_ns;

static LEASE_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Extension of lease files; temporaries being set up end in `.tmp`.
const LEASE_EXT: &str = "lease";

/// Proof that this process is a live run. Dropping it ends the run (the lease file is removed).
#[derive(Debug)]
pub struct RunLease {
    file: Option<File>,
    path: PathBuf,
    started: SystemTime,
    /// The issuing store handle's count of live leases (decremented on drop).
    active: Arc<AtomicUsize>,
}

impl RunLease {
    /// The lease file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// When the run started (entries used since then are protected from `gc`).
    pub fn started(&self) -> SystemTime {
        self.started
    }
}

impl Drop for RunLease {
    fn drop(&mut self) {
        // Remove while still holding the lock, then close (which releases it).
        let _ = fs::remove_file(&self.path);
        drop(self.file.take());
        self.active.fetch_sub(1, Ordering::Relaxed);
    }
}

/// A live run found in `<root>/runs/`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LiveRun {
    pub pid: u32,
    pub started: SystemTime,
    pub lease_file: PathBuf,
}

/// Creates and locks a new lease in `runs_dir`. The file is locked before it gets its `.lease` name, so nobody
/// can ever see an unlocked lease of a live run.
/// `active` counts the live leases of the issuing store handle.
pub(crate) fn acquire(runs_dir: &Path, active: Arc<AtomicUsize>) -> Result<RunLease, StoreError> {
    fs::create_dir_all(runs_dir).map_err(StoreError::io("create folder", runs_dir))?;
    let started = SystemTime::now();
    let pid = std::process::id();
    let stem = format!(
        "{pid}-{}-{}",
        system_time_ns(started),
        LEASE_COUNTER.fetch_add(1, Ordering::Relaxed)
    );
    let tmp = runs_dir.join(format!(".{stem}.tmp"));
    let path = runs_dir.join(format!("{stem}.{LEASE_EXT}"));
    let result = (|| {
        let mut file = File::create(&tmp).map_err(StoreError::io("create lease file", &tmp))?;
        file.lock()
            .map_err(StoreError::io("lock lease file", &tmp))?;
        writeln!(file, "pid {pid}\nstarted_ns {}", system_time_ns(started))
            .map_err(StoreError::io("write lease file", &tmp))?;
        fs::rename(&tmp, &path).map_err(StoreError::io("rename lease file", &tmp))?;
        Ok(file)
    })();
    match result {
        Ok(file) => {
            active.fetch_add(1, Ordering::Relaxed);
            Ok(RunLease {
                file: Some(file),
                path,
                started,
                active,
            })
        }
        Err(e) => {
            let _ = fs::remove_file(&tmp);
            Err(e)
        }
    }
}

fn parse_lease(text: &str) -> Option<(u32, SystemTime)> {
    let mut pid = None;
    let mut started = None;
    for line in text.lines() {
        match line.split_once(' ') {
            Some(("pid", v)) => pid = v.trim().parse::<u32>().ok(),
            Some(("started_ns", v)) => {
                let ns = v.trim().parse::<u64>().ok()?;
                started = Some(UNIX_EPOCH + Duration::from_nanos(ns));
            }
            _ => {}
        }
    }
    Some((pid?, started?))
}

/// Temporaries older than this are left-overs of crashed processes.
pub(crate) const STALE_TEMP_AGE: Duration = Duration::from_secs(3600);

/// Lists live runs; removes leases of dead runs (their lock is free) and old left-over temporaries.
/// Returns (live runs sorted by start, number of stale leases removed).
pub(crate) fn scan(runs_dir: &Path) -> Result<(Vec<LiveRun>, usize), StoreError> {
    let dir = match fs::read_dir(runs_dir) {
        Ok(d) => d,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((Vec::new(), 0)),
        Err(e) => return Err(StoreError::io("list", runs_dir)(e)),
    };
    let mut live = Vec::new();
    let mut stale = 0;
    for item in dir {
        let item = item.map_err(StoreError::io("list", runs_dir))?;
        let path = item.path();
        let name = item.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') && name.ends_with(".tmp") {
            let old = item
                .metadata()
                .ok()
                .and_then(|m| m.modified().ok())
                .and_then(|t| t.elapsed().ok());
            if old.is_some_and(|age| age > STALE_TEMP_AGE) {
                let _ = fs::remove_file(&path);
            }
            continue;
        }
        if path.extension().and_then(|e| e.to_str()) != Some(LEASE_EXT) {
            continue;
        }
        let mut file = match File::open(&path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue, // the run just ended
            Err(e) => return Err(StoreError::io("open lease file", &path)(e)),
        };
        match file.try_lock() {
            Ok(()) => {
                // Nobody holds it: the run died. Remove while holding the lock.
                if fs::remove_file(&path).is_ok() {
                    stale += 1;
                }
            }
            Err(TryLockError::WouldBlock) | Err(TryLockError::Error(_)) => {
                // Held (or lock state unknown): a live run. An unreadable lease protects everything.
                let mut text = String::new();
                let parsed = file
                    .read_to_string(&mut text)
                    .ok()
                    .and_then(|_| parse_lease(&text));
                let (pid, started) = parsed.unwrap_or((0, UNIX_EPOCH));
                live.push(LiveRun {
                    pid,
                    started,
                    lease_file: path,
                });
            }
        }
    }
    live.sort_by(|a, b| (a.started, &a.lease_file).cmp(&(b.started, &b.lease_file)));
    Ok((live, stale))
}

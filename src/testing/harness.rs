//! An engine environment for tests and benchmarks: a cache folder opened with its stat cache and silent
//! progress, so a test or benchmark runs a graph or a session in one call; and the process' CPU time and
//! resident-memory counters that the engine benchmarks report.

use crate::dag::progress::{Progress, ProgressMode};
use crate::dag::{execute, Dag, Env, Mode, Outcome, Session};
use crate::hashing::StatCache;
use crate::store::{Store, StoreError};
use std::path::Path;
use std::time::Duration;

/// A store with its stat cache and silent progress: everything [`Env`] borrows.
pub struct SilentEngine {
    pub store: Store,
    pub stat_cache: StatCache,
    pub progress: Progress,
}

impl SilentEngine {
    /// Open (or create) the cache folder `cache`.
    pub fn open(cache: &Path) -> Result<SilentEngine, StoreError> {
        let store = Store::open(cache)?;
        let stat_cache = StatCache::open(store.root());
        Ok(SilentEngine {
            store,
            stat_cache,
            progress: Progress::new(ProgressMode::Silent),
        })
    }

    /// The environment the executor runs in.
    pub fn env(&self) -> Env<'_> {
        Env {
            store: &self.store,
            stat_cache: &self.stat_cache,
            progress: &self.progress,
        }
    }

    /// Execute `dag` in `mode`.
    pub fn execute(&self, dag: &Dag, mode: Mode) -> Outcome {
        execute(dag, &self.env(), mode)
    }

    /// A staged session over this store.
    pub fn session(&self, mode: Mode) -> Session<'_> {
        Session::new(&self.store, &self.stat_cache, &self.progress, mode)
    }
}

/// CPU time (user + system, all threads) of the whole process so far: on a loaded machine this is the
/// process' own cost, independent of waiting for a core.
pub fn cpu_time() -> Duration {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

/// [`cpu_time`] in seconds.
pub fn cpu_seconds() -> f64 {
    cpu_time().as_secs_f64()
}

/// A `kB` field of `/proc/self/status` (`VmRSS`, `VmHWM`), in bytes (0 where the file or field is absent).
pub fn status_bytes(field: &str) -> u64 {
    let text = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    text.lines()
        .find_map(|l| l.strip_prefix(field)?.strip_prefix(':'))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}

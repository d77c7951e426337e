//! Helpers shared by the peer-comparison benches (`phasecorr`, `ortho`, `mi`, `daisy_agast`), `imaging`, the
//! adjustment benches and `ingest_decode`: the folder the identical inputs go to, thread CPU time, peak memory,
//! median and one-shot timers and a minimal `.npy` writer. Included with
//! `#[path = "peer_support/mod.rs"] mod peer_support;` (not a bench target of its own).

#![allow(dead_code)]

pub mod shifted_pair;

use std::path::{Path, PathBuf};
use std::time::Instant;

/// `$SKYTIE_PEER_DIR/<name>/`, default `<temp>/skytie_peers/<name>/` (`/tmp/skytie_peers/...` on Linux).
pub fn peer_dir(name: &str) -> PathBuf {
    std::env::var_os("SKYTIE_PEER_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("skytie_peers"))
        .join(name)
}

/// CPU time of the calling thread in ns (`clock_gettime(CLOCK_THREAD_CPUTIME_ID)`, as Python's
/// `time.thread_time_ns`), robust against other processes sharing the cores; `None` where unavailable.
/// (`/proc/thread-self/schedstat`, used before, advances only at scheduler ticks — 4 ms steps here — for a
/// running thread, too coarse for sub-millisecond rounds.)
pub fn thread_cpu_ns() -> Option<u64> {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; the call only writes it.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    (rc == 0).then(|| ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64)
}

/// Median over `reps` rounds of the time of one call of `round`, ms: thread CPU time of the calling thread
/// (wall time where unavailable). Work `round` hands to other threads is not counted: run it single-threaded.
pub fn median_round_ms(reps: usize, mut round: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let (c0, s) = (thread_cpu_ns(), Instant::now());
            round();
            match (c0, thread_cpu_ns()) {
                (Some(a), Some(b)) => b.saturating_sub(a) as f64 * 1e-6,
                _ => s.elapsed().as_secs_f64() * 1e3,
            }
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Wall seconds of `f`, and its result.
pub fn timed<T>(f: impl FnOnce() -> T) -> (f64, T) {
    let s = Instant::now();
    let r = f();
    (s.elapsed().as_secs_f64(), r)
}

/// Median over `reps` runs of the wall time of one call of `f`, ms.
pub fn median_wall_ms(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Minimal NumPy `.npy` (format 1.0) writer for a row-major float32 array of shape (rows, cols).
pub fn write_npy_f32(path: &Path, rows: usize, cols: usize, data: &[f32]) {
    let mut header =
        format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({rows}, {cols}), }}");
    // Magic (6) + version (2) + header length (2) + header, padded with spaces to a multiple of 64, ending in \n.
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = Vec::with_capacity(10 + header.len() + 4 * data.len());
    bytes.extend_from_slice(b"\x93NUMPY\x01\x00");
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in data {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes).expect("write .npy");
}

/// The process' peak resident memory so far (`VmHWM`), MiB; NaN where `/proc` does not say.
pub fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kib| kib / 1024.0)
}

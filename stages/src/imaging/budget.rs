//! The process-wide memory budget for image data: decoders reserve the buffers they need from it before
//! allocating them, waiting while other images hold it, and the tile cache of the engine sizes itself by it.
//! An image whose decoding alone needs more than the budget is refused with an error that names the file,
//! its size in pixels and how to raise the budget ([`RAISE_HINT`]).
//!
//! The default is a quarter of the memory the system reports available (`MemAvailable` of
//! `/proc/meminfo`), at least 512 MiB and at most 2 GiB: enough for a 450-megapixel frame's grey plane
//! while leaving the rest of a small machine to the stages.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, OnceLock};

/// How the user raises the budget; appended to every budget error.
pub const RAISE_HINT: &str =
    "raise the memory budget with `--memory-budget SIZE` (e.g. 4G) or the environment variable SKYTIE_MEMORY_BUDGET";

/// Smallest and largest default budget, bytes.
const DEFAULT_MIN: usize = 512 << 20;
const DEFAULT_MAX: usize = 2 << 30;

/// A budget of bytes that reservations draw from.
pub struct MemoryBudget {
    total: AtomicUsize,
    used: Mutex<usize>,
    freed: Condvar,
}

/// Bytes held from a [`MemoryBudget`] until dropped.
pub struct Reservation<'a> {
    budget: &'a MemoryBudget,
    bytes: usize,
}

impl Drop for Reservation<'_> {
    fn drop(&mut self) {
        let mut used = self.budget.used.lock().unwrap_or_else(|p| p.into_inner());
        *used = used.saturating_sub(self.bytes);
        self.budget.freed.notify_all();
    }
}

impl MemoryBudget {
    pub fn new(total: usize) -> Self {
        Self {
            total: AtomicUsize::new(total),
            used: Mutex::new(0),
            freed: Condvar::new(),
        }
    }

    /// The budget, bytes.
    pub fn total(&self) -> usize {
        self.total.load(Ordering::Relaxed)
    }

    /// Sets the budget (bytes; at least 1 MiB).
    pub fn set_total(&self, bytes: usize) {
        self.total.store(bytes.max(1 << 20), Ordering::Relaxed);
        self.freed.notify_all();
    }

    /// Reserves `bytes`, waiting until other reservations leave room. `Err` (with the budget in bytes) when
    /// `bytes` alone exceeds the budget: waiting would never help.
    pub fn reserve(&self, bytes: usize) -> Result<Reservation<'_>, usize> {
        let mut used = self.used.lock().unwrap_or_else(|p| p.into_inner());
        loop {
            let total = self.total();
            if bytes > total {
                return Err(total);
            }
            if *used + bytes <= total || *used == 0 {
                *used += bytes;
                return Ok(Reservation {
                    budget: self,
                    bytes,
                });
            }
            used = self.freed.wait(used).unwrap_or_else(|p| p.into_inner());
        }
    }

    /// Bytes currently reserved.
    pub fn used(&self) -> usize {
        *self.used.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// The process' budget (initialised with [`default_budget_bytes`], or `SKYTIE_MEMORY_BUDGET` when set and
/// valid).
pub fn global() -> &'static MemoryBudget {
    static BUDGET: OnceLock<MemoryBudget> = OnceLock::new();
    BUDGET.get_or_init(|| {
        let from_env = std::env::var("SKYTIE_MEMORY_BUDGET")
            .ok()
            .and_then(|s| parse_size(&s).ok());
        MemoryBudget::new(from_env.unwrap_or_else(default_budget_bytes))
    })
}

/// A quarter of the available memory, clamped to [512 MiB, 2 GiB] (512 MiB when it cannot be read).
pub fn default_budget_bytes() -> usize {
    let available = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("MemAvailable:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<usize>().ok())
        })
        .map(|kib| kib.saturating_mul(1024));
    match available {
        Some(bytes) => (bytes / 4).clamp(DEFAULT_MIN, DEFAULT_MAX),
        None => DEFAULT_MIN,
    }
}

/// Parses a size such as `4G`, `512M`, `2GiB`, `1500000000` (bytes; K/M/G/T are powers of 1024).
pub fn parse_size(text: &str) -> Result<usize, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("'{text}' is not a size (use e.g. 4G, 512M or a number of bytes)"))?;
    let factor: f64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" | "kib" => 1024.0,
        "m" | "mb" | "mib" => 1024.0 * 1024.0,
        "g" | "gb" | "gib" => 1024.0 * 1024.0 * 1024.0,
        "t" | "tb" | "tib" => 1024.0f64.powi(4),
        other => {
            return Err(format!(
                "unknown size unit '{other}' in '{text}' (use K, M, G or T)"
            ))
        }
    };
    let bytes = value * factor;
    if !(bytes.is_finite() && bytes >= (1 << 20) as f64 && bytes < usize::MAX as f64) {
        return Err(format!(
            "'{text}' is not a usable memory budget (at least 1M)"
        ));
    }
    Ok(bytes as usize)
}

/// `bytes` for messages: "1.5 GiB", "300 MiB".
pub fn human_bytes(bytes: usize) -> String {
    let b = bytes as f64;
    if b >= (1u64 << 30) as f64 {
        format!("{:.1} GiB", b / (1u64 << 30) as f64)
    } else {
        format!("{:.0} MiB", (b / (1u64 << 20) as f64).ceil())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn sizes_parse_with_units() {
        assert_eq!(parse_size("4G").unwrap(), 4 << 30);
        assert_eq!(parse_size("512MiB").unwrap(), 512 << 20);
        assert_eq!(parse_size("1.5g").unwrap(), 3 << 29);
        assert_eq!(parse_size("2000000").unwrap(), 2_000_000);
        assert!(parse_size("12x").is_err());
        assert!(parse_size("10").is_err());
        assert!(parse_size("G").is_err());
        assert_eq!(human_bytes(3 << 29), "1.5 GiB");
        assert_eq!(human_bytes(300 << 20), "300 MiB");
    }

    #[test]
    fn reservations_wait_for_room_and_oversized_ones_fail() {
        let b = Arc::new(MemoryBudget::new(100 << 20));
        assert_eq!(b.reserve(200 << 20).err(), Some(100 << 20));
        let first = b.reserve(70 << 20).unwrap();
        let b2 = Arc::clone(&b);
        let waiter = std::thread::spawn(move || {
            let _r = b2.reserve(50 << 20).unwrap();
            b2.used()
        });
        std::thread::sleep(std::time::Duration::from_millis(50));
        assert_eq!(b.used(), 70 << 20, "the second reservation must wait");
        drop(first);
        assert_eq!(waiter.join().unwrap(), 50 << 20);
        assert_eq!(b.used(), 0);
    }

    #[test]
    fn the_default_is_clamped() {
        let d = default_budget_bytes();
        assert!((DEFAULT_MIN..=DEFAULT_MAX).contains(&d));
    }
}

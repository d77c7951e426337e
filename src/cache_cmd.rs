//! Bodies of the `skytie cache stats | verify | gc` commands (the CLI wires them in): human-readable tables
//! built from [`Store::stats`], [`Store::verify`] and [`Store::gc`] (and, with a remote, [`Store::verify_remote`]
//! and [`Store::gc_remote`]), and size and age parsing for `--max-size` and `--remote-min-age`.

use std::fmt::Write;
use std::time::Duration;

use crate::dag::record::{NodeRecord, NODES_NS, OUTPUT_NS};
use crate::hashing::{ContentHash, NodeKey};
use crate::store::Store;

/// Parses an age such as `0`, `90s`, `30m`, `6h`, `2d` (a number without unit is seconds).
pub fn parse_age(text: &str) -> Result<Duration, String> {
    let t = text.trim();
    let split = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let seconds_per = match unit.trim() {
        "" | "s" => 1,
        "m" => 60,
        "h" => 3600,
        "d" => 86_400,
        _ => 0,
    };
    match number.parse::<u64>() {
        Ok(n) if seconds_per > 0 => Ok(Duration::from_secs(n.saturating_mul(seconds_per))),
        _ => Err(format!(
            "invalid age `{text}`: write a whole number with an optional unit s, m, h or d (e.g. 30m, 6h, 2d, 0)"
        )),
    }
}

/// The key a node record (JSON) names: the roots of the remote collection.
fn record_key(payload: &[u8]) -> Option<NodeKey> {
    let record: NodeRecord = serde_json::from_slice(payload).ok()?;
    ContentHash::from_hex(&record.ran_with.key).ok()
}

/// Parses a size such as `10G`, `500M`, `1.5GiB`, `64k`, `0` or `123456` (bytes). Suffixes K, M, G, T are
/// binary multiples (1K = 1024 bytes); an optional `B`/`iB` after them is accepted; case does not matter.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let err = |why: &str| {
        format!("invalid size `{text}`: {why}; write a number with an optional unit K, M, G or T (e.g. 10G, 500M, 0)")
    };
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    if number.is_empty() {
        return Err(err("no number"));
    }
    let unit = unit.trim().to_ascii_uppercase();
    let unit = unit
        .strip_suffix("IB")
        .or_else(|| unit.strip_suffix('B'))
        .unwrap_or(&unit);
    let shift = match unit {
        "" => 0,
        "K" => 10,
        "M" => 20,
        "G" => 30,
        "T" => 40,
        _ => return Err(err("unknown unit")),
    };
    let multiplier = (1u64 << shift) as f64;
    let value: f64 = number.parse().map_err(|_| err("not a number"))?;
    let bytes = (value * multiplier).round();
    if !bytes.is_finite() || bytes >= u64::MAX as f64 {
        return Err(err("too large"));
    }
    if shift == 0 && number.contains('.') {
        return Err(err("a byte count must be a whole number"));
    }
    Ok(bytes as u64)
}

/// `1536` → `1.5 KiB`; exact byte counts below 1 KiB.
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit < UNITS.len() - 1 {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// One row of the `cache stats` table: a label, an entry count and their size.
fn stats_row(out: &mut String, label: &str, entries: u64, bytes: u64) {
    let _ = writeln!(out, "{label:<28} {entries:>10} {:>12}", format_bytes(bytes));
}

/// `skytie cache stats`: totals and a per-stage table.
pub fn stats(store: &Store) -> String {
    let stats = match store.stats() {
        Ok(s) => s,
        Err(e) => return format!("{e}\n"),
    };
    let mut out = String::new();
    let _ = writeln!(out, "cache {}", store.root().display());
    let _ = writeln!(out, "{:<28} {:>10} {:>12}", "stage", "entries", "size");
    for (stage, s) in &stats.per_stage {
        stats_row(&mut out, stage, s.entries, s.bytes);
    }
    if stats.unreadable.entries > 0 {
        let u = &stats.unreadable;
        stats_row(&mut out, "(unreadable or old format)", u.entries, u.bytes);
    }
    stats_row(&mut out, "total", stats.entries, stats.bytes);
    let r = &stats.records;
    stats_row(&mut out, "records", r.entries, r.bytes);
    let _ = writeln!(out, "live runs: {}", stats.live_runs);
    out
}

/// The lines of one verified store in `cache verify`: its summary, then each damaged entry (where it is,
/// what is wrong) with what was done about it (`actions`: the words for removed and for not removed).
fn verify_lines<'a>(
    out: &mut String,
    summary: &str,
    bad: impl Iterator<Item = (String, &'a str, bool)>,
    actions: [&str; 2],
) {
    let _ = writeln!(out, "{summary}");
    for (place, reason, removed) in bad {
        let action = actions[usize::from(!removed)];
        let _ = writeln!(out, "  {place}  {reason} — {action}");
    }
}

/// `skytie cache verify`: re-hashes every entry; the flag is false if any entry was bad (exit status 1).
pub fn verify(store: &Store) -> (String, bool) {
    let report = match store.verify() {
        Ok(r) => r,
        Err(e) => return (format!("{e}\n"), false),
    };
    let mut out = String::new();
    let summary = format!(
        "checked {} entries ({}): {} ok, {} bad",
        report.checked,
        format_bytes(report.bytes_checked),
        report.ok,
        report.bad.len()
    );
    let bad = report
        .bad
        .iter()
        .map(|b| (b.path.display().to_string(), b.reason.as_str(), b.removed));
    verify_lines(&mut out, &summary, bad, ["removed", "could NOT be removed"]);
    if report.temp_files_removed > 0 {
        let _ = writeln!(
            out,
            "removed {} left-over temporary files of crashed writes",
            report.temp_files_removed
        );
    }
    let mut all_ok = report.all_ok();
    match store.verify_remote() {
        None => {}
        Some(Err(e)) => {
            let _ = writeln!(out, "remote: {e}");
            all_ok = false;
        }
        Some(Ok(remote)) => {
            let summary = format!(
                "remote {}: checked {} entries ({}) and {} generated folders: {} bad",
                remote.url,
                remote.entries_checked,
                format_bytes(remote.bytes_checked),
                remote.folders_checked,
                remote.bad.len()
            );
            let bad = remote
                .bad
                .iter()
                .map(|b| (b.name.clone(), b.reason.as_str(), b.removed));
            let actions = ["deleted from the remote", "could NOT be deleted"];
            verify_lines(&mut out, &summary, bad, actions);
            all_ok &= remote.bad.is_empty();
        }
    }
    if !all_ok {
        let _ = writeln!(
            out,
            "bad entries will be recomputed by the next `skytie run`"
        );
    }
    (out, all_ok)
}

/// `skytie cache gc --max-size SIZE`: [`gc_with`] with the default `--remote-min-age` of one hour.
pub fn gc(store: &Store, max_size: &str) -> Result<String, String> {
    gc_with(store, max_size, DEFAULT_REMOTE_MIN_AGE)
}

/// Default of `--remote-min-age`.
pub const DEFAULT_REMOTE_MIN_AGE: &str = "1h";

/// `skytie cache gc --max-size SIZE [--remote-min-age AGE]`: removes least-recently-used entries until the
/// cache folder fits in SIZE; with a remote, then removes the remote results no node record points to.
pub fn gc_with(store: &Store, max_size: &str, remote_min_age: &str) -> Result<String, String> {
    let max_bytes = parse_size(max_size)?;
    let min_age = parse_age(remote_min_age)?;
    let report = store.gc(max_bytes).map_err(|e| e.to_string())?;
    let mut out = String::new();
    let _ = writeln!(out, "{:<22} {:>10} {:>12}", "", "entries", "size");
    let row = |out: &mut String, label: &str, n: u64, b: u64| {
        let _ = writeln!(out, "{:<22} {:>10} {:>12}", label, n, format_bytes(b));
    };
    row(
        &mut out,
        "before",
        report.entries_before,
        report.bytes_before,
    );
    row(
        &mut out,
        "removed (LRU first)",
        report.removed_entries,
        report.removed_bytes,
    );
    row(
        &mut out,
        "kept in use by runs",
        report.protected_entries,
        report.protected_bytes,
    );
    row(&mut out, "after", report.kept_entries, report.kept_bytes);
    let _ = writeln!(
        out,
        "limit {} ({} bytes); live runs: {}",
        format_bytes(max_bytes),
        max_bytes,
        report.live_runs
    );
    if report.stale_leases_removed > 0 {
        let _ = writeln!(
            out,
            "removed {} stale lease(s) of crashed runs",
            report.stale_leases_removed
        );
    }
    if report.temp_files_removed > 0 {
        let _ = writeln!(
            out,
            "removed {} left-over temporary files of crashed writes",
            report.temp_files_removed
        );
    }
    if report.kept_bytes > max_bytes {
        let _ = writeln!(
            out,
            "the cache is still above the limit because live runs use the kept entries"
        );
    }
    for failure in &report.failures {
        let _ = writeln!(out, "warning: {failure}");
    }
    if let Some(remote) = store.gc_remote(NODES_NS, &record_key, OUTPUT_NS, min_age) {
        let r = remote.map_err(|e| e.to_string())?;
        let _ = writeln!(out, "remote {}:", r.url);
        row(&mut out, "before", r.entries_before, r.bytes_before);
        row(
            &mut out,
            "removed (unreachable)",
            r.removed_keys.len() as u64,
            r.removed_bytes,
        );
        row(&mut out, "after", r.kept_entries, r.kept_bytes);
        let _ = writeln!(
            out,
            "roots: {} node records{}; {} unreachable entries younger than {} s kept; {} folders and {} output \
             records removed",
            r.roots,
            if r.unreadable_roots > 0 {
                format!(" ({} unreadable)", r.unreadable_roots)
            } else {
                String::new()
            },
            r.young_entries,
            r.min_age.as_secs(),
            r.removed_folders,
            r.removed_records
        );
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units_and_clear_errors() {
        assert_eq!(parse_size("0"), Ok(0));
        assert_eq!(parse_size("123"), Ok(123));
        assert_eq!(parse_size("10G"), Ok(10 << 30));
        assert_eq!(parse_size("500M"), Ok(500 << 20));
        assert_eq!(parse_size("500mb"), Ok(500 << 20));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("64k"), Ok(64 << 10));
        assert_eq!(parse_size(" 2T "), Ok(2 << 40));
        for bad in ["", "G", "10X", "-5M", "1.2.3G", "1.5", "99999999999T"] {
            let e = parse_size(bad).unwrap_err();
            assert!(
                e.contains("invalid size") && e.contains("10G"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn ages_parse_with_units_and_clear_errors() {
        assert_eq!(parse_age("0"), Ok(Duration::ZERO));
        assert_eq!(parse_age("90s"), Ok(Duration::from_secs(90)));
        assert_eq!(parse_age("30m"), Ok(Duration::from_secs(1800)));
        assert_eq!(parse_age(" 6h"), Ok(Duration::from_secs(6 * 3600)));
        assert_eq!(parse_age("2d"), Ok(Duration::from_secs(2 * 86_400)));
        for bad in ["", "h", "1.5h", "3w", "-1h"] {
            let e = parse_age(bad).unwrap_err();
            assert!(e.contains("invalid age") && e.contains("30m"), "{bad}: {e}");
        }
    }

    #[test]
    fn bytes_format_readably() {
        assert_eq!(format_bytes(0), "0 B");
        assert_eq!(format_bytes(1023), "1023 B");
        assert_eq!(format_bytes(1536), "1.5 KiB");
        assert_eq!(format_bytes(10 << 30), "10.0 GiB");
    }
}

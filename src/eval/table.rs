//! The evaluation table: per preset × profile, each metric's mean and worst case over the held-out seeds
//! (worst = lowest for a higher-is-better metric, highest otherwise), with the seed-to-seed SD kept for the
//! noise bands of the regression guard. Printed as a Markdown table.

use super::grade::{Better, CellMetrics, METRICS};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Mean, worst case and SD of one metric over a row's seeds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub mean: f64,
    pub worst: f64,
    pub sd: f64,
    /// Seeds that produced the metric.
    pub n: usize,
}

/// One row: a preset and profile over its seeds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub seeds: Vec<u64>,
    /// Cells whose run failed (no metrics).
    pub failed: usize,
    pub metrics: BTreeMap<String, Summary>,
}

/// The table: rows keyed `preset/profile`.
pub type Table = BTreeMap<String, Row>;

/// Summary of `values` for a metric that gets better in direction `better`.
pub fn summarize(values: &[f64], better: Better) -> Option<Summary> {
    if values.is_empty() {
        return None;
    }
    let n = values.len();
    let mean = values.iter().sum::<f64>() / n as f64;
    let sd = if n > 1 {
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        0.0
    };
    let worst = match better {
        Better::Higher => values.iter().copied().fold(f64::INFINITY, f64::min),
        _ => values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    };
    Some(Summary { mean, worst, sd, n })
}

/// The table of `cells`: (row key `preset/profile`, seed, metrics or `None` for a failed run).
pub fn build_table(cells: &[(String, u64, Option<CellMetrics>)]) -> Table {
    let mut grouped: BTreeMap<String, Vec<(u64, Option<&CellMetrics>)>> = BTreeMap::new();
    for (key, seed, m) in cells {
        grouped
            .entry(key.clone())
            .or_default()
            .push((*seed, m.as_ref()));
    }
    grouped
        .into_iter()
        .map(|(key, runs)| {
            let metrics = METRICS
                .iter()
                .filter_map(|d| {
                    let v: Vec<f64> = runs
                        .iter()
                        .filter_map(|(_, m)| m.and_then(|m| m.get(d.key).copied()))
                        .collect();
                    summarize(&v, d.better).map(|s| (d.key.to_string(), s))
                })
                .collect();
            let row = Row {
                seeds: runs.iter().map(|(s, _)| *s).collect(),
                failed: runs.iter().filter(|(_, m)| m.is_none()).count(),
                metrics,
            };
            (key, row)
        })
        .collect()
}

/// A number for the table: ratios and metres with 3 decimals, counts as integers.
fn fmt(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() >= 1.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.3}")
    }
}

/// The table as Markdown: one row per preset/profile, each cell `mean (worst)`.
pub fn render_markdown(table: &Table) -> String {
    let mut t = String::from("| preset/profile | seeds |");
    for d in &METRICS {
        t.push_str(&format!(" {} |", d.title));
    }
    t.push_str("\n|---|---|");
    t.push_str(&"---:|".repeat(METRICS.len()));
    t.push('\n');
    for (key, row) in table {
        let failed = if row.failed > 0 {
            format!(" ({} failed)", row.failed)
        } else {
            String::new()
        };
        t.push_str(&format!("| {key} | {}{failed} |", row.seeds.len()));
        for d in &METRICS {
            match row.metrics.get(d.key) {
                Some(s) if d.better == Better::Shown => t.push_str(&format!(" {} |", fmt(s.mean))),
                Some(s) => t.push_str(&format!(" {} ({}) |", fmt(s.mean), fmt(s.worst))),
                None => t.push_str(" – |"),
            }
        }
        t.push('\n');
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_hold_mean_worst_and_sd_per_metric_and_count_failures() {
        let m = |inl: f64, cp: f64| {
            let mut c = CellMetrics::new();
            c.insert("nadir_inlier".into(), inl);
            c.insert("cp_2d_after".into(), cp);
            Some(c)
        };
        let cells = vec![
            ("demo/thesis".to_string(), 101, m(0.98, 0.04)),
            ("demo/thesis".to_string(), 102, m(0.96, 0.06)),
            ("demo/thesis".to_string(), 103, None),
        ];
        let t = build_table(&cells);
        let row = &t["demo/thesis"];
        assert_eq!((row.seeds.len(), row.failed), (3, 1));
        let inl = row.metrics["nadir_inlier"];
        assert!((inl.mean - 0.97).abs() < 1e-12 && inl.worst == 0.96 && inl.n == 2);
        assert!((inl.sd - 0.02f64.hypot(0.0) / 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(row.metrics["cp_2d_after"].worst, 0.06);
        let md = render_markdown(&t);
        assert!(
            md.contains("| demo/thesis | 3 (1 failed) | 0.970 (0.960) |"),
            "{md}"
        );
    }
}

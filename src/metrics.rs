//! Run metrics: per-stage counters and timings, the engine totals, the sections nodes contribute
//! (`DagBuilder::metrics`), and the files `OUT/metrics.json`, `OUT/variants/<name>/metrics.json` and
//! `OUT/sweep.csv` (one row per variant, one column per numeric metric leaf).
//!
//! `metrics.json` schema: `{ "engine": { nodes_total, nodes_executed, nodes_cached, nodes_failed,
//! nodes_skipped, seconds, warnings }, "stages": { <stage>: { executed, cached, failed, skipped, seconds } },
//! <namespace>: { … contributed by nodes … } }`. In a sweep the top-level file holds ONLY the engine and
//! stage counts of the whole (shared) graph plus `"variants": [names]` (no contributed sections: they differ
//! per variant); each variant's file holds the counts of the nodes that variant uses (its `engine.seconds`
//! and `engine.warnings` are those of the whole run) and its contributed sections. `sweep.csv` has one row per
//! variant and one column per numeric leaf of the contributed sections (see [`sweep_csv`]).

use crate::dag::{NodeReport, NodeStatus};
use serde_json::{json, Map, Value};
use skytie_util::csv_out::quote;
use std::collections::BTreeMap;
use std::io;
use std::path::Path;

/// Counters of one stage.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StageCounts {
    pub executed: usize,
    pub cached: usize,
    pub failed: usize,
    pub skipped: usize,
    /// Seconds spent running this stage's nodes (sum over nodes, i.e. CPU-ish time, not wall time).
    pub seconds: f64,
}

/// Counters of a set of nodes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Summary {
    pub stages: BTreeMap<String, StageCounts>,
    pub total: StageCounts,
    pub nodes_total: usize,
}

impl Summary {
    /// Count `reports` (e.g. all nodes of a run, or those of one variant).
    pub fn of<'a>(reports: impl IntoIterator<Item = &'a NodeReport>) -> Summary {
        let mut s = Summary::default();
        for r in reports {
            s.nodes_total += 1;
            let c = s.stages.entry(r.stage.to_string()).or_default();
            for c in [c, &mut s.total] {
                match &r.status {
                    NodeStatus::Executed => c.executed += 1,
                    NodeStatus::Cached => c.cached += 1,
                    NodeStatus::Failed(_) => c.failed += 1,
                    NodeStatus::Skipped { .. } | NodeStatus::WillRun { .. } => c.skipped += 1,
                }
                c.seconds += r.seconds;
            }
        }
        s
    }

    /// The `engine` and `stages` sections; `wall_seconds` is the run's elapsed time.
    pub fn to_json(&self, wall_seconds: f64, warnings: usize) -> Value {
        let mut stages = Map::new();
        for (name, c) in &self.stages {
            stages.insert(
                name.clone(),
                json!({ "executed": c.executed, "cached": c.cached, "failed": c.failed, "skipped": c.skipped,
                        "seconds": round6(c.seconds) }),
            );
        }
        json!({
            "engine": {
                "nodes_total": self.nodes_total,
                "nodes_executed": self.total.executed,
                "nodes_cached": self.total.cached,
                "nodes_failed": self.total.failed,
                "nodes_skipped": self.total.skipped,
                "seconds": round6(wall_seconds),
                "warnings": warnings,
            },
            "stages": Value::Object(stages),
        })
    }

    /// The summary table printed at the end of a run.
    pub fn table(&self, wall_seconds: f64) -> String {
        let mut out = String::new();
        out.push_str(&format!(
            "{:<20} {:>9} {:>9} {:>9} {:>9} {:>10}\n",
            "stage", "executed", "cached", "failed", "skipped", "seconds"
        ));
        for (name, c) in &self.stages {
            out.push_str(&format!(
                "{:<20} {:>9} {:>9} {:>9} {:>9} {:>10.2}\n",
                name, c.executed, c.cached, c.failed, c.skipped, c.seconds
            ));
        }
        let t = &self.total;
        out.push_str(&format!(
            "{:<20} {:>9} {:>9} {:>9} {:>9} {:>10.2}  (wall {:.2} s)\n",
            "total", t.executed, t.cached, t.failed, t.skipped, t.seconds, wall_seconds
        ));
        out
    }
}

fn round6(x: f64) -> f64 {
    (x * 1e6).round() / 1e6
}

/// Insert contributed sections (namespace → object) into a metrics object; a namespace contributed twice
/// is merged key by key, recursively.
pub fn add_sections<'a>(doc: &mut Value, sections: impl IntoIterator<Item = (&'a str, &'a Value)>) {
    let Value::Object(map) = doc else { return };
    for (ns, v) in sections {
        match map.get_mut(ns) {
            Some(existing) => merge_json(existing, v),
            None => {
                map.insert(ns.to_string(), v.clone());
            }
        }
    }
}

/// Merge `new` into `into`: objects key by key, recursively (two nodes may contribute different leaves of one
/// subtree, e.g. `adjust.combined.checkpoints` and `adjust.combined.recordings`); anything else is replaced.
fn merge_json(into: &mut Value, new: &Value) {
    match (into, new) {
        (Value::Object(existing), Value::Object(new)) => {
            for (k, x) in new {
                match existing.get_mut(k) {
                    Some(e) => merge_json(e, x),
                    None => {
                        existing.insert(k.clone(), x.clone());
                    }
                }
            }
        }
        (into, new) => *into = new.clone(),
    }
}

/// Numeric leaves of a JSON value as dotted paths (for sweep.csv columns): object members by key, array
/// elements by index (`ortho.histogram.3`), booleans as 1/0; strings and nulls are not numeric and skipped.
pub fn numeric_leaves(prefix: &str, v: &Value, out: &mut BTreeMap<String, f64>) {
    let child = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                numeric_leaves(&child(k), x, out);
            }
        }
        Value::Array(items) => {
            for (i, x) in items.iter().enumerate() {
                numeric_leaves(&child(&i.to_string()), x, out);
            }
        }
        Value::Number(n) => {
            if let Some(f) = n.as_f64() {
                out.insert(prefix.to_string(), f);
            }
        }
        Value::Bool(b) => {
            out.insert(prefix.to_string(), if *b { 1.0 } else { 0.0 });
        }
        Value::String(_) | Value::Null => {}
    }
}

/// Orders dotted column names segment by segment, numeric segments (array indices) by value: `a.2` before
/// `a.10`, `a.b` before `a.b.c` before `a.c`.
fn column_order(a: &str, b: &str) -> std::cmp::Ordering {
    let mut left = a.split('.');
    let mut right = b.split('.');
    loop {
        match (left.next(), right.next()) {
            (None, None) => return std::cmp::Ordering::Equal,
            (None, Some(_)) => return std::cmp::Ordering::Less,
            (Some(_), None) => return std::cmp::Ordering::Greater,
            (Some(x), Some(y)) => {
                let by_value = match (x.parse::<u64>(), y.parse::<u64>()) {
                    (Ok(i), Ok(j)) => i.cmp(&j),
                    _ => std::cmp::Ordering::Equal,
                };
                let order = by_value.then_with(|| x.cmp(y));
                if order.is_ne() {
                    return order;
                }
            }
        }
    }
}

/// `sweep.csv`: one row per variant (in the given order); columns = `variant`, then every numeric leaf
/// ([`numeric_leaves`]) of any variant's document as a dotted path, in `column_order` (the same order for
/// the same metrics, whichever variant has them). A variant lacking a metric has an empty cell. Values are
/// written in Rust's shortest round-trip form (`3`, `0.25`, `1e-7`).
pub fn sweep_csv(rows: &[(String, Value)]) -> String {
    let leaves: Vec<(String, BTreeMap<String, f64>)> = rows
        .iter()
        .map(|(name, doc)| {
            let mut m = BTreeMap::new();
            numeric_leaves("", doc, &mut m);
            (name.clone(), m)
        })
        .collect();
    let mut columns: Vec<String> = leaves.iter().flat_map(|(_, m)| m.keys().cloned()).collect();
    columns.sort_by(|a, b| column_order(a, b));
    columns.dedup();
    let mut out = String::from("variant");
    for c in &columns {
        out.push(',');
        out.push_str(&quote(c));
    }
    out.push('\n');
    for (name, m) in &leaves {
        out.push_str(&quote(name));
        for c in &columns {
            out.push(',');
            if let Some(v) = m.get(c) {
                out.push_str(&format!("{v}"));
            }
        }
        out.push('\n');
    }
    out
}

/// Write pretty JSON atomically.
pub fn write_json(path: &Path, v: &Value) -> io::Result<()> {
    let mut bytes = serde_json::to_vec_pretty(v).map_err(io::Error::other)?;
    bytes.push(b'\n');
    skytie_util::fsutil::atomic_write(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweep_csv_has_one_row_per_variant_and_union_of_columns() {
        let rows = vec![
            ("a".to_string(), json!({"toy": {"sum": 3.0, "count": 2}})),
            (
                "b".to_string(),
                json!({"toy": {"sum": 5.5}, "x": {"flag": true}}),
            ),
        ];
        let csv = sweep_csv(&rows);
        assert_eq!(csv, "variant,toy.count,toy.sum,x.flag\na,2,3,\nb,,5.5,1\n");
    }

    #[test]
    fn sweep_csv_flattens_arrays_and_orders_indices_by_value() {
        let rows = vec![
            (
                "a".to_string(),
                json!({"m": {"h": [0.5, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11], "n": null, "s": "text"},
                       "adjust": {"sigma0": 1.25, "per_axis": {"x": 0.1, "y": [0.2]}}}),
            ),
            ("b,c".to_string(), json!({"m": {"h": [7]}})),
        ];
        let csv = sweep_csv(&rows);
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let mut expected = vec![
            "variant",
            "adjust.per_axis.x",
            "adjust.per_axis.y.0",
            "adjust.sigma0",
        ];
        let h: Vec<String> = (0..12).map(|i| format!("m.h.{i}")).collect();
        expected.extend(h.iter().map(String::as_str));
        assert_eq!(header, expected);
        assert_eq!(
            lines.next().unwrap(),
            "a,0.1,0.2,1.25,0.5,1,2,3,4,5,6,7,8,9,10,11"
        );
        // Names with commas are quoted; missing metrics are empty cells.
        assert_eq!(lines.next().unwrap(), "\"b,c\",,,,7,,,,,,,,,,,");
        assert!(lines.next().is_none());
    }

    #[test]
    fn every_numeric_leaf_of_every_variant_is_a_column_with_its_value() {
        let docs = [
            json!({"campaign": {"recordings": 39, "name": "demo", "ok": true},
                   "ortho": {"images": 39, "valid_fraction_mean": 0.8125}}),
            json!({"campaign": {"recordings": 6}, "extra": {"list": [{"v": -1.5}]}}),
        ];
        let rows: Vec<(String, Value)> = docs
            .iter()
            .enumerate()
            .map(|(i, d)| (format!("v{i}"), d.clone()))
            .collect();
        let csv = sweep_csv(&rows);
        let table: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
        for (row, doc) in table[1..].iter().zip(&docs) {
            let mut leaves = BTreeMap::new();
            numeric_leaves("", doc, &mut leaves);
            for (path, value) in &leaves {
                let col = table[0].iter().position(|c| c == path).unwrap();
                assert_eq!(row[col].parse::<f64>().unwrap(), *value, "{path}");
            }
            let filled = row[1..].iter().filter(|c| !c.is_empty()).count();
            assert_eq!(filled, leaves.len());
        }
        assert!(table[0].contains(&"extra.list.0.v") && table[0].contains(&"campaign.ok"));
        assert!(!table[0].contains(&"campaign.name"));
    }

    #[test]
    fn sections_merge() {
        let mut doc = json!({"engine": {"n": 1}});
        add_sections(
            &mut doc,
            [("toy", &json!({"a": 1})), ("toy", &json!({"b": 2}))],
        );
        assert_eq!(doc, json!({"engine": {"n": 1}, "toy": {"a": 1, "b": 2}}));
    }

    #[test]
    fn sections_merge_recursively() {
        let mut doc = json!({});
        let first = json!({"combined": {"checkpoints": {"x": 1}, "cost": 2}});
        let second = json!({"combined": {"recordings": {"after": 3}, "cost": 4}});
        add_sections(&mut doc, [("adjust", &first), ("adjust", &second)]);
        assert_eq!(
            doc,
            json!({"adjust": {"combined": {"checkpoints": {"x": 1}, "recordings": {"after": 3}, "cost": 4}}})
        );
    }
}

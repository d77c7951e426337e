//! Run metrics: per-stage counters and timings, the engine totals, the sections nodes contribute
//! (`DagBuilder::metrics`), and the files `OUT/metrics.json`, `OUT/variants/<name>/metrics.json` and
//! `OUT/sweep.csv` (one row per variant, one column per numeric metric leaf).
//!
//! `metrics.json` schema: `{ "engine": { nodes_total, nodes_executed, nodes_cached, nodes_failed,
//! nodes_skipped, seconds, warnings }, "stages": { <stage>: { executed, cached, failed, skipped, seconds } },
//! <namespace>: { … contributed by nodes … } }`. In a sweep the top-level file holds the engine and stage
//! counts of the whole (shared) graph plus `"variants": [names]`; each variant's file holds the counts of
//! the nodes that variant uses and its contributed sections.

use crate::dag::{NodeReport, NodeStatus};
use serde_json::{json, Map, Value};
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
/// is merged key by key.
pub fn add_sections<'a>(doc: &mut Value, sections: impl IntoIterator<Item = (&'a str, &'a Value)>) {
    let Value::Object(map) = doc else { return };
    for (ns, v) in sections {
        match (map.get_mut(ns), v) {
            (Some(Value::Object(existing)), Value::Object(new)) => {
                for (k, x) in new {
                    existing.insert(k.clone(), x.clone());
                }
            }
            _ => {
                map.insert(ns.to_string(), v.clone());
            }
        }
    }
}

/// Numeric leaves of a JSON object as dotted paths (for sweep.csv columns).
pub fn numeric_leaves(prefix: &str, v: &Value, out: &mut BTreeMap<String, f64>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let p = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                numeric_leaves(&p, x, out);
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
        _ => {}
    }
}

/// `sweep.csv`: one row per variant, columns = `variant` + the union of the numeric leaves of each
/// variant's contributed sections and engine counters (sorted).
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
    columns.sort();
    columns.dedup();
    let mut out = String::from("variant");
    for c in &columns {
        out.push(',');
        out.push_str(&csv_field(c));
    }
    out.push('\n');
    for (name, m) in &leaves {
        out.push_str(&csv_field(name));
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

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Write pretty JSON atomically.
pub fn write_json(path: &Path, v: &Value) -> io::Result<()> {
    let mut bytes = serde_json::to_vec_pretty(v).map_err(io::Error::other)?;
    bytes.push(b'\n');
    skytie_stages::fsutil::atomic_write(path, &bytes)
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
    fn sections_merge() {
        let mut doc = json!({"engine": {"n": 1}});
        add_sections(
            &mut doc,
            [("toy", &json!({"a": 1})), ("toy", &json!({"b": 2}))],
        );
        assert_eq!(doc, json!({"engine": {"n": 1}, "toy": {"a": 1, "b": 2}}));
    }
}

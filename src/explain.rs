//! `skytie explain WORKFLOW NODE`: one node's key ingredients (stage, version, params, inputs with their
//! sources and content hashes, key), its planned status, and the provenance of its last run.

use crate::dag::record::load_record;
use crate::dag::{NodeStatus, Session};
use std::fmt::Write;

/// Describe the node whose identity (`stage[item]`) equals `query` (or starts with it, if unique).
pub fn explain(session: &Session<'_>, query: &str) -> Result<String, String> {
    let mut matches = Vec::new();
    for (p, phase) in session.phases.iter().enumerate() {
        for id in phase.dag.find(query) {
            matches.push((p, id));
        }
    }
    if matches.is_empty() {
        let mut known: Vec<String> = session.reports().map(|r| r.identity.clone()).collect();
        known.sort();
        known.dedup();
        let sample: Vec<&str> = known.iter().take(10).map(String::as_str).collect();
        return Err(format!(
            "no node '{query}' in this workflow; nodes are named stage[item], e.g. {}",
            sample.join(", ")
        ));
    }
    let exact: Vec<_> = matches
        .iter()
        .copied()
        .filter(|&(p, id)| session.phases[p].dag.nodes()[id].identity() == query)
        .collect();
    let chosen = if exact.is_empty() { matches } else { exact };
    let mut out = String::new();
    for (p, id) in chosen {
        let phase = &session.phases[p];
        let node = &phase.dag.nodes()[id];
        let r = &phase.reports[id];
        let _ = writeln!(out, "node      {}", r.identity);
        let _ = writeln!(out, "phase     {}", phase.name);
        let _ = writeln!(out, "stage     {} (version {})", node.stage, node.version);
        let _ = writeln!(out, "variants  {}", node.variants.join(", "));
        let params = serde_json::to_string_pretty(&*node.params_json).unwrap_or_default();
        let _ = writeln!(out, "params    {}", params.replace('\n', "\n          "));
        let _ = writeln!(out, "inputs");
        for i in &phase.inputs(id) {
            let h = if i.hash.is_empty() {
                "(not computed yet)"
            } else {
                &i.hash
            };
            let _ = writeln!(
                out,
                "  {:<8} {} = {}",
                if i.label.is_empty() { "-" } else { &i.label },
                i.source,
                h
            );
        }
        match r.key {
            Some(k) => {
                let _ = writeln!(out, "key       {k}");
            }
            None => {
                let _ = writeln!(
                    out,
                    "key       (not known until its upstream nodes have run)"
                );
            }
        }
        let status = match &r.status {
            NodeStatus::Cached | NodeStatus::Executed => "cached".to_string(),
            NodeStatus::WillRun { reasons } => format!("will run: {}", reasons.join("; ")),
            NodeStatus::Failed(m) => format!("cannot run: {m}"),
            NodeStatus::Skipped { upstream } => {
                format!("cannot run: upstream {upstream} cannot run")
            }
        };
        let _ = writeln!(out, "status    {status}");
        if let Some(h) = r.output_hash {
            let _ = writeln!(out, "output    {h}");
        }
        for v in &node.variants {
            match load_record(session.store, &r.identity, v) {
                Some(rec) => {
                    let _ = writeln!(
                        out,
                        "last run  [{v}] key {} output {} ran {:.3} s, recorded at unix {} by skytie {}",
                        rec.ran_with.key, rec.output_hash, rec.seconds, rec.recorded_unix_s, rec.skytie_version
                    );
                }
                None => {
                    let _ = writeln!(out, "last run  [{v}] none recorded");
                }
            }
        }
        out.push('\n');
    }
    Ok(out)
}

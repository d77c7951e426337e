//! `OUT/provenance.json`: everything needed to say how the outputs were made — skytie version, workflow
//! file and hash, campaign source, variants, per stage its version and params (per variant), the content
//! hashes of all raw input files, the keys and output hashes of the run's outputs, and timings.

use crate::dag::{NodeStatus, Session};
use crate::workflow::{CampaignSource, Workflow};
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;

/// Build the provenance document of a finished session.
pub fn provenance(
    workflow: &Workflow,
    session: &Session<'_>,
    started_unix_s: u64,
    wall_seconds: f64,
) -> Value {
    let campaign = match &workflow.campaign {
        CampaignSource::Path(p) => json!({ "path": p.display().to_string() }),
        CampaignSource::Synth { preset, seed } => json!({ "synth": preset, "seed": seed }),
    };
    // stage -> (version, variant -> params)
    let mut stages: BTreeMap<&str, (String, BTreeMap<String, Value>)> = BTreeMap::new();
    let mut raw: BTreeMap<String, String> = BTreeMap::new();
    let mut stage_seconds: BTreeMap<&str, f64> = BTreeMap::new();
    let mut outputs = Map::new();
    for phase in &session.phases {
        for (node, report) in phase.dag.nodes().iter().zip(&phase.reports) {
            let entry = stages
                .entry(node.stage)
                .or_insert_with(|| (node.version.to_string(), BTreeMap::new()));
            for v in &node.variants {
                entry
                    .1
                    .entry(v.clone())
                    .or_insert_with(|| (*node.params_json).clone());
            }
            for input in &phase.inputs(report.id) {
                if let Some(path) = input.source.strip_prefix("file ") {
                    raw.insert(path.to_string(), input.hash.clone());
                }
            }
            *stage_seconds.entry(node.stage).or_default() += report.seconds;
        }
        for &id in &phase.requested {
            let r = &phase.reports[id];
            let status = match &r.status {
                NodeStatus::Executed => "executed",
                NodeStatus::Cached => "cached",
                NodeStatus::Failed(_) => "failed",
                NodeStatus::Skipped { .. } => "skipped",
                NodeStatus::WillRun { .. } => "planned",
            };
            outputs.insert(
                r.identity.clone(),
                json!({
                    "stage": r.stage,
                    "stage_version": r.stage_version,
                    "variants": r.variants,
                    "key": r.key.map(|k| k.to_string()),
                    "output_hash": r.output_hash.map(|h| h.to_string()),
                    "status": status,
                }),
            );
        }
    }
    let stages_json: Map<String, Value> = stages
        .into_iter()
        .map(|(name, (version, params))| {
            let params: Map<String, Value> = params.into_iter().collect();
            (
                name.to_string(),
                json!({ "version": version, "params": params }),
            )
        })
        .collect();
    let finished = started_unix_s + wall_seconds.round() as u64;
    json!({
        "skytie_version": env!("CARGO_PKG_VERSION"),
        "workflow": {
            "name": workflow.name,
            "path": workflow.path.display().to_string(),
            "file_hash": hex(&workflow.file_hash),
            "pipeline": workflow.pipeline,
            "stages": workflow.stages,
        },
        "campaign": campaign,
        "variants": workflow.variants(),
        "stages": stages_json,
        "raw_inputs": raw,
        "outputs": outputs,
        "timings": {
            "started_unix_s": started_unix_s,
            "finished_unix_s": finished,
            "wall_seconds": (wall_seconds * 1e6).round() / 1e6,
            "stage_seconds": stage_seconds,
        },
    })
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

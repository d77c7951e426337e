//! `skytie run … --shard K/N | --merge N | --prepare`: one process's part of a campaign split across cluster
//! tasks that share one cache (the contract is described in `crate::dag::shard` and docs/cluster.md).
//!
//! A shard or prepare run writes no outputs of the campaign; it writes its own summary,
//! `OUT/shards/shard-K-of-N.json` (or `OUT/shards/prepare.json`): nodes executed, cached, failed, with the
//! failed nodes and their errors, and the wall time. It exits 0 when it attempted every node of its part — items
//! that fail on bad input are not a reason to hold back the merge, which reports them as a single run would —
//! and 1 when it could not run (e.g. the campaign cannot be read).

use crate::cli::common::print_problems;
use crate::dag::{NodeStatus, Partition, PipelineError, Session, ShardSpec};
use crate::metrics::{write_json, Summary};
use clap::Args;
use std::path::Path;

/// The sharding flags of `skytie run`.
#[derive(Args, Debug, Clone, Default)]
pub struct ShardOpt {
    /// Compute only shard K of N: the per-recording work of the K-th of N contiguous trajectory segments
    /// (results go to the cache; no outputs). K counts from 1.
    #[arg(long, value_name = "K/N", conflicts_with_all = ["merge", "prepare"])]
    pub shard: Option<ShardSpec>,
    /// After all N shards: check that every shard is complete, then run the global steps (adjustment,
    /// verification, exports, report) and write the outputs, identical to a single run's.
    #[arg(long, value_name = "N", conflicts_with = "prepare", value_parser = clap::value_parser!(u64).range(1..))]
    pub merge: Option<u64>,
    /// Only the steps before the shards (campaign generation, loading, image validation), once, so that
    /// shards started together do not all repeat them.
    #[arg(long)]
    pub prepare: bool,
}

impl ShardOpt {
    /// The part of the work the flags ask for.
    pub fn partition(&self) -> Partition {
        match (self.shard, self.merge, self.prepare) {
            (Some(spec), _, _) => Partition::Shard(spec),
            (_, Some(count), _) => Partition::Merge {
                count: usize::try_from(count).unwrap_or(usize::MAX),
            },
            (_, _, true) => Partition::Prepare,
            _ => Partition::Whole,
        }
    }
}

/// The end of a shard or prepare run: its summary file, the failed nodes, one line; returns the exit code.
pub fn finish_part(
    session: &Session<'_>,
    summary: &Summary,
    result: Result<(), PipelineError>,
    out_dir: &Path,
    partition: Partition,
    wall_seconds: f64,
) -> Result<i32, (i32, String)> {
    let (name, what) = match partition {
        Partition::Shard(s) => (
            format!("shard-{}-of-{}.json", s.index, s.count),
            format!("shard {s}"),
        ),
        _ => ("prepare.json".to_string(), "prepare".to_string()),
    };
    let warnings: usize = session.phases.iter().map(|p| p.warnings.len()).sum();
    let mut doc = summary.to_json(wall_seconds, warnings);
    let failed: Vec<serde_json::Value> = session
        .reports()
        .filter_map(|r| match &r.status {
            NodeStatus::Failed(m) => Some(serde_json::json!({ "node": r.identity, "error": m })),
            _ => None,
        })
        .collect();
    if let serde_json::Value::Object(m) = &mut doc {
        m.insert("part".into(), serde_json::json!(what));
        m.insert("failed".into(), serde_json::json!(failed));
    }
    let path = out_dir.join("shards").join(name);
    write_json(&path, &doc).map_err(|e| (2, format!("cannot write {}: {e}", path.display())))?;
    print_problems(session);
    let t = &summary.total;
    let exit_code = match &result {
        Ok(()) => {
            println!(
                "{what} done: {} nodes: {} executed, {} cached, {} failed, {} skipped ({wall_seconds:.0} s); summary {}",
                summary.nodes_total,
                t.executed,
                t.cached,
                t.failed,
                t.skipped,
                path.display()
            );
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            println!("{what} FAILED (exit 1); summary {}", path.display());
            1
        }
    };
    Ok(exit_code)
}

//! What an execution reports: each node's outcome (status, key, output hash, seconds), the inputs it was
//! keyed on as they are recorded, and the values the pipeline requested.

use super::ABSENT;
use crate::dag::builder::Dag;
use crate::dag::inputs::{InputRef, NodeId};
use crate::dag::node::{AnyValue, Node};
use crate::dag::record::RecordedInput;
use crate::dag::status::NodeStatus;
use crate::hashing::{ContentHash, NodeKey};
use std::collections::HashMap;

/// The outcome of one node.
#[derive(Clone, Debug)]
pub struct NodeReport {
    pub id: NodeId,
    pub identity: String,
    pub stage: &'static str,
    pub stage_version: &'static str,
    pub variants: Vec<String>,
    pub status: NodeStatus,
    pub key: Option<NodeKey>,
    pub output_hash: Option<ContentHash>,
    /// Seconds the stage ran in this run (0 when cached).
    pub seconds: f64,
    /// Content hashes of the node's raw-file inputs, in input order (the other inputs' hashes are their
    /// upstream nodes' output hashes: [`recorded_inputs`] puts them together).
    pub file_hashes: Vec<ContentHash>,
}

/// The inputs of node `id` of `dag` with their sources and hashes, from the reports of its execution: an
/// upstream's output hash, [`ABSENT`] for an optional input whose node failed or was skipped, an empty hash
/// when not known yet (plan mode: the upstream will run).
pub fn recorded_inputs(dag: &Dag, reports: &[NodeReport], id: NodeId) -> Vec<RecordedInput> {
    let Some(node) = dag.nodes.get(id) else {
        return Vec::new();
    };
    let files = reports.get(id).map_or(&[][..], |r| &r.file_hashes[..]);
    recorded_with(dag, node, files, |u| {
        let r = reports.get(u)?;
        Some(match (&r.status, r.output_hash) {
            (NodeStatus::Failed(_) | NodeStatus::Skipped { .. }, _) => Upstream::Unavailable,
            (_, Some(h)) => Upstream::Hash(h),
            _ => Upstream::Unknown,
        })
    })
}

/// What a consumer knows of one upstream node when its inputs are recorded.
pub(super) enum Upstream {
    Hash(ContentHash),
    Unknown,
    Unavailable,
}

pub(super) fn recorded_with(
    dag: &Dag,
    node: &Node,
    file_hashes: &[ContentHash],
    upstream: impl Fn(NodeId) -> Option<Upstream>,
) -> Vec<RecordedInput> {
    let mut files = file_hashes.iter();
    node.inputs
        .iter()
        .map(|(label, r)| {
            let (source, hash) = match r {
                InputRef::File(p) => (
                    format!("file {}", p.display()),
                    files.next().map(|h| h.to_string()).unwrap_or_default(),
                ),
                InputRef::Node(u) | InputRef::OptionalNode(u) => {
                    let hash = match (upstream(*u), r) {
                        (Some(Upstream::Unavailable), InputRef::OptionalNode(_)) => {
                            ABSENT.to_string()
                        }
                        (Some(Upstream::Hash(h)), _) => h.to_string(),
                        _ => String::new(),
                    };
                    (dag.nodes[*u].identity(), hash)
                }
            };
            RecordedInput {
                label: label.to_string(),
                source,
                hash,
            }
        })
        .collect()
}

/// Everything an execution produced.
pub struct Outcome {
    pub reports: Vec<NodeReport>,
    pub(crate) values: HashMap<NodeId, AnyValue>,
    /// Warnings (corrupt cache entries …), each once.
    pub warnings: Vec<String>,
    /// Metrics contributed by nodes: (variant, namespace, object).
    pub metrics: Vec<(String, String, serde_json::Value)>,
    pub seconds: f64,
}

impl Outcome {
    /// The value of a requested node (`DagBuilder::request`), if it was produced.
    pub fn get<T: Send + Sync + 'static>(
        &self,
        handle: crate::dag::Handle<T>,
    ) -> Option<std::sync::Arc<T>> {
        self.values.get(&handle.id)?.clone().downcast::<T>().ok()
    }
    pub fn count(&self, pred: impl Fn(&NodeStatus) -> bool) -> usize {
        self.reports.iter().filter(|r| pred(&r.status)).count()
    }
    pub fn executed(&self) -> usize {
        self.count(|s| matches!(s, NodeStatus::Executed))
    }
    pub fn cached(&self) -> usize {
        self.count(|s| matches!(s, NodeStatus::Cached))
    }
    pub fn failed(&self) -> usize {
        self.count(|s| matches!(s, NodeStatus::Failed(_)))
    }
    pub fn skipped(&self) -> usize {
        self.count(|s| matches!(s, NodeStatus::Skipped { .. }))
    }
    pub fn will_run(&self) -> usize {
        self.count(|s| matches!(s, NodeStatus::WillRun { .. }))
    }
    /// Executed count of one stage.
    pub fn executed_of(&self, stage: &str) -> usize {
        self.reports
            .iter()
            .filter(|r| r.stage == stage && r.status == NodeStatus::Executed)
            .count()
    }
}

//! What happened to a node in a run (or will happen, in a plan).

/// What happened to a node.
#[derive(Clone, Debug, PartialEq)]
pub enum NodeStatus {
    /// The stage ran (or was recomputed because its cached artifact was corrupt or missing).
    Executed,
    /// The output came from the cache.
    Cached,
    /// The stage returned an error or panicked; nothing was stored.
    Failed(String),
    /// Not run because an upstream node failed (identity of that node).
    Skipped { upstream: String },
    /// Plan mode: the node will run, with the reasons.
    WillRun { reasons: Vec<String> },
}

impl NodeStatus {
    pub fn is_ok(&self) -> bool {
        matches!(self, NodeStatus::Executed | NodeStatus::Cached)
    }
}

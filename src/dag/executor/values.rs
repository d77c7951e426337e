//! Step 2 of a wave: the input values of the nodes to run in memory, loaded once each; an input whose cached
//! artifact turns out gone or corrupt is recomputed first, recursively.

use super::Exec;
use crate::dag::inputs::NodeId;
use crate::dag::node::AnyValue;
use crate::dag::status::NodeStatus;
use crate::hashing::ContentHash;
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

impl Exec<'_> {
    /// Make sure the values of `ids` (all processed successfully) are in memory: load them (parallel), and
    /// recompute those whose artifact is gone or corrupt (after ensuring their own inputs). Returns the ids
    /// that could not be provided, with the reason.
    pub(super) fn ensure_values(&self, ids: &[NodeId]) -> Vec<(NodeId, String)> {
        self.ensure_values_keeping(ids, &HashSet::new())
    }

    /// [`Self::ensure_values`], never releasing the values in `keep` (those an enclosing call still needs:
    /// in a diamond, a node can be both an input and an input's input of what is being recomputed).
    pub(super) fn ensure_values_keeping(
        &self,
        ids: &[NodeId],
        keep: &HashSet<NodeId>,
    ) -> Vec<(NodeId, String)> {
        let missing: Vec<NodeId> = ids
            .iter()
            .copied()
            .filter(|&id| self.slot(id).value.is_none())
            .collect();
        if missing.is_empty() {
            return Vec::new();
        }
        let loaded: Vec<(NodeId, Option<(AnyValue, ContentHash)>)> = missing
            .par_iter()
            .map(|&id| {
                let (key, hash) = {
                    let s = self.slot(id);
                    (s.key, s.hash)
                };
                let r = match key {
                    Some(k) => self.load_verified(id, k, hash).ok().flatten(),
                    None => None,
                };
                (id, r)
            })
            .collect();
        let mut recompute = Vec::new();
        for (id, r) in loaded {
            match r {
                Some((v, _)) => self.slot(id).value = Some(v),
                None => recompute.push(id),
            }
        }
        if recompute.is_empty() {
            return Vec::new();
        }
        let mut upstream: Vec<NodeId> = recompute
            .iter()
            .flat_map(|&id| self.dag.nodes[id].upstream_ids())
            .filter(|&u| !self.unavailable(u))
            .collect();
        upstream.sort_unstable();
        upstream.dedup();
        let mut keep_upstream = keep.clone();
        keep_upstream.extend(ids.iter().copied());
        keep_upstream.extend(upstream.iter().copied());
        let upstream_failures: HashMap<NodeId, String> = self
            .ensure_values_keeping(&upstream, &keep_upstream)
            .into_iter()
            .collect();
        // A node recomputed as an upstream of another one in this set is not run twice.
        recompute.retain(|&id| self.slot(id).value.is_none());
        let results: Vec<(NodeId, Result<f64, String>)> = recompute
            .par_iter()
            .map(|&id| {
                let node = &self.dag.nodes[id];
                if let Some((u, m)) = node
                    .upstream_ids()
                    .into_iter()
                    .find_map(|u| upstream_failures.get(&u).map(|m| (u, m)))
                {
                    return (
                        id,
                        Err(format!(
                            "upstream {} unavailable: {m}",
                            self.dag.nodes[u].identity()
                        )),
                    );
                }
                (id, self.execute_node(id))
            })
            .collect();
        let mut failures = Vec::new();
        for (id, r) in results {
            match r {
                Ok(secs) => {
                    let mut s = self.slot(id);
                    s.seconds += secs;
                    if s.status == Some(NodeStatus::Cached) {
                        s.status = Some(NodeStatus::Executed);
                    }
                }
                Err(m) => failures.push((id, m)),
            }
        }
        // Release recomputed upstream values nobody will read again.
        for &u in &upstream {
            if keep.contains(&u) || ids.contains(&u) {
                continue;
            }
            let mut s = self.slot(u);
            if s.consumers_left == 0 && !self.dag.nodes[u].requested {
                s.value = None;
            }
        }
        failures
    }
}

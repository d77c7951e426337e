//! Step 1 of a wave: is a node cached (its key known and its entry present and intact), will it run (and,
//! in plan mode, why), or can it not run (an upstream failed, an input file is unreadable).

use super::{touch_entry, Check, Exec, Mode};
use crate::dag::inputs::{absent_hash, InputRef, NodeId};
use crate::dag::key::node_key;
use crate::dag::node::{AnyValue, Node};
use crate::dag::record::{self, NodeRecord};
use crate::dag::record_pack::name_hash;
use crate::dag::status::NodeStatus;
use crate::hashing::{ContentHash, NodeKey};
use crate::store::Loaded;

impl Exec<'_> {
    /// The input hashes of node `id` for its key, in input order; whether an upstream will run (plan mode);
    /// or why the node cannot run.
    pub(super) fn input_hashes(&self, id: NodeId) -> Result<(Vec<ContentHash>, bool), Check> {
        let node = &self.dag.nodes[id];
        let mut hashes = Vec::with_capacity(node.inputs.len());
        let mut files = Vec::new();
        let mut upstream_running = false;
        for (_, r) in &node.inputs {
            match r {
                InputRef::Node(u) | InputRef::OptionalNode(u) => {
                    let s = self.slot(*u);
                    match (&s.status, r) {
                        (Some(NodeStatus::Failed(_) | NodeStatus::Skipped { .. }), InputRef::OptionalNode(_)) => {
                            hashes.push(absent_hash())
                        }
                        (Some(NodeStatus::Failed(_)), _) => {
                            return Err(Check::Skipped(self.dag.nodes[*u].identity()))
                        }
                        (Some(NodeStatus::Skipped { upstream }), _) => {
                            return Err(Check::Skipped(upstream.clone()))
                        }
                        (Some(NodeStatus::WillRun { .. }), _) => {
                            upstream_running = true;
                            hashes.push(ContentHash([0; 32]));
                        }
                        _ => match s.hash {
                            Some(h) => hashes.push(h),
                            None => {
                                return Err(Check::Failed(format!(
                                    "internal error: upstream {} has no output",
                                    self.dag.nodes[*u].identity()
                                )))
                            }
                        },
                    }
                }
                InputRef::File(p) => match self.env.stat_cache.hash_file(p) {
                    Ok(h) => {
                        hashes.push(h);
                        files.push(h);
                    }
                    Err(e) => {
                        return Err(Check::Failed(format!(
                            "cannot read input file {}: {e} (check that the campaign folder is complete)",
                            p.display()
                        )))
                    }
                },
            }
        }
        if !files.is_empty() {
            self.slot(id).file_hashes = files;
        }
        Ok((hashes, upstream_running))
    }

    /// Step 1 for one node.
    pub(super) fn check(&self, id: NodeId) -> Check {
        let node = &self.dag.nodes[id];
        let (hashes, upstream_running) = match self.input_hashes(id) {
            Ok(h) => h,
            Err(check) => return check,
        };
        let variant = node
            .variants
            .first()
            .map(String::as_str)
            .unwrap_or("default");
        if upstream_running {
            return Check::WillRun(self.upstream_running_reasons(id, variant));
        }
        let key = node_key(node, &hashes);
        let latest = self
            .index
            .latest(name_hash(node.stage, &node.item, variant));
        let (known_hash, record_stale) = match latest {
            Some((k, h)) if k == key => (Some(h), false),
            _ => (self.index.output_of(&key), true),
        };
        if let Some(hash) = known_hash {
            if self.entry_exists(&key) {
                return Check::Cached {
                    key,
                    hash,
                    value: None,
                    record_stale,
                };
            }
        }
        match self.load_verified(id, key, None) {
            Ok(Some((value, hash))) => Check::Cached {
                key,
                hash,
                value: Some(value),
                record_stale: true,
            },
            _ if self.mode == Mode::Plan => {
                let prev = self.load_record(node, variant);
                Check::WillRun(record::reasons(
                    prev.as_ref().map(|r| &r.ran_with),
                    node.version,
                    &node.params_json,
                    &self.recorded_now(id),
                ))
            }
            _ => Check::Run { key },
        }
    }

    /// Plan mode, for a node an upstream of which will run: what changed since its last record, and which
    /// upstream nodes will run.
    pub(super) fn upstream_running_reasons(&self, id: NodeId, variant: &str) -> Vec<String> {
        let node = &self.dag.nodes[id];
        let prev = self.load_record(node, variant);
        let recorded = self.recorded_now(id);
        let mut why = record::reasons(
            prev.as_ref().map(|r| &r.ran_with),
            node.version,
            &node.params_json,
            &recorded,
        );
        why.retain(|w| !w.starts_with("same ingredients") && !w.starts_with("upstream will run"));
        if prev.is_some() {
            const SHOWN: usize = 5;
            let mut running: Vec<String> = Vec::new();
            for (i, (_, r)) in node.inputs.iter().enumerate() {
                if let (Some(u), true) = (r.node(), recorded[i].hash.is_empty()) {
                    let source = self.dag.nodes[u].identity();
                    if !running.contains(&source) {
                        running.push(source);
                    }
                }
            }
            let mut list = running
                .iter()
                .take(SHOWN)
                .cloned()
                .collect::<Vec<_>>()
                .join(", ");
            if running.len() > SHOWN {
                list.push_str(&format!(" and {} more", running.len() - SHOWN));
            }
            why.push(format!("upstream will run: {list}"));
        }
        why
    }

    /// The node's last record (for the reasons it will run).
    pub(super) fn load_record(&self, node: &Node, variant: &str) -> Option<NodeRecord> {
        let identity = node.identity();
        record::record_in(&self.index, &identity, variant)
            .or_else(|| record::load_record_file(self.env.store, &identity, variant))
    }

    /// Whether the entry of `key` exists. Plan mode: from the listing when there is one, else a `stat`. Run
    /// mode: the entry is also marked used now (see [`touch_entry`]).
    pub(super) fn entry_exists(&self, key: &NodeKey) -> bool {
        match (self.mode, &self.present) {
            (Mode::Plan, Some(present)) => present.contains(&self.index, key),
            (Mode::Plan, None) => self.env.store.object_path(key).is_file(),
            (Mode::Run, _) => self
                .marker
                .mark(key)
                .unwrap_or_else(|| touch_entry(self.env.store, key)),
        }
    }

    /// Load and decode node `id`'s artifact under `key`. Ok(None) = miss; Err = corrupt/unusable (warned).
    pub(super) fn load_verified(
        &self,
        id: NodeId,
        key: NodeKey,
        expected: Option<ContentHash>,
    ) -> Result<Option<(AnyValue, ContentHash)>, ()> {
        let node = &self.dag.nodes[id];
        // Decoded while read (one read, hashed on the way); an undecodable entry comes back as Corrupt.
        let loaded = self
            .env
            .store
            .load_with(&key, |source, len| node.erased.decode_from(source, len));
        match loaded {
            Ok(Loaded::Hit {
                value,
                content_hash,
                ..
            }) => {
                if expected.is_some_and(|h| h != content_hash) {
                    self.warn(format!(
                        "{}: cached artifact {key} differs from the recorded output; recomputing",
                        node.identity()
                    ));
                    return Err(());
                }
                if node.erased.cached_output_ok(&value, &self.ctx(node, key)) {
                    Ok(Some((value, content_hash)))
                } else {
                    self.warn(format!(
                        "{}: cached output refers to files that are gone; recomputing",
                        node.identity()
                    ));
                    Err(())
                }
            }
            Ok(Loaded::Miss) => Ok(None),
            Ok(Loaded::Corrupt { message }) => {
                self.warn(format!("{}: {message}; recomputing", node.identity()));
                Err(())
            }
            Err(e) => {
                self.warn(format!(
                    "{}: cache read failed ({e}); recomputing",
                    node.identity()
                ));
                Err(())
            }
        }
    }
}

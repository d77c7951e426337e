//! Building a DAG in Rust code: `DagBuilder::add` returns a typed `Handle` to the node's output.
//!
//! Nodes are deduplicated at build time: adding a node whose stage, version, params, item and inputs equal
//! those of an existing node returns the existing handle (this is how the variants of a sweep share their
//! common prefix: built bottom-up, shared nodes merge and run once). The graph is the nodes' input lists
//! (no separate edge structure: a million-node graph keeps one copy of its edges); handles only refer to
//! existing nodes, so insertion order is a topological order. Equal parameters of many nodes are stored once
//! (their canonical bytes and JSON are shared), and the maps that find equal nodes and identities are keyed by
//! hashes, so a node costs a few hundred bytes.
//!
//! A node's identity `stage[item]` names it in plans, records (`identity@variant`) and `explain`, so within one
//! variant an identity must denote one node: adding the same `stage[item]` again in a variant that already
//! has it with a different structure (params, version or inputs) is refused with an error naming the stage,
//! the item and both variants. Variants of a sweep may of course hold different nodes of one identity.

use crate::codec::encode_params;
use crate::dag::inputs::{Handle, InputRef, InputSet, NodeId};
use crate::dag::node::{Node, TypedNode};
use crate::dag::record_pack::{name_hash, HashKeyed};
use crate::dag::stage::Stage;
use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

/// A wiring mistake found while building the graph.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BuildError {
    pub message: String,
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}
impl std::error::Error for BuildError {}

/// Turns a node's output into a JSON object contributed to `metrics.json` under `namespace`.
pub(crate) type MetricsFn =
    Arc<dyn Fn(&(dyn std::any::Any + Send + Sync)) -> Option<serde_json::Value> + Send + Sync>;

/// A metrics contribution registered with [`DagBuilder::metrics`].
#[derive(Clone)]
pub(crate) struct MetricsSink {
    pub node: NodeId,
    pub variant: String,
    pub namespace: String,
    pub to_json: MetricsFn,
}

/// The canonical bytes and JSON of one set of parameters, shared by the nodes that have them.
type SharedParams = (Arc<[u8]>, Arc<serde_json::Value>);

/// Collects nodes; see the module documentation.
pub struct DagBuilder {
    nodes: Vec<Node>,
    by_structure: HashKeyed<[u8; 32], NodeId>,
    /// Hash of (identity `stage[item]`, variant) → the node that identity denotes in that variant.
    by_identity: HashKeyed<u64, NodeId>,
    /// The same for the rare identities whose hash is already taken by another identity.
    by_identity_overflow: HashMap<(String, String), NodeId>,
    /// Input labels, shared by every node that has them.
    labels: HashMap<String, Arc<str>>,
    /// blake3(stage, canonical params) → the shared bytes and JSON of those params.
    params: HashKeyed<[u8; 32], SharedParams>,
    variant: String,
    sinks: Vec<MetricsSink>,
}

impl Default for DagBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl DagBuilder {
    pub fn new() -> Self {
        DagBuilder {
            nodes: Vec::new(),
            by_structure: HashKeyed::default(),
            by_identity: HashKeyed::default(),
            by_identity_overflow: HashMap::new(),
            labels: HashMap::new(),
            params: HashKeyed::default(),
            variant: "default".to_string(),
            sinks: Vec::new(),
        }
    }

    /// Nodes added from now on belong to `variant` (sweeps build each variant in turn into one builder).
    pub fn set_variant(&mut self, variant: &str) {
        self.variant = variant.to_string();
    }

    /// Add a node of stage `S` for `item` (empty for a global node) with `params` reading `inputs`.
    pub fn add<S: Stage>(
        &mut self,
        stage: S,
        item: &str,
        params: S::Params,
        inputs: S::Inputs,
    ) -> Result<Handle<S::Output>, BuildError> {
        let params_bytes = encode_params(&params).map_err(|e| BuildError {
            message: format!("stage {}: cannot encode params: {e}", S::NAME),
        })?;
        let mut refs = Vec::new();
        inputs.collect_refs("", &mut refs);
        for (label, r) in &refs {
            if let Some(id) = r.node().as_ref() {
                if *id >= self.nodes.len() {
                    return Err(BuildError {
                        message: format!(
                            "stage {} input {label}: handle {id} does not belong to this graph",
                            S::NAME
                        ),
                    });
                }
            }
        }
        let structure = structural_hash(S::NAME, S::VERSION, item, &params_bytes, &refs);
        let existing = self.by_structure.get(&structure).copied();
        let identity = self.identity_node(S::NAME, item);
        if let Some(other) = identity {
            if Some(other) != existing {
                let json = serde_json::to_value(&params).unwrap_or_default();
                return Err(self.identity_clash(other, S::NAME, item, &json));
            }
        }
        if let Some(id) = existing {
            if !self.nodes[id].variants.contains(&self.variant) {
                self.nodes[id].variants.push(self.variant.clone());
            }
            if identity.is_none() {
                self.set_identity_node(S::NAME, item, id);
            }
            return Ok(Handle::new(id));
        }
        let (params_bytes, params_json) = self.shared_params(S::NAME, params_bytes, &params)?;
        let id = self.nodes.len();
        // Exactly as long as needed (collecting in place would keep the growth capacity of `refs`).
        let mut inputs_list: Vec<(Arc<str>, InputRef)> = Vec::with_capacity(refs.len());
        for (label, r) in refs {
            inputs_list.push((self.shared_label(label), r));
        }
        self.nodes.push(Node {
            stage: S::NAME,
            version: S::VERSION,
            item: item.to_string(),
            variants: vec![self.variant.clone()],
            params_bytes,
            params_json,
            inputs: inputs_list,
            erased: Box::new(TypedNode {
                stage,
                params,
                inputs,
            }),
            requested: false,
        });
        self.by_structure.insert(structure, id);
        self.set_identity_node(S::NAME, item, id);
        Ok(Handle::new(id))
    }

    /// `label`, shared with every node that has an input of that label.
    fn shared_label(&mut self, label: String) -> Arc<str> {
        if let Some(shared) = self.labels.get(&label) {
            return shared.clone();
        }
        let shared: Arc<str> = Arc::from(label.as_str());
        self.labels.insert(label, shared.clone());
        shared
    }

    /// The canonical bytes and JSON of `params` of stage `stage`, shared with every node that has equal ones.
    fn shared_params<P: serde::Serialize>(
        &mut self,
        stage: &str,
        bytes: Vec<u8>,
        params: &P,
    ) -> Result<SharedParams, BuildError> {
        let mut h = blake3::Hasher::new();
        h.update(&(stage.len() as u64).to_le_bytes());
        h.update(stage.as_bytes());
        h.update(&bytes);
        let id = *h.finalize().as_bytes();
        if let Some(shared) = self.params.get(&id) {
            return Ok(shared.clone());
        }
        let json = serde_json::to_value(params).map_err(|e| BuildError {
            message: format!("stage {stage}: cannot describe params: {e}"),
        })?;
        let shared = (Arc::<[u8]>::from(bytes), Arc::new(json));
        self.params.insert(id, shared.clone());
        Ok(shared)
    }

    /// The node identity `stage[item]` denotes in the current variant, if any.
    fn identity_node(&self, stage: &str, item: &str) -> Option<NodeId> {
        let id = *self
            .by_identity
            .get(&name_hash(stage, item, &self.variant))?;
        let n = &self.nodes[id];
        if n.stage == stage && n.item == item && n.variants.contains(&self.variant) {
            return Some(id);
        }
        // The hash belongs to another identity.
        self.by_identity_overflow
            .get(&(identity_of(stage, item), self.variant.clone()))
            .copied()
    }

    fn set_identity_node(&mut self, stage: &str, item: &str, id: NodeId) {
        let hash = name_hash(stage, item, &self.variant);
        match self.by_identity.get(&hash) {
            Some(&other) if other != id && self.identity_is(other, stage, item) => {}
            Some(&other) if other != id => {
                self.by_identity_overflow
                    .insert((identity_of(stage, item), self.variant.clone()), id);
                return;
            }
            _ => {}
        }
        self.by_identity.insert(hash, id);
    }

    /// Whether node `id` has identity `stage[item]` in some other variant than the current one (its hash slot
    /// may then be taken over: identities are looked up together with the variant).
    fn identity_is(&self, id: NodeId, stage: &str, item: &str) -> bool {
        let n = &self.nodes[id];
        n.stage == stage && n.item == item
    }

    /// The error for a second, different node of identity `stage[item]` in the current variant; `other` is
    /// the node the variant already has under that identity.
    fn identity_clash(
        &self,
        other: NodeId,
        stage: &str,
        item: &str,
        params_json: &serde_json::Value,
    ) -> BuildError {
        let first = &self.nodes[other];
        let mut differences = Vec::new();
        crate::dag::json_diff::diff_json("", &first.params_json, params_json, &mut differences);
        let what = if differences.is_empty() {
            "same params but different inputs or stage version".to_string()
        } else {
            format!("params differ: {}", differences.join("; "))
        };
        BuildError {
            message: format!(
                "stage {stage}, item '{item}': node {} is added twice with different keys in variant '{}' \
                 (first added for variant(s) {}, then again for variant '{}'; {what}); one identity may denote \
                 only one node per variant: give the items distinct labels or build the node once and reuse \
                 its handle",
                identity_of(stage, item),
                self.variant,
                first
                    .variants
                    .iter()
                    .map(|v| format!("'{v}'"))
                    .collect::<Vec<_>>()
                    .join(", "),
                self.variant,
            ),
        }
    }

    /// Keep this node's value after the run so `Outcome::get` can return it (it is loaded from the cache
    /// when the node is cached).
    pub fn request<T>(&mut self, handle: Handle<T>) {
        if let Some(n) = self.nodes.get_mut(handle.id) {
            n.requested = true;
        }
    }

    /// Contribute `to_json(output)` to the metrics of the current variant under `namespace` (e.g. the
    /// adjustment's statistics under `adjust`). The node is requested.
    pub fn metrics<T, F>(&mut self, handle: Handle<T>, namespace: &str, to_json: F)
    where
        T: Send + Sync + 'static,
        F: Fn(&T) -> serde_json::Value + Send + Sync + 'static,
    {
        self.request(handle);
        let f: MetricsFn = Arc::new(move |v| v.downcast_ref::<T>().map(&to_json));
        self.sinks.push(MetricsSink {
            node: handle.id,
            variant: self.variant.clone(),
            namespace: namespace.to_string(),
            to_json: f,
        });
    }

    /// Number of nodes so far.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Finish building.
    pub fn build(mut self) -> Dag {
        self.nodes.shrink_to_fit();
        Dag {
            nodes: self.nodes,
            sinks: self.sinks,
        }
    }
}

/// `stage[item]`, or `stage` for a global node (same as [`Node::identity`]).
fn identity_of(stage: &str, item: &str) -> String {
    if item.is_empty() {
        stage.to_string()
    } else {
        format!("{stage}[{item}]")
    }
}

fn structural_hash(
    stage: &str,
    version: &str,
    item: &str,
    params: &[u8],
    refs: &[(String, InputRef)],
) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    let mut field = |b: &[u8]| {
        h.update(&(b.len() as u64).to_le_bytes());
        h.update(b);
    };
    field(stage.as_bytes());
    field(version.as_bytes());
    field(item.as_bytes());
    field(params);
    for (label, r) in refs {
        field(label.as_bytes());
        match r {
            InputRef::Node(id) => {
                field(b"node");
                field(&(*id as u64).to_le_bytes());
            }
            InputRef::OptionalNode(id) => {
                field(b"optional node");
                field(&(*id as u64).to_le_bytes());
            }
            InputRef::File(p) => {
                field(b"file");
                field(p.as_os_str().as_encoded_bytes());
            }
        }
    }
    *h.finalize().as_bytes()
}

/// A finished graph, ready for `plan` or `execute`.
pub struct Dag {
    pub(crate) nodes: Vec<Node>,
    pub(crate) sinks: Vec<MetricsSink>,
}

impl Dag {
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }
    pub fn len(&self) -> usize {
        self.nodes.len()
    }
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
    /// Ids of the nodes that read node `id`.
    pub fn consumers(&self, id: NodeId) -> Vec<NodeId> {
        // Consumers come after their inputs.
        (id + 1..self.nodes.len())
            .filter(|&c| {
                self.nodes[c]
                    .inputs
                    .iter()
                    .any(|(_, r)| r.node() == Some(id))
            })
            .collect()
    }
    /// Topological waves: wave k holds the nodes whose longest upstream chain has k nodes. Nodes of one
    /// wave are independent and run in parallel.
    pub fn waves(&self) -> Vec<Vec<NodeId>> {
        let mut depth = vec![0usize; self.nodes.len()];
        let mut waves: Vec<Vec<NodeId>> = Vec::new();
        for (id, node) in self.nodes.iter().enumerate() {
            let d = node
                .upstream_ids()
                .iter()
                .map(|&u| depth[u] + 1)
                .max()
                .unwrap_or(0);
            depth[id] = d;
            if waves.len() <= d {
                waves.resize_with(d + 1, Vec::new);
            }
            waves[d].push(id);
        }
        waves
    }
    /// Find nodes by identity (`stage[item]`), exact match first, else all nodes whose identity starts
    /// with `query`.
    pub fn find(&self, query: &str) -> Vec<NodeId> {
        let exact: Vec<NodeId> = (0..self.nodes.len())
            .filter(|&i| self.nodes[i].identity() == query)
            .collect();
        if !exact.is_empty() {
            return exact;
        }
        (0..self.nodes.len())
            .filter(|&i| self.nodes[i].identity().starts_with(query))
            .collect()
    }
}

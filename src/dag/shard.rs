//! Sharding a phase's graph across processes (cluster array tasks) that share one store.
//!
//! A pipeline names the *seeds* of a phase — the nodes that stand for the campaign's items in their natural
//! order (for a mobile-mapping campaign: one node per recording, in time order along the trajectory) — and its
//! *per-item stages*, whose nodes each work on a few neighbouring items (a recording, a window, a triplet, a
//! recording × aerial image pair). The seeds are cut into `N` contiguous segments of near-equal size. Every
//! node of a per-item stage that descends from a seed is **owned** by exactly one segment: the segment of the
//! first seed it reads (a window or triplet spanning a segment boundary belongs to the segment of its first
//! member), see [`owners`]. Nodes of other stages (campaign-wide ones: adjustment, summaries, grading)
//! are owned by nobody: only the merge runs them.
//!
//! * `--shard K/N` executes the nodes owned by segment `K` and whatever they read (the overlap: e.g. the ortho
//!   image of the first recording of the next segment, which a boundary window needs); results go to the
//!   shared store.
//! * `--merge N` first plans the nodes every segment owns; if a segment has nodes that were never computed,
//!   it stops and names the shards to (re-)run. Otherwise it executes the whole graph as a single process
//!   would — every per-item node is found in the store — so its outputs are the single-process outputs.
//! * `--prepare` runs the phases before the sharded one (campaign, loading, validation) and stops, so that
//!   array tasks started together do not all compute them.
//!
//! Nothing here knows what a recording is; the pipeline decides the seeds.

use crate::dag::builder::Dag;
use crate::dag::executor::{execute, Env, Mode};
use crate::dag::inputs::{InputRef, NodeId};
use crate::dag::record::load_failure;
use crate::dag::status::NodeStatus;
use std::fmt;
use std::ops::Range;
use std::str::FromStr;

/// One shard `K/N` (1-based `index`, as Slurm array task ids usually are).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardSpec {
    /// 1 ≤ index ≤ count.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl FromStr for ShardSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || {
            format!(
                "invalid shard '{s}': write K/N with 1 ≤ K ≤ N, e.g. --shard 3/8 (the third of eight shards)"
            )
        };
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = k.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || count == 0 || index > count {
            return Err(bad());
        }
        Ok(ShardSpec { index, count })
    }
}

impl fmt::Display for ShardSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Which part of the work this process does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Partition {
    /// Everything (an ordinary run).
    #[default]
    Whole,
    /// Only the phases before the sharded one.
    Prepare,
    /// The nodes one segment owns (and what they read).
    Shard(ShardSpec),
    /// The whole graph, refusing to start while a segment of `count` shards is incomplete.
    Merge { count: usize },
}

impl Partition {
    /// Whether this process builds the run's outputs (metrics, exports, report).
    pub fn writes_outputs(&self) -> bool {
        matches!(self, Partition::Whole | Partition::Merge { .. })
    }
}

/// What a pipeline tells the engine about its sharded phase (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct Seeds<'a> {
    /// One node per item, in the order segments follow (e.g. recordings by time).
    pub nodes: &'a [NodeId],
    /// The stages whose nodes work on a few neighbouring items.
    pub per_item_stages: &'a [&'a str],
}

/// The seed ordinals of each of `count` contiguous segments of `len` seeds (sizes differ by at most one).
pub fn segments(len: usize, count: usize) -> Vec<Range<usize>> {
    let count = count.max(1);
    (0..count)
        .map(|k| (k * len / count)..((k + 1) * len / count))
        .collect()
}

/// The segment (0-based) holding seed ordinal `ordinal` among `segments`.
pub fn segment_of(segments: &[Range<usize>], ordinal: usize) -> usize {
    segments
        .partition_point(|r| r.end <= ordinal)
        .min(segments.len().saturating_sub(1))
}

/// For every node of a stage in `per_item_stages` that a seed reaches, its owner's seed ordinal: the lowest
/// seed among its direct inputs (a window or triplet: its first member), or else the lowest owner among its
/// per-item inputs (e.g. a consistency check over a recording's pairs). `None` for other nodes.
pub fn owners(dag: &Dag, seeds: &[NodeId], per_item_stages: &[&str]) -> Vec<Option<usize>> {
    let mut seed_ordinal: Vec<Option<usize>> = vec![None; dag.len()];
    for (ordinal, &id) in seeds.iter().enumerate() {
        if let Some(slot) = seed_ordinal.get_mut(id) {
            *slot = Some(slot.map_or(ordinal, |o: usize| o.min(ordinal)));
        }
    }
    let mut owner: Vec<Option<usize>> = vec![None; dag.len()];
    // Insertion order is a topological order: every upstream node comes first.
    for (id, node) in dag.nodes().iter().enumerate() {
        if !per_item_stages.contains(&node.stage) {
            continue;
        }
        let upstream = || node.inputs.iter().filter_map(|(_, r)| r.node());
        owner[id] = seed_ordinal[id]
            .or_else(|| upstream().filter_map(|u| seed_ordinal[u]).min())
            .or_else(|| upstream().filter_map(|u| owner[u]).min());
    }
    owner
}

/// `targets` and all their ancestors.
pub fn with_ancestors(dag: &Dag, targets: &[bool]) -> Vec<bool> {
    let mut keep = targets.to_vec();
    keep.resize(dag.len(), false);
    for id in (0..dag.len()).rev() {
        if keep[id] {
            for u in dag.nodes()[id].upstream_ids() {
                keep[u] = true;
            }
        }
    }
    keep
}

impl Dag {
    /// The graph of the nodes marked in `targets` and their ancestors; node ids are renumbered densely in their
    /// old order, metrics of dropped nodes are dropped. Returns the graph and, for each new id, the old one.
    pub fn into_subgraph(self, targets: &[bool]) -> (Dag, Vec<NodeId>) {
        let keep = with_ancestors(&self, targets);
        let Dag {
            nodes, mut sinks, ..
        } = self;
        let mut new_id: Vec<Option<NodeId>> = vec![None; nodes.len()];
        let mut old_ids = Vec::new();
        let mut kept = Vec::new();
        for (old, mut node) in nodes.into_iter().enumerate() {
            if !keep[old] {
                continue;
            }
            let id = kept.len();
            new_id[old] = Some(id);
            old_ids.push(old);
            for (_, r) in node.inputs.iter_mut() {
                if let InputRef::Node(u) | InputRef::OptionalNode(u) = r {
                    // Kept nodes' ancestors are kept (`with_ancestors`), and come first.
                    if let Some(n) = new_id[*u] {
                        *u = n;
                    }
                }
            }
            kept.push(node);
        }
        sinks.retain_mut(|s| match new_id.get(s.node).copied().flatten() {
            Some(id) => {
                s.node = id;
                true
            }
            None => false,
        });
        let dag = Dag { nodes: kept, sinks };
        (dag, old_ids)
    }
}

/// The nodes segment `spec` owns among `seeds` (see the module documentation).
pub fn segment_targets(dag: &Dag, seeds: &Seeds<'_>, spec: ShardSpec) -> Vec<bool> {
    let segs = segments(seeds.nodes.len(), spec.count);
    owners(dag, seeds.nodes, seeds.per_item_stages)
        .into_iter()
        .map(|o| o.is_some_and(|o| segment_of(&segs, o) + 1 == spec.index))
        .collect()
}

/// Before a merge: plan `dag` and fail, naming the shards to (re-)run, if a node some segment of `count`
/// owns was never computed. A node whose last attempt failed (recorded with the same key) and the nodes below
/// it do not count as missing: the merge attempts them again, as a single run would, and reports them.
pub fn check_complete(
    dag: &Dag,
    seeds: &Seeds<'_>,
    count: usize,
    env: &Env<'_>,
) -> Result<(), String> {
    let outcome = execute(dag, env, Mode::Plan);
    let segs = segments(seeds.nodes.len(), count);
    let owner = owners(dag, seeds.nodes, seeds.per_item_stages);
    let mut tainted = vec![false; dag.len()];
    // Per segment: number of missing nodes and the first one.
    let mut missing: Vec<(usize, Option<String>)> = vec![(0, None); segs.len()];
    for report in &outcome.reports {
        let id = report.id;
        let node = &dag.nodes()[id];
        let failed_before = report.key.is_some_and(|key| {
            let variant = node.variants.first().map_or("default", String::as_str);
            load_failure(env.store, &report.identity, variant)
                .is_some_and(|f| f.ran_with.key == key.to_string())
        });
        tainted[id] = failed_before || node.upstream_ids().iter().any(|&u| tainted[u]);
        let (Some(o), NodeStatus::WillRun { .. }) = (owner[id], &report.status) else {
            continue;
        };
        if !tainted[id] {
            let m = &mut missing[segment_of(&segs, o)];
            m.0 += 1;
            m.1.get_or_insert_with(|| report.identity.clone());
        }
    }
    let incomplete: Vec<String> = missing
        .iter()
        .enumerate()
        .filter(|(_, (n, _))| *n > 0)
        .map(|(k, (n, first))| {
            format!(
                "shard {}/{count}: {n} node(s) not computed (first: {})",
                k + 1,
                first.as_deref().unwrap_or("?")
            )
        })
        .collect();
    if incomplete.is_empty() {
        return Ok(());
    }
    let list: Vec<String> = missing
        .iter()
        .enumerate()
        .filter(|(_, (n, _))| *n > 0)
        .map(|(k, _)| (k + 1).to_string())
        .collect();
    Err(format!(
        "cannot merge: {} of {count} shard(s) are incomplete — {}. Run them again (`skytie run WORKFLOW --shard K/{count}` \
         for K in {}, with the same workflow, campaign and cache), then merge again; a plain run without \
         --merge computes whatever is missing itself",
        incomplete.len(),
        incomplete.join("; "),
        list.join(", ")
    ))
}

//! Executes (or plans) a DAG against the content-addressed store.
//!
//! Nodes run in topological waves on the rayon pool; every parallel step collects in node order, so results
//! and records are identical for 1 or N threads. For each wave:
//! 1. check (parallel): skip nodes whose upstream failed; hash raw-file inputs (stat cache); compute the key
//!    from the inputs' content hashes (early cutoff); a key whose output hash is known (the record packs'
//!    index, loaded once per execution) and whose entry exists is CACHED without reading the artifact
//!    (existence: one listing of the store in plan mode, one call marking the entry used in run mode);
//!    otherwise `Store::load` (Hit ⇒ cached; Corrupt ⇒ one warning, recompute; Miss ⇒ run).
//! 2. load (parallel, each value once) the inputs the nodes to run need; an input that turns out corrupt or
//!    missing is recomputed first (recursively).
//! 3. run (parallel) inside `catch_unwind`: an error or panic marks the node FAILED and nothing is stored;
//!    success is encoded, saved, then recorded (output record, node record).
//! 4. account (sequential): statuses, progress, release values no consumer needs any more.
//!
//! The records of the nodes that ran (or were found under a key their record did not have) go into one record
//! pack per execution, and the store is flushed once at the end.
//!
//! No lock is ever held while a stage runs or the store is called (rayon work stealing could otherwise
//! re-enter the lock on the same thread).

mod cache_check;
mod outcome;
mod records;
mod values;

pub use outcome::{recorded_inputs, NodeReport, Outcome};
use outcome::{recorded_with, Upstream};

use crate::dag::builder::Dag;
use crate::dag::inputs::{absent_hash, InputRef, InputValue, NodeId, RawFileValue};
use crate::dag::key::node_key;
use crate::dag::node::{AnyValue, Node};
use crate::dag::progress::Progress;
use crate::dag::record::{self, RecordedInput};
use crate::dag::record_pack::{PackWriter, RecordIndex};
use crate::dag::stage::{dirs_root, tmp_dir_for, NodeCtx};
pub use crate::dag::status::NodeStatus;
use crate::hashing::{ContentHash, NodeKey, StatCache};
use crate::store::{EntryMeta, Store};
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

/// The recorded hash of an optional input that was absent.
pub const ABSENT: &str = "absent";

/// Run the stages, or only say what would run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Run,
    Plan,
}

/// Where an execution reads and writes.
pub struct Env<'a> {
    pub store: &'a Store,
    pub stat_cache: &'a StatCache,
    pub progress: &'a Progress,
}

#[derive(Default)]
struct Slot {
    status: Option<NodeStatus>,
    key: Option<NodeKey>,
    hash: Option<ContentHash>,
    value: Option<AnyValue>,
    seconds: f64,
    file_hashes: Vec<ContentHash>,
    consumers_left: u32,
}

enum Check {
    Cached {
        key: NodeKey,
        hash: ContentHash,
        value: Option<AnyValue>,
        record_stale: bool,
    },
    Run {
        key: NodeKey,
    },
    WillRun(Vec<String>),
    Failed(String),
    Skipped(String),
}

struct Exec<'a> {
    dag: &'a Dag,
    env: &'a Env<'a>,
    mode: Mode,
    slots: Vec<Mutex<Slot>>,
    warnings: Mutex<(Vec<String>, BTreeSet<String>)>,
    /// The record packs' index: last key and output hash of each node, output hash of each key.
    index: RecordIndex,
    /// Plan mode: the keys of the index whose entry exists, from one listing of the store (`None`: the store
    /// holds far more entries than the graph has nodes, each node checks its own entry).
    present: Option<crate::dag::objects_listing::Present>,
    /// The pack this execution writes its records into (opened on the first record).
    pack: Mutex<Option<PackWriter>>,
    /// Whether any failure record exists (only then does a success remove the node's failure record).
    failures_recorded: bool,
    /// Run mode: marks cached entries used.
    marker: crate::dag::objects_listing::EntryMarker,
}

/// Execute (or plan) `dag`. Never panics on stage errors/panics or store trouble; those become node
/// statuses and warnings.
pub fn execute(dag: &Dag, env: &Env<'_>, mode: Mode) -> Outcome {
    let start = Instant::now();
    let mut slots: Vec<Mutex<Slot>> = (0..dag.nodes.len())
        .map(|_| Mutex::new(Slot::default()))
        .collect();
    for node in &dag.nodes {
        for u in node.upstream_ids() {
            lock(&mut slots, u).consumers_left += 1;
        }
    }
    let index = RecordIndex::load(env.store);
    let present = match mode {
        Mode::Plan => crate::dag::objects_listing::Present::list(env.store, &index, dag.len()),
        Mode::Run => None,
    };
    let ex = Exec {
        dag,
        env,
        mode,
        slots,
        warnings: Mutex::new((Vec::new(), BTreeSet::new())),
        index,
        present,
        pack: Mutex::new(None),
        failures_recorded: record::any_failure_recorded(env.store),
        marker: crate::dag::objects_listing::EntryMarker::new(env.store),
    };
    let mut totals: BTreeMap<&'static str, usize> = BTreeMap::new();
    for n in &dag.nodes {
        *totals.entry(n.stage).or_default() += 1;
    }
    if mode == Mode::Run {
        env.progress.begin(&totals);
    }
    for wave in dag.waves() {
        ex.run_wave(&wave);
    }
    // Values the caller asked for (loaded from the cache if the node was cached).
    let requested: Vec<NodeId> = (0..dag.nodes.len())
        .filter(|&i| {
            dag.nodes[i].requested && ex.slot(i).status.as_ref().is_some_and(|s| s.is_ok())
        })
        .collect();
    let failures = ex.ensure_values(&requested);
    for (id, msg) in failures {
        ex.set_status(id, NodeStatus::Failed(msg));
    }
    if mode == Mode::Run {
        env.progress.end();
        ex.commit_records();
    }
    // The index is not needed any more: free it before the reports are built (peak memory).
    let Exec {
        slots,
        warnings,
        index,
        present,
        ..
    } = ex;
    drop((index, present));
    let mut values = HashMap::new();
    let mut reports = Vec::with_capacity(dag.nodes.len());
    // Last node first, giving the slots' memory back as the reports take it (peak memory of a large graph).
    let mut slots = slots;
    while let Some(slot) = slots.pop() {
        let id = slots.len();
        let node = &dag.nodes[id];
        if id % 4096 == 0 && slots.capacity() > slots.len() + slots.len() / 8 {
            slots.shrink_to_fit();
        }
        let mut s = slot.into_inner().unwrap_or_else(|e| e.into_inner());
        if node.requested {
            if let Some(v) = s.value.take() {
                values.insert(id, v);
            }
        }
        reports.push(NodeReport {
            id,
            identity: node.identity(),
            stage: node.stage,
            stage_version: node.version,
            variants: node.variants.clone(),
            status: s.status.take().unwrap_or(NodeStatus::Failed(
                "internal error: node was not processed".into(),
            )),
            key: s.key,
            output_hash: s.hash,
            seconds: s.seconds,
            file_hashes: s.file_hashes,
        });
    }
    reports.reverse();
    let mut metrics = Vec::new();
    for sink in &dag.sinks {
        if let Some(v) = values.get(&sink.node) {
            if let Some(json) = (sink.to_json)(v.as_ref()) {
                metrics.push((sink.variant.clone(), sink.namespace.clone(), json));
            }
        }
    }
    let warnings = warnings.into_inner().unwrap_or_else(|e| e.into_inner()).0;
    Outcome {
        reports,
        values,
        warnings,
        metrics,
        seconds: start.elapsed().as_secs_f64(),
    }
}

fn lock(slots: &mut [Mutex<Slot>], id: NodeId) -> &mut Slot {
    slots[id].get_mut().unwrap_or_else(|e| e.into_inner())
}

/// Whether the entry of `key` exists; if so mark it as used now (like `Store::load` does), so `cache gc`
/// sees it as recently used and a live run protects it, without reading the artifact. One `utimensat`
/// system call on Unix (it fails with ENOENT when the entry is absent).
fn touch_entry(store: &Store, key: &NodeKey) -> bool {
    let path = store.object_path(key);
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        let Ok(c_path) = std::ffi::CString::new(path.as_os_str().as_bytes()) else {
            return false;
        };
        // SAFETY: `c_path` is a valid NUL-terminated string; a null `times` pointer means "now" for both
        // access and modification time (POSIX utimensat).
        let rc = unsafe { libc::utimensat(libc::AT_FDCWD, c_path.as_ptr(), std::ptr::null(), 0) };
        if rc == 0 {
            return true;
        }
        // Not ours to touch (e.g. a read-only shared cache): fall back to an existence check.
        std::io::Error::last_os_error().kind() != std::io::ErrorKind::NotFound && path.is_file()
    }
    #[cfg(not(unix))]
    match std::fs::File::open(&path) {
        Ok(f) => {
            let _ = f.set_modified(SystemTime::now());
            true
        }
        Err(_) => false,
    }
}

fn now_unix_s() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0)
}

fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "(non-text panic payload)".to_string()
    }
}

impl<'a> Exec<'a> {
    fn slot(&self, id: NodeId) -> std::sync::MutexGuard<'_, Slot> {
        self.slots[id].lock().unwrap_or_else(|e| e.into_inner())
    }

    fn warn(&self, message: String) {
        let mut w = self.warnings.lock().unwrap_or_else(|e| e.into_inner());
        if w.1.insert(message.clone()) {
            self.env.progress.warn(&message);
            w.0.push(message);
        }
    }

    /// Whether node `id` failed or was skipped (an optional input of it is absent).
    fn unavailable(&self, id: NodeId) -> bool {
        matches!(
            self.slot(id).status,
            Some(NodeStatus::Failed(_) | NodeStatus::Skipped { .. })
        )
    }

    fn set_status(&self, id: NodeId, status: NodeStatus) {
        self.slot(id).status = Some(status);
    }

    fn ctx(&self, node: &Node, key: NodeKey) -> NodeCtx<'a> {
        NodeCtx {
            stage: node.stage,
            item: node.item.clone(),
            key,
            cache_root: self.env.store.root().to_path_buf(),
            progress: Some(self.env.progress),
        }
    }

    fn run_wave(&self, wave: &[NodeId]) {
        // 1. check
        let checks: Vec<Check> = wave.par_iter().map(|&id| self.check(id)).collect();
        let mut to_run: Vec<(NodeId, NodeKey)> = Vec::new();
        for (&id, check) in wave.iter().zip(checks) {
            let node = &self.dag.nodes[id];
            match check {
                Check::Cached {
                    key,
                    hash,
                    value,
                    record_stale,
                } => {
                    if record_stale && self.mode == Mode::Run {
                        self.write_records(id, key, hash, 0.0);
                    }
                    let mut s = self.slot(id);
                    s.key = Some(key);
                    s.hash = Some(hash);
                    s.value = value;
                    s.status = Some(NodeStatus::Cached);
                    drop(s);
                    self.done(node, &NodeStatus::Cached);
                }
                Check::Run { key } => {
                    self.slot(id).key = Some(key);
                    to_run.push((id, key));
                }
                Check::WillRun(reasons) => self.set_status(id, NodeStatus::WillRun { reasons }),
                Check::Failed(msg) => {
                    let st = NodeStatus::Failed(msg);
                    self.done(node, &st);
                    self.set_status(id, st);
                }
                Check::Skipped(upstream) => {
                    let st = NodeStatus::Skipped { upstream };
                    self.done(node, &st);
                    self.set_status(id, st);
                }
            }
        }
        // 2. load inputs of the nodes to run
        if !to_run.is_empty() {
            let mut needed: Vec<NodeId> = to_run
                .iter()
                .flat_map(|(id, _)| self.dag.nodes[*id].upstream_ids())
                .filter(|&u| !self.unavailable(u))
                .collect();
            needed.sort_unstable();
            needed.dedup();
            let failures: HashMap<NodeId, String> =
                self.ensure_values(&needed).into_iter().collect();
            // 3. run
            if self.mode == Mode::Run {
                let mut stages: Vec<&'static str> = to_run
                    .iter()
                    .map(|(id, _)| self.dag.nodes[*id].stage)
                    .collect();
                stages.dedup();
                for stage in stages {
                    self.env.progress.stage_running(stage);
                }
            }
            let results: Vec<(NodeId, Result<f64, String>)> = to_run
                .par_iter()
                .map(|&(id, _)| {
                    let node = &self.dag.nodes[id];
                    let blocked = node
                        .upstream_ids()
                        .into_iter()
                        .find_map(|u| failures.get(&u).map(|m| (u, m.clone())));
                    let r = match blocked {
                        Some((u, m)) => Err(format!(
                            "upstream {} could not be loaded or recomputed: {m}",
                            self.dag.nodes[u].identity()
                        )),
                        None => self.execute_node(id),
                    };
                    let st = match &r {
                        Ok(_) => NodeStatus::Executed,
                        Err(m) => NodeStatus::Failed(m.clone()),
                    };
                    self.done(node, &st);
                    (id, r)
                })
                .collect();
            for (id, r) in results {
                let mut s = self.slot(id);
                match r {
                    Ok(secs) => {
                        s.seconds = secs;
                        s.status = Some(NodeStatus::Executed);
                    }
                    Err(m) => s.status = Some(NodeStatus::Failed(m)),
                }
            }
        }
        // 4. release values nobody needs any more (leaf nodes of this wave, inputs whose consumers are done)
        for &id in wave {
            if !self.dag.nodes[id].requested {
                let mut s = self.slot(id);
                if s.consumers_left == 0 {
                    s.value = None;
                }
            }
            for u in self.dag.nodes[id].upstream_ids() {
                let mut s = self.slot(u);
                s.consumers_left = s.consumers_left.saturating_sub(1);
                if s.consumers_left == 0 && !self.dag.nodes[u].requested {
                    s.value = None;
                }
            }
        }
    }

    fn done(&self, node: &Node, status: &NodeStatus) {
        if self.mode == Mode::Run {
            self.env.progress.node_done(node.stage, status);
        }
    }

    /// The inputs of node `id` as recorded now (from the slots of its upstream nodes).
    fn recorded_now(&self, id: NodeId) -> Vec<RecordedInput> {
        let files = self.slot(id).file_hashes.clone();
        recorded_with(self.dag, &self.dag.nodes[id], &files, |u| {
            let s = self.slot(u);
            Some(match (&s.status, s.hash) {
                (Some(NodeStatus::Failed(_) | NodeStatus::Skipped { .. }), _) => {
                    Upstream::Unavailable
                }
                (Some(NodeStatus::WillRun { .. }), _) => Upstream::Unknown,
                (_, Some(h)) => Upstream::Hash(h),
                _ => Upstream::Unknown,
            })
        })
    }

    /// Run node `id` (its input values are in memory), store and record its output. Returns seconds.
    fn execute_node(&self, id: NodeId) -> Result<f64, String> {
        let node = &self.dag.nodes[id];
        let mut values = Vec::with_capacity(node.inputs.len());
        let mut hashes = Vec::with_capacity(node.inputs.len());
        for (_, r) in &node.inputs {
            match r {
                InputRef::OptionalNode(u) if self.unavailable(*u) => {
                    values.push(InputValue::Absent);
                    hashes.push(absent_hash());
                }
                InputRef::Node(u) | InputRef::OptionalNode(u) => {
                    let s = self.slot(*u);
                    match (&s.value, s.hash) {
                        (Some(v), Some(h)) => {
                            values.push(InputValue::Node(v.clone()));
                            hashes.push(h);
                        }
                        _ => {
                            return Err(format!(
                                "internal error: input {} not loaded",
                                self.dag.nodes[*u].identity()
                            ))
                        }
                    }
                }
                InputRef::File(p) => {
                    let h = self
                        .env
                        .stat_cache
                        .hash_file(p)
                        .map_err(|e| format!("cannot read input file {}: {e}", p.display()))?;
                    values.push(InputValue::File(RawFileValue {
                        path: p.to_path_buf(),
                        hash: h,
                    }));
                    hashes.push(h);
                }
            }
        }
        let key = node_key(node, &hashes);
        let ctx = self.ctx(node, key);
        let start = Instant::now();
        let result = catch_unwind(AssertUnwindSafe(|| node.erased.run(&values, &ctx)));
        drop(values);
        let seconds = start.elapsed().as_secs_f64();
        let tmp = tmp_dir_for(self.env.store.root(), &key);
        let value = match result {
            Ok(Ok(v)) => v,
            Ok(Err(e)) => {
                let _ = std::fs::remove_dir_all(&tmp);
                return Err(e.message);
            }
            Err(p) => {
                let _ = std::fs::remove_dir_all(&tmp);
                return Err(format!("panicked: {}", panic_message(p.as_ref())));
            }
        };
        if tmp.exists() {
            let fin = dirs_root(self.env.store.root()).join(key.to_string());
            if fin.exists() || std::fs::rename(&tmp, &fin).is_err() {
                let _ = std::fs::remove_dir_all(&tmp);
            }
            if !fin.exists() {
                return Err(format!(
                    "could not move the output folder into place at {}",
                    fin.display()
                ));
            }
        }
        let meta = EntryMeta {
            stage: node.stage.to_string(),
            stage_version: node.version.to_string(),
            item: node.identity(),
        };
        // Encoded straight into the entry file (no payload buffer); encoding may panic on a type bincode cannot
        // represent (see `serde_artifact!`), which fails the node like a stage panic.
        let saved = catch_unwind(AssertUnwindSafe(|| {
            self.env
                .store
                .save_with(&key, &meta, |sink| node.erased.encode_to(&value, sink))
        }));
        let hash = match saved {
            Ok(Ok(hash)) => hash,
            Ok(Err(e)) => return Err(format!("could not store the result: {e}")),
            Err(p) => {
                return Err(format!(
                    "panicked while encoding its result: {}",
                    panic_message(p.as_ref())
                ))
            }
        };
        {
            let mut s = self.slot(id);
            s.key = Some(key);
            s.hash = Some(hash);
        }
        self.write_records(id, key, hash, seconds);
        let mut s = self.slot(id);
        s.key = Some(key);
        s.hash = Some(hash);
        s.value = Some(value);
        Ok(seconds)
    }
}

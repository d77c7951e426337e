//! A session runs (or plans) a pipeline's DAG phases against one store and keeps their reports.
//!
//! Staged planning: a pipeline builds phase 1 (e.g. the node that generates or imports the campaign), calls
//! [`Session::execute`], reads the requested outputs from the returned [`PhaseValues`] and builds phase 2
//! from them (per-item nodes). In plan mode a phase whose input is not cached yet cannot be built: the
//! pipeline gets [`PipelineError::NotYetAvailable`] from [`PhaseValues::require`] and `plan` reports the
//! phases it could plan.

use crate::dag::builder::Dag;
use crate::dag::executor::{execute, Env, Mode, NodeReport, Outcome};
use crate::dag::inputs::{Handle, NodeId};
use crate::dag::node::AnyValue;
use crate::dag::progress::Progress;
use crate::dag::shard::{Partition, Seeds};
use crate::hashing::StatCache;
use crate::store::Store;
use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

/// Why a pipeline could not be built or run to the end.
#[derive(Debug)]
pub enum PipelineError {
    /// A workflow problem (message already carries file:line:col).
    Workflow(String),
    /// A wiring problem in the pipeline code.
    Build(crate::dag::BuildError),
    /// Bad input data (message names the file and what to do).
    Input(String),
    /// Plan mode: this value is produced by a node that has not run yet.
    NotYetAvailable(String),
    /// A node whose output the next phase needs failed.
    Failed(String),
}

impl fmt::Display for PipelineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PipelineError::Workflow(m) | PipelineError::Input(m) => f.write_str(m),
            PipelineError::Build(e) => write!(f, "pipeline wiring error: {e}"),
            PipelineError::NotYetAvailable(what) => {
                write!(f, "{what} is not computed yet: the rest of the graph can be planned after it has run")
            }
            PipelineError::Failed(m) => write!(f, "{m}"),
        }
    }
}
impl std::error::Error for PipelineError {}

impl From<crate::dag::BuildError> for PipelineError {
    fn from(e: crate::dag::BuildError) -> Self {
        PipelineError::Build(e)
    }
}

/// The requested values of one executed phase.
pub struct PhaseValues {
    values: HashMap<NodeId, AnyValue>,
    mode: Mode,
    failed: HashMap<NodeId, String>,
}

impl PhaseValues {
    /// The value of a requested node, if available.
    pub fn get<T: Send + Sync + 'static>(&self, handle: Handle<T>) -> Option<Arc<T>> {
        self.values.get(&handle.id)?.clone().downcast::<T>().ok()
    }
    /// The value of a requested node, or the reason it is not there (`what` names it for the user).
    pub fn require<T: Send + Sync + 'static>(
        &self,
        handle: Handle<T>,
        what: &str,
    ) -> Result<Arc<T>, PipelineError> {
        if let Some(v) = self.get(handle) {
            return Ok(v);
        }
        match (self.mode, self.failed.get(&handle.id)) {
            (_, Some(msg)) => Err(PipelineError::Failed(format!(
                "{what} could not be produced: {msg}"
            ))),
            (Mode::Plan, None) => Err(PipelineError::NotYetAvailable(what.to_string())),
            (Mode::Run, None) => Err(PipelineError::Failed(format!("{what} was not produced"))),
        }
    }
}

/// One executed phase: its graph and what happened.
pub struct Phase {
    pub name: String,
    pub dag: Dag,
    pub reports: Vec<NodeReport>,
    pub warnings: Vec<String>,
    pub metrics: Vec<(String, String, serde_json::Value)>,
    pub seconds: f64,
    /// Ids of the requested nodes (the phase's useful outputs).
    pub requested: Vec<NodeId>,
}

impl Phase {
    /// The inputs of node `id` with their sources and hashes (see [`crate::dag::executor::recorded_inputs`]).
    pub fn inputs(&self, id: NodeId) -> Vec<crate::dag::record::RecordedInput> {
        crate::dag::executor::recorded_inputs(&self.dag, &self.reports, id)
    }
}

/// See the module documentation.
pub struct Session<'a> {
    pub store: &'a Store,
    pub stat_cache: &'a StatCache,
    pub progress: &'a Progress,
    pub mode: Mode,
    pub phases: Vec<Phase>,
    /// Where a run writes its outputs (`None` when planning): pipelines write their user-facing exports here
    /// after the phase that produced them (sweeps: into `variants/<name>/`).
    pub out_dir: Option<std::path::PathBuf>,
    /// Which part of the sharded phase this process runs (see [`crate::dag::shard`]).
    pub partition: Partition,
}

impl<'a> Session<'a> {
    pub fn new(
        store: &'a Store,
        stat_cache: &'a StatCache,
        progress: &'a Progress,
        mode: Mode,
    ) -> Self {
        Session {
            store,
            stat_cache,
            progress,
            mode,
            phases: Vec::new(),
            out_dir: None,
            partition: Partition::Whole,
        }
    }

    /// Execute (or plan) one phase's DAG; the requested values come back, the reports stay in the session.
    pub fn execute(&mut self, name: &str, dag: Dag) -> PhaseValues {
        let env = Env {
            store: self.store,
            stat_cache: self.stat_cache,
            progress: self.progress,
        };
        let Outcome {
            reports,
            values,
            warnings,
            metrics,
            seconds,
        } = execute(&dag, &env, self.mode);
        if self.mode == Mode::Run {
            // `plan` says "failed last time: <error>" for these until they succeed.
            if let Err(e) = crate::dag::failures::save_failures(self.store, &dag, &reports) {
                self.progress
                    .warn(&format!("could not record the failed nodes: {e}"));
            }
        }
        let failed: HashMap<NodeId, String> = reports
            .iter()
            .filter_map(|r| match &r.status {
                crate::dag::NodeStatus::Failed(m) => Some((r.id, m.clone())),
                crate::dag::NodeStatus::Skipped { upstream } => {
                    Some((r.id, format!("skipped: upstream {upstream} failed")))
                }
                _ => None,
            })
            .collect();
        let requested = dag
            .nodes()
            .iter()
            .enumerate()
            .filter(|(_, n)| n.requested)
            .map(|(i, _)| i)
            .collect();
        self.phases.push(Phase {
            name: name.to_string(),
            dag,
            reports,
            warnings,
            metrics,
            seconds,
            requested,
        });
        PhaseValues {
            values,
            mode: self.mode,
            failed,
        }
    }

    /// Execute the phase whose per-item nodes are sharded, as [`Session::partition`] says: everything, nothing
    /// (`Prepare`), the nodes one segment of `seeds` owns (`Shard`; no values come back), or everything once
    /// every segment is complete (`Merge`). See [`crate::dag::shard`].
    pub fn execute_sharded(
        &mut self,
        name: &str,
        dag: Dag,
        seeds: &Seeds<'_>,
    ) -> Result<PhaseValues, PipelineError> {
        match self.partition {
            Partition::Whole => Ok(self.execute(name, dag)),
            Partition::Prepare => Ok(PhaseValues {
                values: HashMap::new(),
                mode: self.mode,
                failed: HashMap::new(),
            }),
            Partition::Shard(spec) => {
                let targets = crate::dag::shard::segment_targets(&dag, seeds, spec);
                let (mut sub, _) = dag.into_subgraph(&targets);
                for n in &mut sub.nodes {
                    n.requested = false;
                }
                Ok(self.execute(name, sub))
            }
            Partition::Merge { count } => {
                if self.mode == Mode::Run {
                    let env = Env {
                        store: self.store,
                        stat_cache: self.stat_cache,
                        progress: self.progress,
                    };
                    crate::dag::shard::check_complete(&dag, seeds, count, &env)
                        .map_err(PipelineError::Failed)?;
                }
                Ok(self.execute(name, dag))
            }
        }
    }

    /// All node reports of all phases.
    pub fn reports(&self) -> impl Iterator<Item = &NodeReport> {
        self.phases.iter().flat_map(|p| p.reports.iter())
    }

    /// All metrics contributions: (variant, namespace, object).
    pub fn metrics(&self) -> impl Iterator<Item = &(String, String, serde_json::Value)> {
        self.phases.iter().flat_map(|p| p.metrics.iter())
    }
}

//! The dataflow engine: typed stages and handles, graph building, keys, records and the executor.

pub mod builder;
pub mod executor;
pub mod inputs;
pub mod key;
pub mod node;
pub mod record;
pub mod stage;

pub use builder::{BuildError, Dag, DagBuilder};
pub use executor::{execute, Env, Mode, NodeReport, NodeStatus, Outcome};
pub use inputs::{Handle, InputSet, NodeId, RawFile, RawFileValue};
pub use stage::{NodeCtx, Stage, StageError};
pub mod pipeline;
pub mod session;

pub use pipeline::{pipeline_by_name, Pipeline};
pub use session::{Phase, PhaseValues, PipelineError, Session};

//! The dataflow engine: typed stages and handles, graph building, keys, records and the executor.

pub mod builder;
pub mod error;
pub mod executor;
pub mod failures;
pub mod inputs;
pub mod json_diff;
pub mod key;
pub mod node;
pub mod objects_listing;
pub mod progress;
pub mod record;
pub mod record_pack;
pub mod shard;
pub mod stage;
pub mod status;

pub use builder::{BuildError, Dag, DagBuilder};
pub use error::StageError;
pub use executor::{execute, recorded_inputs, Env, Mode, NodeReport, NodeStatus, Outcome};
pub use inputs::{optional_all, Handle, InputSet, NodeId, Optional, RawFile, RawFileValue};
pub use stage::{InputsOf, NodeCtx, RunResult, Stage};
pub mod pipeline;
pub mod session;

pub use pipeline::Pipeline;
pub use session::{Phase, PhaseValues, PipelineError, Session};
pub use shard::{Partition, Seeds, ShardSpec};

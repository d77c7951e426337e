//! Pipelines: Rust functions that turn a workflow into DAG phases. A workflow names its pipeline
//! (`pipeline = "skytie"` by default); the command line's registry (`pipelines::by_name`) maps names to
//! implementations, so the engine knows none of them.

use crate::dag::session::{PipelineError, Session};
use crate::workflow::Workflow;

/// Builds and executes a workflow's phases in a session.
pub trait Pipeline: Sync {
    /// The name workflows use.
    fn name(&self) -> &'static str;
    /// The stage names this pipeline knows (for messages).
    fn stage_names(&self) -> Vec<&'static str>;
    /// Check everything that can be checked before running (all params of all variants), so a workflow
    /// error is reported before any work is done. Messages carry file:line:col.
    fn validate(&self, _workflow: &Workflow) -> Result<(), String> {
        Ok(())
    }
    /// Build each phase, execute it with `session.execute`, build the next from its values.
    fn run(&self, workflow: &Workflow, session: &mut Session<'_>) -> Result<(), PipelineError>;
}

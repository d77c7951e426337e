//! Pipelines: Rust functions that turn a workflow into DAG phases. A workflow names its pipeline
//! (`pipeline = "skytie"` by default); the registry below maps names to implementations.

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

/// The pipeline a workflow asks for.
pub fn pipeline_by_name(name: &str) -> Result<&'static dyn Pipeline, String> {
    match name {
        "skytie" => Ok(&crate::pipelines::skytie::SkytiePipeline),
        "toy" => Ok(&crate::testing::toy_pipeline::ToyPipeline),
        other => Err(format!(
            "unknown pipeline '{other}': this skytie knows: {} (set `pipeline = ...` in the workflow)",
            known_pipelines().join(", ")
        )),
    }
}

/// Names of the registered pipelines.
pub fn known_pipelines() -> Vec<&'static str> {
    vec!["skytie", "toy"]
}

//! Pipelines built from the real stages (`pipeline = "skytie"`, the default). The `toy` pipeline used by the
//! engine's own tests lives in `crate::testing`.

pub mod adjust;
pub mod nadir;
pub mod oblique;
pub mod skytie;
pub mod vehicle;

use crate::dag::PipelineError;
use crate::workflow::Workflow;
use skytie_stages::campaign::Recording;

/// A workflow problem found while building the graph.
pub(crate) fn wf_err(e: impl std::fmt::Display) -> PipelineError {
    PipelineError::Workflow(e.to_string())
}

/// Horizontal distance between two recordings' recorded positions, metres.
pub(crate) fn distance_m(a: &Recording, b: &Recording) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

/// The error for a chain enabled up to `last` whose upstream stages `missing` are not in `stages`; `order`
/// lists the chain's stages in dependency order.
pub(crate) fn missing_upstream(
    wf: &Workflow,
    chain: &str,
    last: &str,
    missing: &[&str],
    order: &str,
) -> PipelineError {
    wf_err(format!(
        "{}: the {chain} chain is enabled up to '{last}' but its upstream stage(s) {} are not in `stages`; \
         add them (order: {order})",
        wf.path.display(),
        missing.join(", "),
    ))
}

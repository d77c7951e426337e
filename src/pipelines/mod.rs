//! Pipelines built from the real stages (`pipeline = "skytie"`, the default), and the registry of every
//! pipeline the command line can run (the `toy` pipeline used by the engine's own tests lives in
//! `crate::testing`).

pub mod adjust;
pub mod catalogue;
pub mod nadir;
pub mod oblique;
pub mod orthophoto;
pub mod shards;
pub mod skytie;
pub mod validate;
pub mod vehicle;

use crate::dag::{Pipeline, PipelineError};
use crate::workflow::Workflow;
use skytie_stages::campaign::Recording;

/// Stage names as each stage defines them next to its algorithm (`STAGE.name`); workflows enable stages and
/// name parameter tables with these.
pub mod stage {
    #[allow(missing_docs)]
    pub const SYNTH: &str = skytie_stages::synth::generate::STAGE.name;
    #[allow(missing_docs)]
    pub const LOAD: &str = skytie_stages::campaign::read::STAGE.name;
    #[allow(missing_docs)]
    pub const ORTHO: &str = skytie_stages::nadir::ortho::STAGE.name;
    #[allow(missing_docs)]
    pub const SUMMARY: &str = crate::nodes::campaign::summary::STAGE.name;
    #[allow(missing_docs)]
    pub const MM_MATCH: &str = skytie_stages::nadir::mm_matching::STAGE.name;
    #[allow(missing_docs)]
    pub const ORTHO_AERIAL: &str = skytie_stages::nadir::aerial_patch::STAGE.name;
    #[allow(missing_docs)]
    pub const TRANSFORM: &str = skytie_stages::nadir::initial_transform::STAGE.name;
    #[allow(missing_docs)]
    pub const REFINE: &str = skytie_stages::nadir::refine::STAGE.name;
    #[allow(missing_docs)]
    pub const CONTROL: &str = skytie_stages::nadir::control_points::STAGE.name;
    #[allow(missing_docs)]
    pub const NADIR: &str = skytie_stages::nadir::summary::STAGE.name;
    #[allow(missing_docs)]
    pub const GRADE_NADIR: &str = skytie_stages::nadir::grading::STAGE.name;
    #[allow(missing_docs)]
    pub const ADJUST: &str = skytie_stages::adjustment::from_correspondences::STAGE.name;
    #[allow(missing_docs)]
    pub const GRADE_ADJUST: &str = crate::nodes::adjust::grade::STAGE.name;
    #[allow(missing_docs)]
    pub const VERIFY: &str = skytie_stages::adjustment::verify::STAGE.name;
    #[allow(missing_docs)]
    pub const BASELINE: &str = skytie_stages::nadir::baseline::STAGE.name;
    #[allow(missing_docs)]
    pub const SPARSE_CLOUD: &str = skytie_stages::oblique::sparse_cloud::STAGE.name;
    #[allow(missing_docs)]
    pub const FACADES: &str = skytie_stages::oblique::facades::STAGE.name;
    #[allow(missing_docs)]
    pub const PATCHES: &str = skytie_stages::oblique::patch_registration::STAGE.name;
    #[allow(missing_docs)]
    pub const OBLIQUE: &str = skytie_stages::oblique::consensus::STAGE.name;
    #[allow(missing_docs)]
    pub const GRADE_OBLIQUE: &str = skytie_stages::oblique::grading::STAGE.name;

    /// Every stage a workflow may enable in `stages = [...]`, in pipeline order.
    pub const ALL: [&str; 20] = [
        SYNTH,
        LOAD,
        ORTHO,
        SUMMARY,
        MM_MATCH,
        ORTHO_AERIAL,
        TRANSFORM,
        REFINE,
        CONTROL,
        NADIR,
        GRADE_NADIR,
        ADJUST,
        GRADE_ADJUST,
        VERIFY,
        BASELINE,
        SPARSE_CLOUD,
        FACADES,
        PATCHES,
        OBLIQUE,
        GRADE_OBLIQUE,
    ];
}

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

/// The pipeline a workflow asks for.
pub fn pipeline_by_name(name: &str) -> Result<&'static dyn Pipeline, String> {
    match name {
        "skytie" => Ok(&skytie::SkytiePipeline),
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

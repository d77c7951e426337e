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
pub mod variant;
pub mod vehicle;

use crate::dag::{Pipeline, PipelineError};
use crate::workflow::Workflow;
use skytie_stages::campaign::Recording;

/// Declares the module `stage`: one constant per stage name, taken from the stage's `STAGE` next to its
/// algorithm, and `ALL`, every name in the order listed.
macro_rules! stage_names {
    ($($name:ident = $id:path),+ $(,)?) => {
        /// Stage names as each stage defines them next to its algorithm (`STAGE.name`); workflows enable stages
        /// and name parameter tables with these.
        pub mod stage {
            $(
                #[allow(missing_docs)]
                pub const $name: &str = $id.name;
            )+

            /// Every stage a workflow may enable in `stages = [...]`, in pipeline order.
            pub const ALL: [&str; [$(stringify!($name)),+].len()] = [$($name),+];
        }
    };
}

stage_names! {
    SYNTH = skytie_stages::synth::generate::STAGE,
    LOAD = skytie_stages::campaign::read::STAGE,
    ORTHO = skytie_stages::nadir::ortho::STAGE,
    SUMMARY = crate::nodes::campaign::summary::STAGE,
    MM_MATCH = skytie_stages::nadir::mm_matching::STAGE,
    ORTHO_AERIAL = skytie_stages::nadir::aerial_patch::STAGE,
    TRANSFORM = skytie_stages::nadir::initial_transform::STAGE,
    REFINE = skytie_stages::nadir::refine::STAGE,
    CONTROL = skytie_stages::nadir::control_points::STAGE,
    ORTHOPHOTO = skytie_stages::orthophoto::STAGE,
    NADIR = skytie_stages::nadir::summary::STAGE,
    GRADE_NADIR = skytie_stages::nadir::grading::STAGE,
    ADJUST = skytie_stages::adjustment::from_correspondences::STAGE,
    GRADE_ADJUST = crate::nodes::adjust::grade::STAGE,
    VERIFY = skytie_stages::adjustment::verify::STAGE,
    BASELINE = skytie_stages::nadir::baseline::STAGE,
    SPARSE_CLOUD = skytie_stages::oblique::sparse_cloud::STAGE,
    FACADES = skytie_stages::oblique::facades::STAGE,
    PATCHES = skytie_stages::oblique::patch_registration::STAGE,
    OBLIQUE = skytie_stages::oblique::consensus::STAGE,
    GRADE_OBLIQUE = skytie_stages::oblique::grading::STAGE,
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

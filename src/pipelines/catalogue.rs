//! The parameter tables of the `skytie` pipeline: which workflow table configures which stage, with which
//! parameter type. One list serves three purposes — the whole workflow is validated against it before any work
//! starts (every table × every sweep variant), `skytie params [TABLE]` prints it, and `docs/parameters.md` is
//! generated from it (a test keeps the file equal to the output).
//!
//! Table names are the stages' own names (`skytie_stages::…::STAGE.name`), defined once next to each algorithm.

use crate::nodes::campaign::synth::SynthParams;
use crate::nodes::nadir::options::NadirOptions;
use crate::nodes::oblique::options::ObliqueOptions;
use crate::workflow::{StageParams, Workflow, WorkflowError};
use serde::Serialize;
use skytie_stages::adjustment::verify::VerifyConfig;
use skytie_stages::adjustment::AdjustConfig;
use skytie_stages::nadir::baseline::BaselineParams;
use skytie_stages::nadir::control_points::ControlParams;
use skytie_stages::nadir::initial_transform::TransformParams;
use skytie_stages::nadir::mm_matching::MmMatchParams;
use skytie_stages::nadir::refine::RefineParams;
use skytie_stages::nadir::OrthoParams;
use skytie_stages::oblique::facades::FacadeParams;
use skytie_stages::oblique::patch_registration::PatchParams;
use skytie_stages::oblique::sparse_cloud::SparseCloudParams;
use skytie_stages::orthophoto::OrthophotoParams;
use skytie_stages::params::{ParamSpec, Params, StageId};
use skytie_stages::{adjustment, nadir, oblique, orthophoto, synth};

/// One workflow table: its name (the stage's), what the stage does, and its parameter type's documentation,
/// defaults and validation.
pub struct ParamTable {
    /// The table name in a workflow (`[ortho]`), equal to the stage name.
    pub table: &'static str,
    /// What the stage does, in one line (with the thesis section where there is one).
    pub summary: &'static str,
    specs: fn() -> Vec<ParamSpec>,
    defaults: fn() -> toml::Value,
    check: fn(&Workflow, &'static str, &str) -> Result<(), WorkflowError>,
}

impl ParamTable {
    /// Every parameter of the table (sections carry their nested parameters).
    pub fn specs(&self) -> Vec<ParamSpec> {
        (self.specs)()
    }

    /// The defaults as a TOML table (what an empty `[table]` means).
    pub fn defaults(&self) -> toml::Value {
        (self.defaults)()
    }

    /// Deserialise and validate the table of `variant` in `wf`.
    pub fn check(&self, wf: &Workflow, variant: &str) -> Result<(), WorkflowError> {
        (self.check)(wf, self.table, variant)
    }
}

fn table<P>(stage: StageId, summary: &'static str) -> ParamTable
where
    P: Params + StageParams + Serialize,
{
    fn defaults<P: Params + Serialize>() -> toml::Value {
        toml::Value::try_from(P::default()).unwrap_or(toml::Value::Table(toml::Table::new()))
    }
    fn check<P: StageParams>(
        wf: &Workflow,
        table: &'static str,
        variant: &str,
    ) -> Result<(), WorkflowError> {
        wf.params::<P>(table, variant).map(|_| ())
    }
    ParamTable {
        table: stage.name,
        summary,
        specs: P::specs,
        defaults: defaults::<P>,
        check: check::<P>,
    }
}

/// Every parameter table of the `skytie` pipeline, in pipeline order.
pub fn tables() -> Vec<ParamTable> {
    vec![
        table::<SynthParams>(
            synth::generate::STAGE,
            "generate a synthetic campaign (used when the workflow's campaign is `synth:PRESET`)",
        ),
        table::<OrthoParams>(
            nadir::ortho::STAGE,
            "project each panorama onto the road plane as a top-view image (thesis 3.4.3)",
        ),
        table::<MmMatchParams>(
            nadir::mm_matching::STAGE,
            "match consecutive top-view images to link recordings (thesis 3.4.4)",
        ),
        table::<TransformParams>(
            nadir::initial_transform::STAGE,
            "initial transform of a top-view image onto the aerial nadir image (thesis 3.4.5.2)",
        ),
        table::<RefineParams>(
            nadir::refine::STAGE,
            "locate the tie points in the aerial image by phase correlation (thesis 3.4.5.3)",
        ),
        table::<ControlParams>(
            nadir::control_points::STAGE,
            "triangulate registered road points from the aerial images as control (thesis 3.4.5.4)",
        ),
        table::<OrthophotoParams>(
            orthophoto::STAGE,
            "register the top-view images with the campaign's orthophoto and take control from it and the DTM",
        ),
        table::<BaselineParams>(
            nadir::baseline::STAGE,
            "the thesis' feature-matching baseline registration, for comparison (thesis 2.2.3)",
        ),
        table::<NadirOptions>(
            nadir::summary::STAGE,
            "options of the nadir chain as a whole: which matcher, which aerial images",
        ),
        table::<SparseCloudParams>(
            oblique::sparse_cloud::STAGE,
            "sparse point cloud from the panoramas around a recording (thesis 4.4.1)",
        ),
        table::<FacadeParams>(
            oblique::facades::STAGE,
            "façade planes fitted to the sparse cloud (thesis 4.4.2–4.4.4)",
        ),
        table::<PatchParams>(
            oblique::patch_registration::STAGE,
            "register façade patches with the oblique aerial images (thesis 4.4.5–4.4.6)",
        ),
        table::<ObliqueOptions>(
            oblique::consensus::STAGE,
            "options of the oblique chain as a whole and the consensus of its matches (thesis 4.4.7)",
        ),
        table::<AdjustConfig>(
            adjustment::from_correspondences::STAGE,
            "adjust the trajectory to the aerial control (thesis chapter 5)",
        ),
        table::<VerifyConfig>(
            adjustment::verify::STAGE,
            "verify a trajectory against the aerial images per segment, without adjusting (thesis 5.7)",
        ),
    ]
}

/// The table named `name`, if the pipeline has one.
pub fn find(name: &str) -> Option<ParamTable> {
    tables().into_iter().find(|t| t.table == name)
}

/// Validate every table of `wf` for every variant; all problems, one per line.
pub fn validate(wf: &Workflow) -> Result<(), String> {
    let mut problems: Vec<String> = Vec::new();
    let variants = wf.variants();
    for t in tables() {
        // The synthetic campaign is generated once, from the workflow without variant overrides.
        let for_variants: &[String] = if t.table == synth::generate::STAGE.name {
            &[]
        } else {
            &variants
        };
        let default = [crate::workflow::DEFAULT_VARIANT.to_string()];
        for v in for_variants.iter().chain(default.iter()) {
            if let Err(e) = t.check(wf, v) {
                let line = e.to_string();
                if !problems.contains(&line) {
                    problems.push(line);
                }
            }
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("\n"))
    }
}

//! Workflows: TOML files that choose the campaign, the pipeline, the enabled stages and their parameters, and
//! optionally sweep variants; with includes, and errors that carry `file:line:col` and "did you mean".
//! The format is documented for users in `workflows/README.md`.
//!
//! ```no_run
//! # use skytie::workflow::{Workflow, StageParams, ParamError};
//! # #[derive(serde::Serialize, serde::Deserialize, Default, Clone)]
//! # #[serde(deny_unknown_fields, default)] struct OrthoParams { gsd_m: f64 }
//! # impl StageParams for OrthoParams { fn validate(&self) -> Result<(), Vec<ParamError>> { Ok(()) } }
//! let workflow = Workflow::load(std::path::Path::new("workflows/default.toml"))?;
//! for variant in workflow.variants() {
//!     let ortho: OrthoParams = workflow.params("ortho", &variant)?;
//! }
//! # Ok::<(), skytie::workflow::WorkflowError>(())
//! ```

mod campaign_source;
mod definition;
mod deserializer;
mod error;
mod file;
mod params;
mod source;
pub mod suggest;
mod sweep;
mod tree;

pub use campaign_source::{CampaignSource, SYNTH_PRESETS};
pub use definition::{Workflow, DEFAULT_PIPELINE, DEFAULT_VARIANT, TOP_LEVEL_KEYS};
pub use error::{ParamError, WorkflowError};
pub use params::{default_field_names, StageParams};

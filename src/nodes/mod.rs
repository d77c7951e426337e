//! The engine's wrappers of `skytie-stages` algorithms as typed, cached DAG stages, grouped like the
//! pipelines (`campaign`, `nadir`, `oblique`, `adjust`), one file per stage, and the artifacts they exchange.
//! The algorithms, their versions and their parameters live in `stages/`; this layer only adds typed inputs and
//! encoding.

pub mod adjust;
pub mod campaign;
pub mod nadir;
pub mod oblique;
pub mod params;

pub use campaign::load::{
    CampaignSnapshot, LoadCampaign, LoadCampaignParams, SelectRecording, SelectRecordingParams,
};
pub use campaign::summary::{CampaignSummary, SummarizeCampaign, SummaryParams};
pub use campaign::synth::{GeneratedCampaign, RenderCampaign, SynthCampaign, SynthParams};
pub use nadir::ortho::OrthoProject;

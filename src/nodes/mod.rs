//! The engine's wrappers of `skytie-stages` algorithms as typed, cached DAG stages (one file per stage), and
//! the artifacts they exchange. The algorithms live in `stages/`; this layer only adds names, versions, typed
//! inputs, parameter validation and encoding.

pub mod adjust;
pub mod adjust_grade;
pub mod aerial;
pub mod baseline;
pub mod campaign;
pub mod consensus;
pub mod control;
pub mod decoded_images;
pub mod facades;
pub mod mm_match;
pub mod nadir_grade;
pub mod nadir_options;
pub mod nadir_summary;
pub mod oblique_grade;
pub mod oblique_options;
pub mod ortho;
pub mod ortho_aerial;
pub mod params;
pub mod patches;
pub mod refine;
pub mod sparse_cloud;
pub mod summary;
pub mod synth;
pub mod transform;
pub mod transform_agreement;
pub mod vehicle;
pub mod verify;

pub use campaign::{
    CampaignSnapshot, LoadCampaign, LoadCampaignParams, SelectRecording, SelectRecordingParams,
};
pub use ortho::OrthoProject;
pub use summary::{CampaignSummary, SummarizeCampaign, SummaryParams};
pub use synth::{GeneratedCampaign, RenderCampaign, SynthCampaign, SynthParams};

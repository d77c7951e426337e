//! The engine's wrappers of `skytie-stages` algorithms as typed, cached DAG stages, grouped like the
//! pipelines (`campaign`, `nadir`, `oblique`, `adjust`), one file per stage, and the artifacts they exchange.
//! The algorithms, their versions and their parameters live in `stages/`; this layer only adds typed inputs and
//! encoding.

/// Inside `impl Stage for …`: the node's identity (name and version from the algorithm's `StageId`, so
/// both are defined once, next to the algorithm), its parameters and its output:
/// `stage_types!(skytie_stages::oblique::facades::STAGE, FacadeParams => TripletFacades);`.
macro_rules! stage_types {
    ($id:expr, $params:ty => $output:ty) => {
        const NAME: &'static str = $id.name;
        const VERSION: &'static str = $id.version;
        type Params = $params;
        type Output = $output;
    };
}
pub(crate) use stage_types;

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

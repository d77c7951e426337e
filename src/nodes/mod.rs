//! The engine's wrappers of `skytie-stages` algorithms as typed, cached DAG stages, grouped like the
//! pipelines (`campaign`, `nadir`, `oblique`, `adjust`), one file per stage, and the artifacts they exchange.
//! The algorithms, their versions and their parameters live in `stages/`; this layer only adds typed inputs and
//! encoding.

/// Inside `impl Stage for …`: the node's whole signature in one declaration — its identity (name and version
/// from the algorithm's `StageId`, so both are defined once, next to the algorithm), its parameters, its output
/// and its typed inputs:
/// `stage_types!(skytie_stages::oblique::facades::STAGE, FacadeParams => TripletFacades, inputs: (Handle<A>, Vec<Handle<B>>));`.
/// A node with no algorithm of its own in `skytie-stages` names itself: `stage_types!(named "probe" version "1", …)`.
macro_rules! stage_types {
    (named $name:literal version $version:literal, $params:ty => $output:ty, inputs: $inputs:ty) => {
        $crate::nodes::stage_types!(
            skytie_stages::params::StageId::new($name, $version),
            $params => $output, inputs: $inputs
        );
    };
    ($id:expr, $params:ty => $output:ty, inputs: $inputs:ty) => {
        $crate::stage_items!($id.name, $id.version, $params => $output, inputs: $inputs);
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

//! `transform_agreement`: per (recording × nadir image), the initial transform checked against the recording's
//! transforms to its other nadir images (`skytie_stages::nadir::transform_agreement`). A transform that
//! disagrees becomes a rejection with its reason, counted with the other transform rejections.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage};
use skytie_stages::nadir::initial_transform::TransformParams;
use skytie_stages::nadir::transform_agreement::check_agreement;
use skytie_stages::nadir::TransformOutcome;

/// The agreement node. Inputs: this pair's transform outcome, then all outcomes of the same recording.
pub struct TransformAgreementStage;

impl Stage for TransformAgreementStage {
    crate::nodes::stage_types!(skytie_stages::nadir::transform_agreement::STAGE, TransformParams => TransformOutcome,
        inputs: (Handle<TransformOutcome>, Vec<Handle<TransformOutcome>>));

    fn run(&self, p: &TransformParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (own, all) = inputs;
        let refs: Vec<&TransformOutcome> = all.iter().map(|o| o.as_ref()).collect();
        Ok(check_agreement(&own, &refs, p.max_offset_disagreement_m))
    }
}

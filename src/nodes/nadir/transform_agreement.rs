//! `transform_agreement`: per (recording × nadir image), the initial transform checked against the recording's
//! transforms to its other nadir images (`skytie_stages::nadir::transform_agreement`). A transform that
//! disagrees becomes a rejection with its reason, counted with the other transform rejections.

use crate::dag::{Handle, NodeCtx, Stage, StageError};
use skytie_stages::nadir::initial_transform::TransformParams;
use skytie_stages::nadir::transform_agreement::check_agreement;
use skytie_stages::nadir::TransformOutcome;
use std::sync::Arc;

/// The agreement node. Inputs: this pair's transform outcome, then all outcomes of the same recording.
pub struct TransformAgreementStage;

impl Stage for TransformAgreementStage {
    const NAME: &'static str = skytie_stages::nadir::transform_agreement::STAGE.name;
    const VERSION: &'static str = skytie_stages::nadir::transform_agreement::STAGE.version;
    type Params = TransformParams;
    type Output = TransformOutcome;
    type Inputs = (Handle<TransformOutcome>, Vec<Handle<TransformOutcome>>);

    fn run(
        &self,
        p: &TransformParams,
        (own, all): (Arc<TransformOutcome>, Vec<Arc<TransformOutcome>>),
        _: &NodeCtx,
    ) -> Result<TransformOutcome, StageError> {
        let refs: Vec<&TransformOutcome> = all.iter().map(|o| o.as_ref()).collect();
        Ok(check_agreement(&own, &refs, p.max_offset_disagreement_m))
    }
}

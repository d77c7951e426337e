//! `baseline`: the chapter-2 baseline matcher (thesis 2.2.3: isolated Förstner keypoints in the aerial image +
//! NCC template matching, `skytie_stages::nadir::baseline`) in place of the phase-correlation `refine` node when
//! `[nadir] matcher = "baseline"` — so thesis Table 2-10's comparison can be regenerated as a sweep.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage};
use crate::nodes::campaign::ingest::IngestedImage;
use crate::nodes::nadir::refine::locate_with_accepted;
use skytie_stages::campaign::AerialImage;
use skytie_stages::nadir::baseline::{baseline_matches, BaselineParams};
use skytie_stages::nadir::{AerialRefinement, MmWindowMatch, OrthoImage, TransformOutcome};

/// The baseline matching node (same inputs and output as `refine`).
pub struct BaselineStage;

impl Stage for BaselineStage {
    crate::nodes::stage_types!(skytie_stages::nadir::baseline::STAGE, BaselineParams => AerialRefinement,
        inputs: (Handle<OrthoImage>, Handle<IngestedImage>, Handle<AerialImage>, Handle<TransformOutcome>, Handle<MmWindowMatch>));

    fn run(&self, p: &BaselineParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (ortho, aerial_file, aerial, outcome, window) = inputs;
        locate_with_accepted(&outcome, &window, &aerial, &aerial_file, |t, image| {
            baseline_matches(&ortho, image, &aerial, t, &window, p)
        })
    }
}

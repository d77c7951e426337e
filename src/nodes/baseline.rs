//! `baseline`: the chapter-2 baseline matcher (thesis 2.2.3: isolated Förstner keypoints in the aerial image +
//! NCC template matching, `skytie_stages::nadir::baseline`) in place of the phase-correlation `refine` node when
//! `[nadir] matcher = "baseline"` — so thesis Table 2-10's comparison can be regenerated as a sweep.

use crate::dag::{Handle, NodeCtx, RawFile, RawFileValue, Stage, StageError};
use crate::workflow::{ParamError, StageParams};
use skytie_stages::campaign::AerialImage;
use skytie_stages::imaging::io::load_gray;
use skytie_stages::nadir::baseline::{baseline_matches, BaselineParams};
use skytie_stages::nadir::{AerialRefinement, MmWindowMatch, OrthoImage, TransformOutcome};
use std::sync::Arc;

impl StageParams for BaselineParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        BaselineParams::validate(self).map_err(|errs| {
            errs.into_iter()
                .map(|(f, m)| ParamError::new(f, m))
                .collect()
        })
    }
}

/// The baseline matching node (same inputs and output as `refine`).
pub struct BaselineStage;

impl Stage for BaselineStage {
    const NAME: &'static str = "baseline";
    const VERSION: &'static str = "1";
    type Params = BaselineParams;
    type Output = AerialRefinement;
    type Inputs = (
        Handle<OrthoImage>,
        RawFile,
        Handle<AerialImage>,
        Handle<TransformOutcome>,
        Handle<MmWindowMatch>,
    );

    fn run(
        &self,
        p: &BaselineParams,
        (ortho, aerial_file, aerial, outcome, window): (
            Arc<OrthoImage>,
            RawFileValue,
            Arc<AerialImage>,
            Arc<TransformOutcome>,
            Arc<MmWindowMatch>,
        ),
        _: &NodeCtx,
    ) -> Result<AerialRefinement, StageError> {
        let TransformOutcome::Accepted(t) = outcome.as_ref() else {
            return Ok(AerialRefinement {
                recording_id: window.recording_id.clone(),
                aerial_id: aerial.image_id.clone(),
                tried: 0,
                matches: Vec::new(),
            });
        };
        let image = load_gray(&aerial_file.path).map_err(|e| StageError::new(e.to_string()))?;
        Ok(baseline_matches(&ortho, &image, &aerial, t, &window, p))
    }
}

//! `refine`: per (recording × nadir image) with an accepted initial transform, every MM tie point of the
//! recording's window located in the aerial image by phase correlation (thesis 3.4.5.3,
//! `skytie_stages::nadir::refine`), each template first compared with the window's neighbouring recordings'
//! views (their orthos for the same aerial image, `skytie_stages::nadir::parallax_check`). A rejected transform
//! gives an empty refinement.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage, StageError};
use crate::nodes::campaign::image_tiles::{self, CachedPyramid};
use crate::nodes::campaign::ingest::IngestedImage;
use skytie_stages::campaign::AerialImage;
use skytie_stages::imaging::pyramid::PyramidError;
use skytie_stages::nadir::refine::{refine_in_aerial, NeighbourOrtho, RefineParams};
use skytie_stages::nadir::{
    AerialRefinement, InitialTransform, MmWindowMatch, OrthoImage, TransformOutcome,
};

crate::serde_artifact!(AerialRefinement);

/// The phase-correlation refinement node.
pub struct RefineStage;

impl Stage for RefineStage {
    crate::nodes::stage_types!(skytie_stages::nadir::refine::STAGE, RefineParams => AerialRefinement,
        inputs: (Handle<OrthoImage>, Handle<IngestedImage>, Handle<AerialImage>, Handle<TransformOutcome>, Handle<MmWindowMatch>, Vec<Handle<OrthoImage>>));

    fn run(&self, p: &RefineParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (ortho, aerial_file, aerial, outcome, window, neighbour_orthos) = inputs;
        let neighbours = NeighbourOrtho::of_window(&window, &neighbour_orthos);
        locate_with_accepted(&outcome, &window, &aerial, &aerial_file, |t, image| {
            refine_in_aerial(&ortho, image, &aerial, t, &window, &neighbours, p)
        })
    }
}

/// Shared by `refine` and `baseline`: an empty refinement when the transform was rejected, else `locate` on
/// the ingested aerial image.
pub fn locate_with_accepted(
    outcome: &TransformOutcome,
    window: &MmWindowMatch,
    aerial: &AerialImage,
    aerial_image: &IngestedImage,
    locate: impl FnOnce(&InitialTransform, &CachedPyramid) -> Result<AerialRefinement, PyramidError>,
) -> Result<AerialRefinement, StageError> {
    let TransformOutcome::Accepted(t) = outcome else {
        return Ok(AerialRefinement::empty(
            &window.recording_id,
            &aerial.image_id,
        ));
    };
    let pyramid = image_tiles::open(aerial_image)?;
    locate(t, &pyramid).map_err(|e| StageError::new(e.to_string()))
}

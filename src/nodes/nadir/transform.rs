//! `transform`: per (recording × nadir image), the initial KAZE similarity between the recording's aerial-
//! oriented ortho image and the aerial image (thesis 3.4.5.2, `skytie_stages::nadir::initial_transform`).
//! A rejected transform is a normal output (with its reason), not a failure.

use crate::dag::{Handle, NodeCtx, Stage, StageError};
use crate::nodes::campaign::image_tiles;
use crate::nodes::campaign::ingest::IngestedImage;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::nadir::initial_transform::{initial_transform, TransformParams};
use skytie_stages::nadir::{OrthoImage, TransformOutcome};
use std::sync::Arc;

crate::serde_artifact!(TransformOutcome);

/// The initial-transform node.
pub struct InitialTransformStage;

impl Stage for InitialTransformStage {
    const NAME: &'static str = skytie_stages::nadir::initial_transform::STAGE.name;
    const VERSION: &'static str = skytie_stages::nadir::initial_transform::STAGE.version;
    type Params = TransformParams;
    type Output = TransformOutcome;
    type Inputs = (
        Handle<Recording>,
        Handle<OrthoImage>,
        Handle<IngestedImage>,
        Handle<AerialImage>,
    );

    fn run(
        &self,
        p: &TransformParams,
        (rec, ortho, aerial_file, aerial): (
            Arc<Recording>,
            Arc<OrthoImage>,
            Arc<IngestedImage>,
            Arc<AerialImage>,
        ),
        _: &NodeCtx,
    ) -> Result<TransformOutcome, StageError> {
        let pyramid = image_tiles::open(&aerial_file)?;
        initial_transform(&rec, &ortho, &pyramid, &aerial, p)
            .map_err(|e| StageError::new(e.to_string()))
    }
}

//! `transform`: per (recording × nadir image), the initial KAZE similarity between the recording's aerial-
//! oriented ortho image and the aerial image (thesis 3.4.5.2, `skytie_stages::nadir::initial_transform`).
//! A rejected transform is a normal output (with its reason), not a failure.

use crate::dag::{Handle, NodeCtx, RawFile, RawFileValue, Stage, StageError};
use crate::nodes::campaign::decoded_images;
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
        RawFile,
        Handle<AerialImage>,
    );

    fn run(
        &self,
        p: &TransformParams,
        (rec, ortho, aerial_file, aerial): (
            Arc<Recording>,
            Arc<OrthoImage>,
            RawFileValue,
            Arc<AerialImage>,
        ),
        _: &NodeCtx,
    ) -> Result<TransformOutcome, StageError> {
        let image = decoded_images::gray(&aerial_file)?;
        Ok(initial_transform(&rec, &ortho, &image, &aerial, p))
    }
}

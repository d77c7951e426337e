//! `transform`: per (recording × nadir image), the initial KAZE similarity between the recording's aerial-
//! oriented ortho image and the aerial image (thesis 3.4.5.2, `skytie_stages::nadir::initial_transform`).
//! A rejected transform is a normal output (with its reason), not a failure.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage, StageError};
use crate::nodes::campaign::image_tiles;
use crate::nodes::campaign::ingest::IngestedImage;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::nadir::initial_transform::{initial_transform, TransformParams};
use skytie_stages::nadir::{OrthoImage, TransformOutcome};

crate::serde_artifact!(TransformOutcome);

/// The initial-transform node.
pub struct InitialTransformStage;

impl Stage for InitialTransformStage {
    crate::nodes::stage_types!(skytie_stages::nadir::initial_transform::STAGE, TransformParams => TransformOutcome,
        inputs: (Handle<Recording>, Handle<OrthoImage>, Handle<IngestedImage>, Handle<AerialImage>));

    fn run(&self, p: &TransformParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (rec, ortho, aerial_file, aerial) = inputs;
        let pyramid = image_tiles::open(&aerial_file)?;
        initial_transform(&rec, &ortho, &pyramid, &aerial, p)
            .map_err(|e| StageError::new(e.to_string()))
    }
}

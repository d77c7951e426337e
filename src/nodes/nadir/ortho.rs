//! `ortho`: per recording, the panorama ortho-projected onto the ground plane — thesis 3.4.3
//! (`skytie_stages::nadir::ortho_project`). Inputs: the recording's row and its panorama file (hashed by content).

use crate::dag::{Handle, NodeCtx, RawFile, RawFileValue, Stage, StageError};
use skytie_stages::campaign::Recording;
use skytie_stages::nadir::{ortho_project, OrthoImage, OrthoParams};
use std::sync::Arc;

crate::serde_artifact!(OrthoImage);

/// The ortho-projection node.
pub struct OrthoProject;

impl Stage for OrthoProject {
    const NAME: &'static str = skytie_stages::nadir::ortho::STAGE.name;
    const VERSION: &'static str = skytie_stages::nadir::ortho::STAGE.version;
    type Params = OrthoParams;
    type Output = OrthoImage;
    type Inputs = (Handle<Recording>, RawFile);

    fn run(
        &self,
        p: &OrthoParams,
        (rec, pano): (Arc<Recording>, RawFileValue),
        _: &NodeCtx,
    ) -> Result<OrthoImage, StageError> {
        // Shared with the recording's other ortho nodes (one decode per panorama while it stays in memory).
        let image = crate::nodes::campaign::decoded_images::gray(&pano)?;
        if image.width != 2 * image.height {
            return Err(StageError::new(format!(
                "{}: panorama is {}×{} px; an equirectangular panorama must be twice as wide as high",
                pano.path.display(),
                image.width,
                image.height
            )));
        }
        Ok(ortho_project(&image, &rec, p))
    }
}

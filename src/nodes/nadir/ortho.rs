//! `ortho`: per recording, the panorama ortho-projected onto the ground plane — thesis 3.4.3
//! (`skytie_stages::nadir::ortho_project`). Inputs: the recording's row and its ingested panorama, of which only
//! the bands of rows and pyramid levels the projection samples are read.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage, StageError};
use crate::nodes::campaign::image_tiles;
use crate::nodes::campaign::ingest::IngestedImage;
use skytie_stages::campaign::Recording;
use skytie_stages::imaging::equirect::PanoramaLevels;
use skytie_stages::imaging::pyramid::TileSource;
use skytie_stages::nadir::ortho::panorama_bands;
use skytie_stages::nadir::{ortho_project, OrthoImage, OrthoParams};

crate::serde_artifact!(OrthoImage);

/// The panorama of `rec` ortho-projected with `params` derived from another image (`subject` names it in the
/// error, e.g. "aerial image 'n_01'"): the derived parameters are checked first, since a bad source image
/// (absurd GSD, size) yields parameters the projection cannot use.
pub fn ortho_with_derived_params(
    subject: &str,
    params: &OrthoParams,
    pano: &IngestedImage,
    rec: &Recording,
) -> Result<OrthoImage, StageError> {
    if let Err(errs) = skytie_stages::params::Params::validate(params) {
        return Err(StageError::new(format!(
            "{subject}: the ortho parameters derived from it are invalid ({})",
            errs.iter()
                .map(|v| format!("{}: {}", v.field, v.message))
                .collect::<Vec<_>>()
                .join("; ")
        )));
    }
    let panorama = panorama_for_ortho(pano, rec, params)?;
    Ok(ortho_project(&panorama, rec, params))
}

/// The bands of `pano` that the ortho-projection of `rec` with `p` samples; an error when the panorama is not
/// equirectangular (W = 2H).
pub fn panorama_for_ortho(
    pano: &IngestedImage,
    rec: &Recording,
    p: &OrthoParams,
) -> Result<PanoramaLevels, StageError> {
    if pano.width != 2 * pano.height {
        return Err(StageError::new(format!(
            "{}: panorama is {}×{} px; an equirectangular panorama must be twice as wide as high",
            pano.source, pano.width, pano.height
        )));
    }
    let pyramid = image_tiles::open(pano)?;
    let size = (pano.width as usize, pano.height as usize);
    let bands = panorama_bands(rec, p, size, pyramid.layout().levels() - 1);
    PanoramaLevels::read_bands(&pyramid, &bands).map_err(|e| StageError::new(e.to_string()))
}

/// The ortho-projection node.
pub struct OrthoProject;

impl Stage for OrthoProject {
    crate::nodes::stage_types!(skytie_stages::nadir::ortho::STAGE, OrthoParams => OrthoImage,
        inputs: (Handle<Recording>, Handle<IngestedImage>));

    fn run(&self, p: &OrthoParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (rec, pano) = inputs;
        let panorama = panorama_for_ortho(&pano, &rec, p)?;
        Ok(ortho_project(&panorama, &rec, p))
    }
}

//! `orthophoto_ortho`: per (recording × orthophoto tile), the panorama ortho-projected north-up at the pixel size
//! of the orthophoto's working level (`skytie_stages::orthophoto::ortho_params_for_orthophoto`: the level not
//! finer than `registration_gsd_m`, and never finer than the orthophoto's detail level, so an orthophoto
//! enlarged by pixel repetition gets the ortho of the orthophoto it was enlarged from). The ingested orthophoto
//! is an input for its size and detail level only.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage};
use crate::nodes::campaign::ingest::IngestedImage;
use crate::nodes::nadir::ortho::ortho_with_derived_params;
use crate::workflow::{ParamError, StageParams};
use serde::{Deserialize, Serialize};
use skytie_stages::campaign::Recording;
use skytie_stages::nadir::{OrthoImage, OrthoParams};
use skytie_stages::orthophoto::ortho_params_for_orthophoto;
use skytie_stages::params::StageId;

/// The node's identity in cache keys.
pub const STAGE: StageId = StageId::new("orthophoto_ortho", "1");

/// Parameters: the workflow's `[ortho]` table (diagonal, vehicle mask, `registration_gsd_m`; `gsd_m` and
/// `rotation_deg` are replaced) and the orthophoto tile's pixel size.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OrthophotoOrthoParams {
    pub base: OrthoParams,
    /// The orthophoto's full-resolution pixel size (its geotransform), m.
    pub pixel_m: f64,
}

impl StageParams for OrthophotoOrthoParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        StageParams::validate(&self.base)
    }
}

/// The north-up ortho-projection for the orthophoto route. Inputs: the recording, its panorama and the
/// ingested orthophoto tile.
pub struct OrthoForOrthophoto;

impl Stage for OrthoForOrthophoto {
    crate::nodes::stage_types!(STAGE, OrthophotoOrthoParams => OrthoImage,
        inputs: (Handle<Recording>, Handle<IngestedImage>, Handle<IngestedImage>));

    fn run(
        &self,
        p: &OrthophotoOrthoParams,
        inputs: InputsOf<Self>,
        _: &NodeCtx,
    ) -> RunResult<Self> {
        let (rec, pano, photo) = inputs;
        let size_px = (
            u32::try_from(photo.width).unwrap_or(u32::MAX),
            u32::try_from(photo.height).unwrap_or(u32::MAX),
        );
        let params =
            ortho_params_for_orthophoto(&p.base, p.pixel_m, size_px, photo.detail_level as usize);
        let subject = format!("orthophoto '{}'", photo.source);
        ortho_with_derived_params(&subject, &params, &pano, &rec)
    }
}

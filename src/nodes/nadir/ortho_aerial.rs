//! `ortho_aerial`: per (recording × nadir image), the panorama ortho-projected at the aerial image's ground
//! sampling distance and rotated to its orientation (thesis 3.4.3 and 3.4.5.2: "the MM are ortho-projected again
//! for this step, but with a resolution of 10 cm"), so that MM and aerial patches differ by about a translation.
//! The aerial frame's ingested pyramid is an input for its detail level only: a frame enlarged by pixel
//! repetition gets the ortho of the frame it was enlarged from.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage};
use crate::nodes::campaign::ingest::IngestedImage;
use crate::nodes::nadir::ortho::ortho_with_derived_params;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::geometry::FrameCamera;
use skytie_stages::nadir::aerial_overlap::foot_point_world;
use skytie_stages::nadir::aerial_patch::ortho_params_for_aerial_image;
use skytie_stages::nadir::{OrthoImage, OrthoParams};

/// The aerial-oriented ortho-projection node. Its params are the workflow's `[ortho]` table (diagonal,
/// vehicle mask, `registration_gsd_m`); `gsd_m` and `rotation_deg` are replaced by the aerial image's (at its
/// working level, `skytie_stages::nadir::aerial_patch::working_level`, never finer than the frame's detail
/// level). Inputs: the recording, its panorama, the aerial image's row and its ingested frame.
pub struct OrthoForAerial;

impl Stage for OrthoForAerial {
    crate::nodes::stage_types!(skytie_stages::nadir::aerial_patch::STAGE, OrthoParams => OrthoImage,
        inputs: (Handle<Recording>, Handle<IngestedImage>, Handle<AerialImage>, Handle<IngestedImage>));

    fn run(&self, base: &OrthoParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (rec, pano, aerial, aerial_file) = inputs;
        let cam = FrameCamera::from_aerial(&aerial);
        let params = ortho_params_for_aerial_image(
            &cam,
            foot_point_world(&rec),
            base,
            aerial_file.detail_level as usize,
        );
        let subject = format!("aerial image '{}'", aerial.image_id);
        ortho_with_derived_params(&subject, &params, &pano, &rec)
    }
}

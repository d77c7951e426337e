//! `mm_match`: per recording, MM-to-MM matching of its 3 cm ortho image with the next one or two recordings
//! along the trajectory (thesis 3.4.4, `skytie_stages::nadir::mm_matching`). Inputs: the window's recording rows,
//! ortho images and panorama files (the panoramas only for their pixel size; they are hashed by content).

use crate::dag::{Handle, InputsOf, NodeCtx, RawFile, RunResult, Stage, StageError};
use skytie_stages::campaign::Recording;
use skytie_stages::imaging::io::dimensions;
use skytie_stages::nadir::mm_matching::{match_window, MmMatchParams, OrthoView};
use skytie_stages::nadir::{MmWindowMatch, OrthoImage};

crate::serde_artifact!(MmWindowMatch);

/// The MM-to-MM matching node; the first recording of the window is the detecting one.
pub struct MmMatch;

impl Stage for MmMatch {
    crate::nodes::stage_types!(skytie_stages::nadir::mm_matching::STAGE, MmMatchParams => MmWindowMatch,
        inputs: (Vec<Handle<Recording>>, Vec<Handle<OrthoImage>>, Vec<RawFile>));

    fn run(&self, p: &MmMatchParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (recs, orthos, panos) = inputs;
        if recs.is_empty() || recs.len() != orthos.len() || recs.len() != panos.len() {
            return Err(StageError::new(
                "internal: mm_match needs one recording, ortho image and panorama per window member",
            ));
        }
        let mut views = Vec::with_capacity(recs.len());
        for ((rec, ortho), pano) in recs.iter().zip(&orthos).zip(&panos) {
            let (w, h) = dimensions(&pano.path).map_err(|e| StageError::new(e.to_string()))?;
            views.push(OrthoView {
                recording: rec,
                ortho,
                pano_width_px: w,
                pano_height_px: h,
            });
        }
        Ok(match_window(&views[0], &views[1..], p))
    }
}

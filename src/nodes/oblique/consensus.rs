//! `oblique`: one global node per variant — the 3-D median consensus of every (panorama × oblique image)
//! registration set, optional consensus tracking, and the oblique control points (thesis 4.4.7,
//! `skytie_stages::oblique::consensus`), with the pipeline's own counts (`oblique.*` metrics that need no truth).

use crate::dag::StageError;
use crate::dag::{Handle, InputsOf, NodeCtx, Optional, RawFile, RunResult, Stage};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::map_frame::campaign_frame_spec;
use crate::nodes::campaign::panorama_sizes::pano_sizes;
use serde::{Deserialize, Serialize};
use skytie_stages::crs::MapFrame;
use skytie_stages::oblique::consensus::{consensus_with_diagnostics, ConsensusParams};
use skytie_stages::oblique::summary::ObliqueSummary;
use skytie_stages::oblique::{ObliqueResult, PatchRegistrationSet, SparseCloud, TripletFacades};

/// The consensus node's output: the correspondences and control points, and the pipeline's counts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObliqueOutput {
    pub result: ObliqueResult,
    pub summary: ObliqueSummary,
}
crate::serde_artifact!(ObliqueOutput);

/// The consensus node. Inputs: snapshot, panorama files (snapshot order), every triplet's sparse cloud and
/// façades, every registration set.
pub struct ConsensusStage;

impl Stage for ConsensusStage {
    crate::nodes::stage_types!(skytie_stages::oblique::consensus::STAGE, ConsensusParams => ObliqueOutput,
        inputs: (Handle<CampaignSnapshot>, Vec<RawFile>, Vec<Optional<SparseCloud>>, Vec<Optional<TripletFacades>>, Vec<Optional<PatchRegistrationSet>>));

    fn run(&self, p: &ConsensusParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (snap, panos, clouds, facades, sets) = inputs;
        let c = &snap.campaign;
        let sizes = pano_sizes(&panos)?;
        let clouds: Vec<SparseCloud> = clouds.iter().flatten().map(|x| (**x).clone()).collect();
        let facades: Vec<TripletFacades> =
            facades.iter().flatten().map(|x| (**x).clone()).collect();
        let sets: Vec<PatchRegistrationSet> =
            sets.iter().flatten().map(|x| (**x).clone()).collect();
        let frame = MapFrame::from_spec(&campaign_frame_spec(c).0)
            .map_err(|e| StageError::new(format!("the campaign's frame: {e}")))?;
        let result = consensus_with_diagnostics(
            &sets,
            &clouds,
            &c.recordings,
            &c.oblique,
            &sizes,
            p,
            &frame,
        )
        .0;
        let summary = ObliqueSummary::from_parts(&clouds, &facades, &sets, &result);
        Ok(ObliqueOutput { result, summary })
    }
}

//! `nadir`: the global summary of the nadir pipeline — counts of MM pairs, tie points, transforms,
//! correspondences and control points (`skytie_stages::nadir::summary`), contributed to metrics as `nadir`.

use crate::dag::{Handle, InputsOf, NodeCtx, Optional, RunResult, Stage};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::summary::SummaryParams;
use skytie_stages::nadir::summary::NadirSummary;
use skytie_stages::nadir::{AerialRefinement, MmWindowMatch, RecordingControl, TransformOutcome};

crate::serde_artifact!(NadirSummary);

/// The nadir summary node (no tunable parameters).
pub struct SummarizeNadir;

impl Stage for SummarizeNadir {
    crate::nodes::stage_types!(skytie_stages::nadir::summary::STAGE, SummaryParams => NadirSummary,
        inputs: (Handle<CampaignSnapshot>, Vec<Optional<MmWindowMatch>>, Vec<Optional<TransformOutcome>>, Vec<Optional<AerialRefinement>>, Vec<Optional<RecordingControl>>));

    fn run(&self, _: &SummaryParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (snap, windows, transforms, refinements, control) = inputs;
        let w: Vec<&MmWindowMatch> = windows.iter().flatten().map(|x| x.as_ref()).collect();
        let t: Vec<&TransformOutcome> = transforms.iter().flatten().map(|x| x.as_ref()).collect();
        let r: Vec<&AerialRefinement> = refinements.iter().flatten().map(|x| x.as_ref()).collect();
        let c: Vec<&RecordingControl> = control.iter().flatten().map(|x| x.as_ref()).collect();
        Ok(NadirSummary::from_parts(
            snap.campaign.recordings.len(),
            &w,
            &t,
            &r,
            &c,
        ))
    }
}

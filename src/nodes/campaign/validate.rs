//! `probe` and `validate`: the image part of the campaign validation `skytie check` applies, as cached nodes.
//! One `probe` node per image file reads its header and structure (keyed by the file's content, so an edited
//! or replaced image is probed again and an unchanged one never); the global `validate` node applies the
//! outcomes to the loaded snapshot (`campaign::apply_image_checks`): a row whose image is truncated, of
//! the wrong size or no image at all is removed with a problem naming file, row and field, before any
//! per-item node is built for it, so one bad image never fails a node of the run.

use crate::dag::{Handle, InputsOf, NodeCtx, RunResult, Stage, StageError};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::summary::SummaryParams;
use serde::{Deserialize, Serialize};
use skytie_stages::campaign::{apply_image_checks, image_jobs, sort_problems, ProbeOutcome};
use skytie_stages::imaging::probe::probe;

/// The outcome of probing one image file (an unusable image is a value, not a failed node).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageProbe {
    pub outcome: ProbeOutcome,
}
crate::serde_artifact!(ImageProbe);

/// Probes one image file.
pub struct ProbeImage;

impl Stage for ProbeImage {
    crate::nodes::stage_types!(named "probe" version "1", SummaryParams => ImageProbe,
        inputs: crate::dag::RawFile);

    fn run(&self, _: &SummaryParams, file: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        Ok(ImageProbe {
            outcome: probe(&file.path),
        })
    }
}

/// Applies the probes (in `image_jobs` order) to the loaded snapshot.
pub struct ValidateImages;

impl Stage for ValidateImages {
    crate::nodes::stage_types!(named "validate" version "1", SummaryParams => CampaignSnapshot,
        inputs: (Handle<CampaignSnapshot>, Vec<Handle<ImageProbe>>));

    fn run(&self, _: &SummaryParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (snap, probes) = inputs;
        let sourced = snap.sourced();
        let jobs = image_jobs(&sourced);
        if jobs.len() != probes.len() {
            return Err(StageError::new(format!(
                "internal error: {} images to validate but {} probes (please report)",
                jobs.len(),
                probes.len()
            )));
        }
        let outcomes: Vec<ProbeOutcome> = probes.iter().map(|p| p.outcome.clone()).collect();
        let mut problems = snap.problems.clone();
        let sourced = apply_image_checks(sourced, &jobs, &outcomes, &mut problems);
        sort_problems(&mut problems);
        Ok(CampaignSnapshot::new(sourced, problems))
    }
}

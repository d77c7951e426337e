//! What the chains of one sweep variant are built from: the per-recording handles every chain starts from
//! (`RecordingItem`), and the workflow, variant and campaign they share (`VariantContext`), with the two
//! questions every chain asks of them — is a stage enabled, and what are its parameters for this variant.

use super::wf_err;
use crate::dag::{Handle, PipelineError, RawFile};
use crate::nodes::campaign::ingest::IngestedImage;
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::nadir::grade::TRUTH_RECORDINGS;
use crate::workflow::{StageParams, Workflow};
use skytie_stages::campaign::Recording;
use skytie_stages::nadir::OrthoImage;
use std::path::Path;

/// One recording's per-item handles, built by the main pipeline.
pub struct RecordingItem<'a> {
    pub recording: &'a Recording,
    pub row: Handle<Recording>,
    /// The 3 cm ortho image (thesis 3.4.3); `None` when the workflow does not enable `ortho`.
    pub ortho: Option<Handle<OrthoImage>>,
    /// The panorama file (stages that only read its header or hash).
    pub pano: RawFile,
    /// The panorama ingested into its pyramid (stages that read its pixels).
    pub pano_image: Handle<IngestedImage>,
}

/// The workflow and variant a chain is added for, the campaign folder with its validated snapshot (the value
/// and its node) and the recordings' handles in trajectory (time) order.
#[derive(Clone, Copy)]
pub struct VariantContext<'a> {
    pub wf: &'a Workflow,
    pub variant: &'a str,
    pub root: &'a Path,
    pub snapshot: &'a CampaignSnapshot,
    pub snap: Handle<CampaignSnapshot>,
    pub items: &'a [RecordingItem<'a>],
}

impl VariantContext<'_> {
    /// Whether the workflow enables `stage`.
    pub fn on(&self, stage: &str) -> bool {
        self.wf.enables(stage)
    }

    /// The truth files of the evaluation node `grade_stage`, when it is enabled and the campaign has
    /// `truth/recordings.csv`: that file, then each file of `optional` (relative to the campaign) that exists.
    pub fn truth_files(&self, grade_stage: &str, optional: &[&str]) -> Option<Vec<RawFile>> {
        let truth = self.root.join(TRUTH_RECORDINGS);
        if !(self.on(grade_stage) && truth.is_file()) {
            return None;
        }
        let present = optional
            .iter()
            .map(|f| self.root.join(f))
            .filter(|p| p.is_file());
        Some(std::iter::once(truth).chain(present).map(RawFile).collect())
    }

    /// The parameters of `stage` for this variant (a workflow error when they do not parse).
    pub fn params<T: StageParams>(&self, stage: &str) -> Result<T, PipelineError> {
        self.wf.params(stage, self.variant).map_err(wf_err)
    }
}

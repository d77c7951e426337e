//! `summary`: a global node over the campaign snapshot and the per-recording ortho images: counts, input
//! problems and ortho coverage, contributed to `metrics.json` under `campaign` and `ortho`.

use crate::dag::{Handle, InputsOf, NodeCtx, Optional, RunResult, Stage};
use crate::nodes::campaign::load::CampaignSnapshot;
use serde::{Deserialize, Serialize};
use skytie_stages::campaign::{InputAccount, Severity};
use skytie_stages::nadir::OrthoImage;
use skytie_stages::params::StageId;
use std::sync::Arc;

skytie_stages::params! {
    /// The summary has no tunable parameters.
    pub struct SummaryParams {}
}

/// What the campaign holds and how much of it the per-recording stages covered.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CampaignSummary {
    pub name: String,
    pub recordings: usize,
    pub nadir_images: usize,
    pub oblique_images: usize,
    pub checkpoints: usize,
    pub observations: usize,
    pub input_errors: usize,
    pub input_warnings: usize,
    /// Errors per kind and rows dropped per file.
    pub input: InputAccount,
    /// Every input problem, rendered (`file:row: field …`).
    pub problems: Vec<String>,
    /// Recordings whose ortho image was produced.
    pub ortho_images: usize,
    /// Mean fraction of ortho pixels that hold ground (not masked by the vehicle).
    pub ortho_valid_fraction_mean: f64,
}
crate::serde_artifact!(CampaignSummary);

impl CampaignSummary {
    /// The `campaign` and `ortho` metrics sections.
    pub fn metrics(&self) -> (serde_json::Value, serde_json::Value) {
        (
            serde_json::json!({
                "name": self.name,
                "recordings": self.recordings,
                "nadir_images": self.nadir_images,
                "oblique_images": self.oblique_images,
                "checkpoints": self.checkpoints,
                "observations": self.observations,
                "input_errors": self.input_errors,
                "input_warnings": self.input_warnings,
                "input_errors_by_kind": self.input.errors_by_kind,
                "dropped_rows": self.input.dropped_rows,
                "rows_dropped": self.input.rows_dropped(),
                "files_with_errors": self.input.files_with_errors,
            }),
            serde_json::json!({
                "images": self.ortho_images,
                "valid_fraction_mean": self.ortho_valid_fraction_mean,
            }),
        )
    }
}

/// The stage's identity in cache keys (the computation lives in this node); bump the version whenever its
/// output for the same inputs and parameters changes.
pub const STAGE: StageId = StageId::new("summary", "2");

/// The summary node.
pub struct SummarizeCampaign;

impl Stage for SummarizeCampaign {
    crate::nodes::stage_types!(STAGE, SummaryParams => CampaignSummary,
        inputs: (Handle<CampaignSnapshot>, Vec<Optional<OrthoImage>>));

    fn run(&self, _: &SummaryParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (snap, orthos) = inputs;
        let orthos: Vec<Arc<OrthoImage>> = orthos.into_iter().flatten().collect();
        let c = &snap.campaign;
        let valid_fraction = |o: &OrthoImage| {
            let n = o.valid.len().max(1);
            o.valid.iter().filter(|&&v| v != 0).count() as f64 / n as f64
        };
        let mean = if orthos.is_empty() {
            0.0
        } else {
            orthos.iter().map(|o| valid_fraction(o)).sum::<f64>() / orthos.len() as f64
        };
        Ok(CampaignSummary {
            name: c.name.clone(),
            recordings: c.recordings.len(),
            nadir_images: c.nadir.len(),
            oblique_images: c.oblique.len(),
            checkpoints: c.checkpoints.len(),
            observations: c.observations.len(),
            input_errors: snap
                .problems
                .iter()
                .filter(|p| p.severity == Severity::Error)
                .count(),
            input_warnings: snap
                .problems
                .iter()
                .filter(|p| p.severity == Severity::Warning)
                .count(),
            input: InputAccount::of(&snap.problems),
            problems: snap.problems.iter().map(|p| p.to_string()).collect(),
            ortho_images: orthos.len(),
            ortho_valid_fraction_mean: mean,
        })
    }
}

//! `campaign`: read and validate a campaign folder (campaign-format.md) into a snapshot, and `recording`: pick
//! one recording's row out of it — the per-item entry point of the pipeline.
//!
//! Keys: the load node hashes the campaign's CSV/TOML files by content (raw-file inputs) plus the listing of all
//! file names (a parameter), so adding an image or editing a row re-reads the campaign. Every per-recording
//! node then re-selects its row; rows that did not change produce identical output, so by early cutoff only the
//! new or edited recordings' downstream nodes run again.

use crate::dag::{Handle, InputsOf, NodeCtx, RawFile, RunResult, Stage, StageError};
use crate::nodes::campaign::row_index::RowIndex;
use serde::{Deserialize, Serialize};
use skytie_stages::campaign::{
    read_sourced, AerialImage, AerialKind, Campaign, Problem, Recording, SourceRows,
    SourcedCampaign,
};
use skytie_stages::params::StageId;
use std::path::Path;

/// The campaign's metadata files, in a fixed order (only those that exist are inputs).
pub const METADATA_FILES: [&str; 6] = [
    "campaign.toml",
    "mm/recordings.csv",
    "aerial/nadir/cameras.csv",
    "aerial/oblique/cameras.csv",
    "control/checkpoints.csv",
    "control/observations.csv",
];

skytie_stages::params! {
    /// Parameters of the load node (set by the pipeline, not by users).
    pub struct LoadCampaignParams {
        /// The campaign folder (absolute).
        root: String = String::new();
        /// blake3 of the sorted list of every file name below the folder (so file presence is part of the key).
        listing_hash: String = String::new();
    }
}

/// A validated campaign and the problems found while reading it (bad rows were skipped, never guessed).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CampaignSnapshot {
    pub campaign: Campaign,
    /// The row each item came from (parallel to the campaign's vectors).
    pub rows: SourceRows,
    pub problems: Vec<Problem>,
    /// Rows by `image_id`, built on first use (not part of the artifact's bytes).
    #[serde(skip)]
    pub index: RowIndex,
}

impl CampaignSnapshot {
    pub fn new(sourced: SourcedCampaign, problems: Vec<Problem>) -> Self {
        CampaignSnapshot {
            campaign: sourced.campaign,
            rows: sourced.rows,
            problems,
            index: RowIndex::default(),
        }
    }

    /// The recording `image_id`, found through the index (constant time per look-up).
    pub fn recording(&self, image_id: &str) -> Option<&Recording> {
        let i = self.index.recording(&self.campaign, image_id)?;
        self.campaign.recordings.get(i)
    }

    /// The aerial image `image_id` among the rows of `kind`.
    pub fn aerial(&self, kind: AerialKind, image_id: &str) -> Option<&AerialImage> {
        let i = self.index.aerial(&self.campaign, kind, image_id)?;
        match kind {
            AerialKind::Nadir => self.campaign.nadir.get(i),
            AerialKind::Oblique => self.campaign.oblique.get(i),
        }
    }

    /// The campaign with its rows (a copy).
    pub fn sourced(&self) -> SourcedCampaign {
        SourcedCampaign {
            campaign: self.campaign.clone(),
            rows: self.rows.clone(),
        }
    }
}
crate::serde_artifact!(CampaignSnapshot, Recording);

/// The raw-file inputs of the load node for the campaign in `root`.
pub fn metadata_inputs(root: &Path) -> Vec<RawFile> {
    METADATA_FILES
        .iter()
        .map(|f| root.join(f))
        .filter(|p| p.is_file())
        .map(RawFile)
        .collect()
}

/// blake3 (hex) of the sorted relative names of every file below `root` (not their contents).
pub fn listing_hash(root: &Path) -> std::io::Result<String> {
    let files = crate::nodes::campaign::synth::list_files(root)?;
    let mut h = blake3::Hasher::new();
    for (name, _) in &files {
        h.update(name.as_bytes());
        h.update(&[0]);
    }
    Ok(h.finalize().to_hex().to_string())
}

/// Reads the campaign and validates its rows (the images are validated by `nodes::validate`).
pub struct LoadCampaign;

impl Stage for LoadCampaign {
    crate::nodes::stage_types!(skytie_stages::campaign::read::STAGE, LoadCampaignParams => CampaignSnapshot,
        inputs: Vec<RawFile>);

    fn run(&self, p: &LoadCampaignParams, _files: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (sourced, problems) = read_sourced(Path::new(&p.root))
            .map_err(|e| StageError::new(format!("cannot read the campaign: {e}")))?;
        Ok(CampaignSnapshot::new(sourced, problems))
    }
}

skytie_stages::params! {
    /// Parameters of the per-recording selector (set by the pipeline).
    pub struct SelectRecordingParams {
        /// The recording's `image_id`.
        image_id: String = String::new();
    }
}

/// The stage's identity in cache keys (the computation lives in this node); bump the version whenever its
/// output for the same inputs and parameters changes.
pub const RECORDING_STAGE: StageId = StageId::new("recording", "1");

/// One recording's row of the snapshot.
pub struct SelectRecording;

impl Stage for SelectRecording {
    crate::nodes::stage_types!(RECORDING_STAGE, SelectRecordingParams => Recording,
        inputs: Handle<CampaignSnapshot>);

    fn run(&self, p: &SelectRecordingParams, snap: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        snap.recording(&p.image_id).cloned().ok_or_else(|| {
            StageError::new(format!(
                "recording '{}' is not in the campaign any more",
                p.image_id
            ))
        })
    }
}

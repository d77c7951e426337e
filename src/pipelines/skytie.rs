//! The `skytie` pipeline: the thesis' processing chain as cached DAG phases.
//!
//! Phases (each built from the values of the previous one — staged planning):
//! 1. `campaign`: the synthetic generator node when the workflow says `campaign = "synth:<preset>"`;
//! 2. `load`: read and validate the campaign (its images probed by content); then `vehicle`: the recording vehicle found in a sample of the
//!    panoramas (`pipelines::vehicle`), which masks every ortho image;
//! 3. `items`, per sweep variant: per recording `recording` → `ortho` (thesis 3.4.3), the nadir chain
//!    (`pipelines::nadir`, thesis chapter 3), the oblique chain (`pipelines::oblique`, chapter 4), the
//!    adjustment, grading and verification (`pipelines::adjust`, chapter 5), then the global `summary`.
//!
//! After phase 3 the exports of every variant are written into `OUT` (`OUT/variants/<name>/` in a sweep).
//! A stage name the pipeline does not know is refused with the list of available ones.

use super::validate::add_validated_snapshot;
use super::{adjust, nadir, oblique, stage, vehicle, wf_err};
use crate::dag::{
    optional_all, DagBuilder, NodeId, Pipeline, PipelineError, RawFile, Seeds, Session,
};
use crate::exports::{write_exports, ExportInputs};
use crate::nodes::campaign::ingest::ingest_file;
use crate::nodes::campaign::load::{listing_hash, metadata_inputs};
use crate::nodes::{
    CampaignSummary, LoadCampaign, LoadCampaignParams, OrthoProject, RenderCampaign,
    SelectRecording, SelectRecordingParams, SummarizeCampaign, SummaryParams, SynthCampaign,
    SynthParams,
};
use crate::workflow::{CampaignSource, Workflow};
use skytie_stages::nadir::OrthoParams;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// See the module documentation.
pub struct SkytiePipeline;

/// Stage names a workflow may enable in `stages = [...]`.
pub const STAGES: [&str; 20] = stage::ALL;

/// Absolute form of a campaign folder (keys must not depend on the working directory's spelling).
fn absolute(p: &Path) -> PathBuf {
    std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf())
}

impl Pipeline for SkytiePipeline {
    fn name(&self) -> &'static str {
        "skytie"
    }

    fn stage_names(&self) -> Vec<&'static str> {
        STAGES.to_vec()
    }

    fn validate(&self, wf: &Workflow) -> Result<(), String> {
        super::catalogue::validate(wf)
    }

    fn run(&self, wf: &Workflow, session: &mut Session<'_>) -> Result<(), PipelineError> {
        for s in &wf.stages {
            if !STAGES.contains(&s.as_str()) {
                return Err(PipelineError::Workflow(format!(
                    "{}: stage '{s}' is not available in this skytie (available: {})",
                    wf.path.display(),
                    STAGES.join(", ")
                )));
            }
        }
        // Phase 1: the campaign folder.
        let root: PathBuf = match &wf.campaign {
            CampaignSource::Path(p) => absolute(p),
            CampaignSource::Synth { preset, seed } => {
                let mut params: SynthParams = wf.params(stage::SYNTH, "default").map_err(wf_err)?;
                params.preset = preset.clone();
                params.seed = *seed;
                let options = params
                    .options()
                    .map_err(|v| wf_err(format!("[synth] {v}")))?;
                let mut b = DagBuilder::new();
                let rendered = b.add(RenderCampaign, preset, options.render_identity(), ())?;
                let h = b.add(SynthCampaign, preset, params, rendered)?;
                b.request(h);
                let values = session.execute("campaign", b.build());
                values.require(h, "the synthetic campaign")?.path()
            }
        };
        // Phase 2: read and validate it.
        let load_params = LoadCampaignParams {
            root: root.to_string_lossy().into_owned(),
            listing_hash: listing_hash(&root).map_err(|e| {
                PipelineError::Input(format!(
                    "{}: cannot list the campaign folder: {e}",
                    root.display()
                ))
            })?,
        };
        let inputs = metadata_inputs(&root);
        if inputs.is_empty() {
            return Err(PipelineError::Input(format!(
                "{}: not a campaign (no campaign.toml or mm/recordings.csv; see docs/campaign-format.md)",
                root.display()
            )));
        }
        let mut b = DagBuilder::new();
        let snap_h = b.add(LoadCampaign, "", load_params.clone(), inputs.clone())?;
        b.request(snap_h);
        let values = session.execute("load", b.build());
        let loaded = values.require(snap_h, "the campaign")?;
        // Phase 2b: its images, probed by content (the validation `skytie check` applies).
        let mut b = DagBuilder::new();
        let valid_h = add_validated_snapshot(&mut b, &root, &load_params, &inputs, &loaded)?;
        b.request(valid_h);
        let values = session.execute("validate", b.build());
        let snapshot = values.require(valid_h, "the validated campaign")?;
        if !snapshot.problems.is_empty() {
            eprintln!(
                "campaign {}: {} problem(s) in the input; affected items are skipped (run `skytie check {}` for the list)",
                root.display(),
                snapshot.problems.len(),
                root.display()
            );
        }
        // Phase 2c: the recording vehicle, found in the panoramas (masks every ortho image).
        let campaign = vehicle::LoadedCampaign {
            root: &root,
            load_params: &load_params,
            inputs: &inputs,
            loaded: &loaded,
            validated: &snapshot,
        };
        let vehicle = vehicle::detect(wf, session, &campaign)?;
        // Phase 3: per-recording stages and the summary, for every variant.
        let ortho_on = wf.stages.iter().any(|s| s == stage::ORTHO);
        let nadir_on = nadir::enabled(wf)?;
        let oblique_on = oblique::enabled(wf)?;
        let mut b = DagBuilder::new();
        let mut exports = Vec::new();
        // The shard seeds: one node per recording, in trajectory order (shared by every variant).
        let mut seeds: Vec<NodeId> = Vec::new();
        let mut seeded: HashSet<NodeId> = HashSet::new();
        for variant in wf.variants() {
            b.set_variant(&variant);
            let snap = add_validated_snapshot(&mut b, &root, &load_params, &inputs, &loaded)?;
            let ortho: OrthoParams = vehicle::ortho_params(wf, &variant, vehicle.as_ref())?;
            let mut orthos = Vec::new();
            let mut items = Vec::new();
            for rec in &snapshot.campaign.recordings {
                let label = format!("rec {}", rec.image_id);
                let row = b.add(
                    SelectRecording,
                    &label,
                    SelectRecordingParams {
                        image_id: rec.image_id.clone(),
                    },
                    snap,
                )?;
                if seeded.insert(row.id) {
                    seeds.push(row.id);
                }
                let pano = RawFile(root.join("mm/panoramas").join(&rec.file));
                let pano_image = ingest_file(&mut b, &label, pano.0.clone())?;
                let ortho = if ortho_on {
                    let o = b.add(OrthoProject, &label, ortho.clone(), (row, pano_image))?;
                    orthos.push(o);
                    Some(o)
                } else {
                    None
                };
                items.push(nadir::RecordingItem {
                    recording: rec,
                    row,
                    ortho,
                    pano,
                    pano_image,
                });
            }
            let nadir_handles = if nadir_on {
                Some(nadir::add_nadir(
                    &mut b, wf, &variant, &root, &snapshot, snap, &items, &ortho,
                )?)
            } else {
                None
            };
            let oblique_handles = if oblique_on {
                Some(oblique::add_oblique(
                    &mut b, wf, &variant, &root, &snapshot, snap, &items,
                )?)
            } else {
                None
            };
            let adjust_handles = adjust::add_adjust(
                &mut b,
                wf,
                &variant,
                &root,
                snap,
                &items,
                nadir_handles.as_ref(),
                oblique_handles.as_ref(),
            )?;
            // The exports (correspondences.csv) read these values: request them, or cached runs would not
            // load them.
            for c in nadir_handles.iter().flat_map(|n| &n.control) {
                b.request(*c);
            }
            if let Some(o) = oblique_handles.as_ref().and_then(|o| o.result) {
                b.request(o);
            }
            exports.push((
                variant.clone(),
                adjust_handles,
                nadir_handles.map(|n| n.control).unwrap_or_default(),
                oblique_handles.and_then(|o| o.result),
            ));
            let summary = b.add(
                SummarizeCampaign,
                "",
                SummaryParams::default(),
                (snap, optional_all(&orthos)),
            )?;
            b.metrics(summary, "campaign", |s: &CampaignSummary| s.metrics().0);
            b.metrics(summary, "ortho", |s: &CampaignSummary| s.metrics().1);
        }
        let seeds = Seeds {
            nodes: &seeds,
            per_item_stages: &super::shards::PER_ITEM_STAGES,
        };
        let values = session.execute_sharded("items", b.build(), &seeds)?;
        if !session.partition.writes_outputs() {
            return Ok(());
        }
        if let Some(out) = session.out_dir.clone() {
            for (variant, h, nadir_control, oblique_result) in &exports {
                let report = h.report.and_then(|r| values.get(r));
                let verification = h.verification.and_then(|v| values.get(v));
                let verification_adjusted = h.verification_adjusted.and_then(|v| values.get(v));
                let nadir_control: Vec<_> = nadir_control
                    .iter()
                    .filter_map(|c| values.get(*c))
                    .collect();
                let oblique = oblique_result.and_then(|o| values.get(o));
                if report.is_none()
                    && verification.is_none()
                    && nadir_control.is_empty()
                    && oblique.is_none()
                {
                    continue;
                }
                let dir = if wf.is_sweep() {
                    out.join("variants").join(variant)
                } else {
                    out.clone()
                };
                let inputs = ExportInputs {
                    snapshot: &snapshot,
                    report: report.as_deref(),
                    verification: verification.as_deref(),
                    verification_adjusted: verification_adjusted.as_deref(),
                    nadir_control: &nadir_control,
                    oblique: oblique.as_deref(),
                };
                for problem in write_exports(&dir, &inputs) {
                    session.progress.warn(&problem);
                }
            }
        }
        Ok(())
    }
}

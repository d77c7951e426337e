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

use super::adjust::AdjustHandles;
use super::validate::add_validated_snapshot;
use super::variant::{RecordingItem, VariantContext};
use super::vehicle::LoadedCampaign;
use super::{adjust, nadir, oblique, stage, vehicle, wf_err};
use crate::dag::{
    optional_all, DagBuilder, Handle, NodeId, PhaseValues, Pipeline, PipelineError, RawFile, Seeds,
    Session,
};
use crate::exports::{write_exports, ExportInputs};
use crate::nodes::campaign::ingest::ingest_file;
use crate::nodes::campaign::load::{listing_hash, metadata_inputs, CampaignSnapshot};
use crate::nodes::oblique::consensus::ObliqueOutput;
use crate::nodes::{
    CampaignSummary, LoadCampaign, LoadCampaignParams, OrthoProject, RenderCampaign,
    SelectRecording, SelectRecordingParams, SummarizeCampaign, SummaryParams, SynthCampaign,
    SynthParams,
};
use crate::workflow::{CampaignSource, Workflow};
use skytie_stages::nadir::{OrthoParams, RecordingControl};
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// See the module documentation.
pub struct SkytiePipeline;

/// Stage names a workflow may enable in `stages = [...]`.
pub const STAGES: [&str; 21] = stage::ALL;

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
        check_stage_names(wf)?;
        let root = campaign_root(wf, session)?;
        let campaign = load_campaign(session, root)?;
        // Phase 2c: the recording vehicle, found in the panoramas (masks every ortho image).
        let vehicle = vehicle::detect(wf, session, &campaign.view())?;
        // Phase 3: per-recording stages and the summary, for every variant.
        let mut b = DagBuilder::new();
        let mut seeds = ShardSeeds::default();
        let mut exports = Vec::new();
        for variant in wf.variants() {
            b.set_variant(&variant);
            let ortho = vehicle::ortho_params(wf, &variant, vehicle.as_ref())?;
            exports.push(add_variant(
                &mut b, wf, &variant, &campaign, &ortho, &mut seeds,
            )?);
        }
        let seeds = Seeds {
            nodes: &seeds.nodes,
            per_item_stages: &super::shards::PER_ITEM_STAGES,
        };
        let values = session.execute_sharded("items", b.build(), &seeds)?;
        if !session.partition.writes_outputs() {
            return Ok(());
        }
        if let Some(out) = session.out_dir.clone() {
            for e in &exports {
                let dir = if wf.is_sweep() {
                    out.join("variants").join(&e.variant)
                } else {
                    out.clone()
                };
                for problem in e.write(&dir, &campaign.snapshot, &values) {
                    session.progress.warn(&problem);
                }
            }
        }
        Ok(())
    }
}

/// A stage name the pipeline does not know is refused with the list of available ones.
fn check_stage_names(wf: &Workflow) -> Result<(), PipelineError> {
    match wf.stages.iter().find(|s| !STAGES.contains(&s.as_str())) {
        Some(s) => Err(PipelineError::Workflow(format!(
            "{}: stage '{s}' is not available in this skytie (available: {})",
            wf.path.display(),
            STAGES.join(", ")
        ))),
        None => Ok(()),
    }
}

/// Phase 1: the campaign folder — the workflow's folder, or the synthetic campaign generated for it.
fn campaign_root(wf: &Workflow, session: &mut Session<'_>) -> Result<PathBuf, PipelineError> {
    let (preset, seed) = match &wf.campaign {
        CampaignSource::Path(p) => return Ok(absolute(p)),
        CampaignSource::Synth { preset, seed } => (preset, seed),
    };
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
    Ok(values.require(h, "the synthetic campaign")?.path())
}

/// The campaign as phase 2 read and validated it.
struct Campaign {
    root: PathBuf,
    load_params: LoadCampaignParams,
    inputs: Vec<RawFile>,
    /// The tables as read.
    loaded: Arc<CampaignSnapshot>,
    /// The usable rows once every image file is probed.
    snapshot: Arc<CampaignSnapshot>,
}

impl Campaign {
    fn view(&self) -> LoadedCampaign<'_> {
        LoadedCampaign {
            root: &self.root,
            load_params: &self.load_params,
            inputs: &self.inputs,
            loaded: &self.loaded,
            validated: &self.snapshot,
        }
    }

    /// The validated snapshot's node in `b`.
    fn add_snapshot(&self, b: &mut DagBuilder) -> Result<Handle<CampaignSnapshot>, PipelineError> {
        Ok(add_validated_snapshot(
            b,
            &self.root,
            &self.load_params,
            &self.inputs,
            &self.loaded,
        )?)
    }
}

/// Phase 2: read the campaign's tables, then probe its images by content (the validation `skytie check`
/// applies).
fn load_campaign(session: &mut Session<'_>, root: PathBuf) -> Result<Campaign, PipelineError> {
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
    Ok(Campaign {
        root,
        load_params,
        inputs,
        loaded,
        snapshot,
    })
}

/// The shard seeds: one node per recording, in trajectory order (shared by every variant).
#[derive(Default)]
struct ShardSeeds {
    nodes: Vec<NodeId>,
    seen: HashSet<NodeId>,
}

/// Add one variant's graph: per recording its row, panorama and ortho image, then the nadir and oblique
/// chains, the adjustment and the campaign summary. Returns what the exports read.
fn add_variant(
    b: &mut DagBuilder,
    wf: &Workflow,
    variant: &str,
    campaign: &Campaign,
    ortho: &OrthoParams,
    seeds: &mut ShardSeeds,
) -> Result<VariantExports, PipelineError> {
    let snap = campaign.add_snapshot(b)?;
    let ortho_on = wf.enables(stage::ORTHO);
    let mut items = Vec::new();
    for rec in &campaign.snapshot.campaign.recordings {
        let label = format!("rec {}", rec.image_id);
        let params = SelectRecordingParams {
            image_id: rec.image_id.clone(),
        };
        let row = b.add(SelectRecording, &label, params, snap)?;
        if seeds.seen.insert(row.id) {
            seeds.nodes.push(row.id);
        }
        let pano = RawFile(campaign.root.join("mm/panoramas").join(&rec.file));
        let pano_image = ingest_file(b, &label, pano.0.clone())?;
        let ortho = match ortho_on {
            true => Some(b.add(OrthoProject, &label, ortho.clone(), (row, pano_image))?),
            false => None,
        };
        items.push(RecordingItem {
            recording: rec,
            row,
            ortho,
            pano,
            pano_image,
        });
    }
    let cx = VariantContext {
        wf,
        variant,
        root: &campaign.root,
        snapshot: &campaign.snapshot,
        snap,
        items: &items,
    };
    let nadir_handles = match nadir::enabled(wf)? {
        true => Some(nadir::add_nadir(b, &cx, ortho)?),
        false => None,
    };
    let oblique_handles = match oblique::enabled(wf)? {
        true => Some(oblique::add_oblique(b, &cx)?),
        false => None,
    };
    let adjust = adjust::add_adjust(
        b,
        &cx,
        nadir_handles.as_ref(),
        oblique_handles.as_ref(),
        ortho,
    )?;
    // The exports write the control the adjustment used (after the second registration passes, if any).
    let nadir_control = match &adjust.second_pass_control {
        Some(c) => c.clone(),
        None => nadir_handles.map(|n| n.control).unwrap_or_default(),
    };
    let oblique = match &adjust.second_pass_oblique {
        Some(o) => o.result,
        None => oblique_handles.and_then(|o| o.result),
    };
    // The exports (correspondences.csv) read these values: request them, or cached runs would not load them.
    for c in &nadir_control {
        b.request(*c);
    }
    if let Some(o) = oblique {
        b.request(o);
    }
    let orthos: Vec<_> = items.iter().filter_map(|i| i.ortho).collect();
    let summary = b.add(
        SummarizeCampaign,
        "",
        SummaryParams::default(),
        (snap, optional_all(&orthos)),
    )?;
    b.metrics(summary, "campaign", |s: &CampaignSummary| s.metrics().0);
    b.metrics(summary, "ortho", |s: &CampaignSummary| s.metrics().1);
    Ok(VariantExports {
        variant: variant.to_string(),
        adjust,
        nadir_control,
        oblique,
    })
}

/// What one variant's exports read once the graph has run.
struct VariantExports {
    variant: String,
    adjust: AdjustHandles,
    nadir_control: Vec<Handle<RecordingControl>>,
    oblique: Option<Handle<ObliqueOutput>>,
}

impl VariantExports {
    /// Write the variant's output files into `dir` (nothing when none of their inputs was produced); returns
    /// the problems to warn about.
    fn write(&self, dir: &Path, snapshot: &CampaignSnapshot, values: &PhaseValues) -> Vec<String> {
        let h = &self.adjust;
        let report = h.report.and_then(|r| values.get(r));
        let verification = h.verification.and_then(|v| values.get(v));
        let verification_adjusted = h.verification_adjusted.and_then(|v| values.get(v));
        let nadir_control: Vec<_> = self
            .nadir_control
            .iter()
            .filter_map(|c| values.get(*c))
            .collect();
        let oblique = self.oblique.and_then(|o| values.get(o));
        if report.is_none()
            && verification.is_none()
            && nadir_control.is_empty()
            && oblique.is_none()
        {
            return Vec::new();
        }
        let inputs = ExportInputs {
            snapshot,
            report: report.as_deref(),
            verification: verification.as_deref(),
            verification_adjusted: verification_adjusted.as_deref(),
            nadir_control: &nadir_control,
            oblique: oblique.as_deref(),
        };
        write_exports(dir, &inputs)
    }
}

//! The nadir part of the `skytie` pipeline (thesis chapter 3) for one variant: per recording an MM matching
//! window (`mm_match`), per (recording × overlapping nadir image) the aerial-oriented ortho (`ortho_aerial`),
//! the initial transform (`transform`) and the phase-correlation refinement (`refine`), per recording the
//! aerial control points (`control`), then the global `nadir` summary and — on synthetic campaigns with
//! `truth/` — the evaluation node `grade_nadir`.

use super::orthophoto::OrthophotoRoute;
use super::{distance_m, missing_upstream, stage, wf_err};
use crate::dag::{optional_all, DagBuilder, Handle, PipelineError, RawFile};
use crate::nodes::campaign::aerial::AerialRowNodes;
use crate::nodes::campaign::ingest::{ingest_file, IngestedImage};
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::summary::SummaryParams;
use crate::nodes::nadir::baseline::BaselineStage;
use crate::nodes::nadir::control::ControlStage;
use crate::nodes::nadir::grade::{grade_metrics, GradeNadir, TRUTH_AERIAL_NADIR, TRUTH_RECORDINGS};
use crate::nodes::nadir::mm_match::MmMatch;
use crate::nodes::nadir::options::{Matcher, NadirOptions};
use crate::nodes::nadir::ortho_aerial::OrthoForAerial;
use crate::nodes::nadir::refine::RefineStage;
use crate::nodes::nadir::summary::SummarizeNadir;
use crate::nodes::nadir::transform::InitialTransformStage;
use crate::nodes::nadir::transform_agreement::TransformAgreementStage;
use crate::workflow::Workflow;
use skytie_stages::campaign::{AerialKind, Recording};
use skytie_stages::nadir::aerial_overlap::NadirOverlap;
use skytie_stages::nadir::baseline::BaselineParams;
use skytie_stages::nadir::control_points::ControlParams;
use skytie_stages::nadir::grading::NadirGrade;
use skytie_stages::nadir::initial_transform::TransformParams;
use skytie_stages::nadir::mm_matching::MmMatchParams;
use skytie_stages::nadir::refine::RefineParams;
use skytie_stages::nadir::summary::NadirSummary;
use skytie_stages::nadir::{
    AerialRefinement, MmWindowMatch, OrthoImage, OrthoParams, RecordingControl, TransformOutcome,
};
use std::path::Path;

/// The stages of the nadir chain, in dependency order.
pub const NADIR_STAGES: [&str; 7] = [
    stage::MM_MATCH,
    stage::ORTHO_AERIAL,
    stage::TRANSFORM,
    stage::REFINE,
    stage::CONTROL,
    stage::NADIR,
    stage::GRADE_NADIR,
];

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

/// What the nadir chain hands to later stages (the adjustment).
pub struct NadirHandles {
    pub windows: Vec<Handle<MmWindowMatch>>,
    pub control: Vec<Handle<RecordingControl>>,
}

/// Which nadir stages the workflow enables; an enabled stage whose upstream is not enabled is an error.
pub fn enabled(wf: &Workflow) -> Result<bool, PipelineError> {
    let on = |s: &str| wf.stages.iter().any(|x| x == s);
    let Some(last) = NADIR_STAGES
        .iter()
        .rposition(|s| on(s) && *s != stage::GRADE_NADIR)
    else {
        if on(stage::GRADE_NADIR) {
            return Err(wf_err(format!(
                "{}: stage 'grade_nadir' needs the nadir chain ({})",
                wf.path.display(),
                NADIR_STAGES[..6].join(", ")
            )));
        }
        return Ok(false);
    };
    let mut needed: Vec<&str> = NADIR_STAGES[..=last].to_vec();
    if !on(stage::ORTHO) {
        needed.insert(0, stage::ORTHO);
    }
    let missing: Vec<&str> = needed.into_iter().filter(|s| !on(s)).collect();
    if !missing.is_empty() {
        return Err(missing_upstream(
            wf,
            stage::NADIR,
            NADIR_STAGES[last],
            &missing,
            &format!("ortho, {}", NADIR_STAGES.join(", ")),
        ));
    }
    Ok(true)
}

/// Add the nadir chain for `variant`. `items` are in trajectory (time) order.
#[allow(clippy::too_many_arguments)]
pub fn add_nadir(
    b: &mut DagBuilder,
    wf: &Workflow,
    variant: &str,
    root: &Path,
    snapshot: &CampaignSnapshot,
    snap: Handle<CampaignSnapshot>,
    items: &[RecordingItem<'_>],
    ortho_base: &OrthoParams,
) -> Result<NadirHandles, PipelineError> {
    let on = |s: &str| wf.stages.iter().any(|x| x == s);
    let options: NadirOptions = wf.params(stage::NADIR, variant).map_err(wf_err)?;
    let mm_params: MmMatchParams = wf.params(stage::MM_MATCH, variant).map_err(wf_err)?;
    let transform_params: TransformParams = wf.params(stage::TRANSFORM, variant).map_err(wf_err)?;
    let refine_params: RefineParams = wf.params(stage::REFINE, variant).map_err(wf_err)?;
    let control_params: ControlParams = wf.params(stage::CONTROL, variant).map_err(wf_err)?;
    let window_len = if options.triples { 2 } else { 1 };
    let Some(orthos) = items.iter().map(|i| i.ortho).collect::<Option<Vec<_>>>() else {
        return Err(wf_err(format!(
            "{}: the nadir chain needs stage 'ortho' in `stages`",
            wf.path.display()
        )));
    };
    let nadir_dir = root.join("aerial/nadir");
    let mut photo_route = match on(stage::CONTROL) {
        true => OrthophotoRoute::new(b, wf, variant, root, snapshot, ortho_base)?,
        false => None,
    };

    let mut aerial_rows = AerialRowNodes::new(AerialKind::Nadir, snap);
    let overlap = NadirOverlap::new(&snapshot.campaign.nadir, &snapshot.campaign.recordings);
    let mut windows = Vec::new();
    let mut transforms: Vec<Handle<TransformOutcome>> = Vec::new();
    let mut refinements: Vec<Handle<AerialRefinement>> = Vec::new();
    let mut control = Vec::new();
    for (i, item) in items.iter().enumerate() {
        let neighbours: Vec<&RecordingItem> = items[i + 1..]
            .iter()
            .take(window_len)
            .take_while(|n| {
                distance_m(item.recording, n.recording) <= options.max_neighbour_distance_m
            })
            .collect();
        if neighbours.is_empty() {
            continue;
        }
        let label = format!("rec {}", item.recording.image_id);
        let members: Vec<&RecordingItem> = std::iter::once(item).chain(neighbours).collect();
        let member_orthos = &orthos[i..i + members.len()];
        let window = b.add(
            MmMatch,
            &label,
            mm_params.clone(),
            (
                members.iter().map(|m| m.row).collect::<Vec<_>>(),
                member_orthos.to_vec(),
                members.iter().map(|m| m.pano.clone()).collect::<Vec<_>>(),
            ),
        )?;
        windows.push(window);
        if let Some(route) = photo_route.as_mut() {
            let handles: Vec<_> = members
                .iter()
                .map(|m| (m.recording, m.row, m.pano_image))
                .collect();
            control.extend(route.add_recording(b, &handles, window)?);
        }
        if !on(stage::ORTHO_AERIAL) {
            continue;
        }
        let mut rec_refinements = Vec::new();
        let mut rec_aerials = Vec::new();
        // Per overlapping nadir image: (aerial handle, file, pair label, ortho, transform outcome, aerial image_id).
        let mut pairs = Vec::new();
        for a in overlap.overlapping(item.recording, options.overlap_margin_m) {
            let row = &snapshot.campaign.nadir[a];
            let aerial = aerial_rows.get_or_add(b, a, row)?;
            let pair = pair_label(&item.recording.image_id, &row.image_id);
            let aerial_file = ingest_file(
                b,
                &format!("nadir {}", row.image_id),
                nadir_dir.join(&row.file),
            )?;
            let ortho = b.add(
                OrthoForAerial,
                &pair,
                ortho_base.clone(),
                (item.row, item.pano_image, aerial),
            )?;
            if !on(stage::TRANSFORM) {
                continue;
            }
            let outcome = b.add(
                InitialTransformStage,
                &pair,
                transform_params.clone(),
                (item.row, ortho, aerial_file, aerial),
            )?;
            pairs.push((
                aerial,
                aerial_file,
                pair,
                ortho,
                outcome,
                row.image_id.clone(),
            ));
        }
        // The recording's transforms must agree with each other (`nadir::transform_agreement`).
        let outcomes: Vec<Handle<TransformOutcome>> = pairs.iter().map(|p| p.4).collect();
        for (aerial, aerial_file, pair, ortho, outcome, aerial_id) in pairs {
            let outcome = b.add(
                TransformAgreementStage,
                &pair,
                transform_params.clone(),
                (outcome, outcomes.clone()),
            )?;
            transforms.push(outcome);
            if !on(stage::REFINE) {
                continue;
            }
            let inputs = (ortho, aerial_file, aerial, outcome, window);
            let refined = match options.matcher {
                Matcher::PhaseCorrelation => {
                    // The neighbours' orthos for this aerial image (the same nodes their own pairs use), in
                    // the window's neighbour order, for the parallax check.
                    let neighbour_orthos = members[1..]
                        .iter()
                        .map(|n| {
                            b.add(
                                OrthoForAerial,
                                &pair_label(&n.recording.image_id, &aerial_id),
                                ortho_base.clone(),
                                (n.row, n.pano_image, aerial),
                            )
                        })
                        .collect::<Result<Vec<_>, _>>()?;
                    let (o, f, a, t, w) = inputs;
                    b.add(
                        RefineStage,
                        &pair,
                        refine_params.clone(),
                        (o, f, a, t, w, neighbour_orthos),
                    )?
                }
                Matcher::Baseline => {
                    let p: BaselineParams = wf.params(stage::BASELINE, variant).map_err(wf_err)?;
                    b.add(BaselineStage, &pair, p, inputs)?
                }
            };
            refinements.push(refined);
            rec_refinements.push(refined);
            rec_aerials.push(aerial);
        }
        if on(stage::CONTROL) {
            control.push(b.add(
                ControlStage,
                &label,
                control_params.clone(),
                (window, optional_all(&rec_refinements), rec_aerials),
            )?);
        }
    }
    if let Some(route) = photo_route {
        route.finish(b)?;
    }
    if on(stage::NADIR) {
        let summary = b.add(
            SummarizeNadir,
            "",
            SummaryParams::default(),
            (
                snap,
                optional_all(&windows),
                optional_all(&transforms),
                optional_all(&refinements),
                optional_all(&control),
            ),
        )?;
        b.metrics(summary, "nadir", |s: &NadirSummary| s.metrics());
    }
    let truth = root.join(TRUTH_RECORDINGS);
    if on(stage::GRADE_NADIR) && truth.is_file() {
        let mut truth_files = vec![RawFile(truth)];
        let truth_aerial = root.join(TRUTH_AERIAL_NADIR);
        if truth_aerial.is_file() {
            truth_files.push(RawFile(truth_aerial));
        }
        let grade = b.add(
            GradeNadir,
            "",
            SummaryParams::default(),
            (
                snap,
                truth_files,
                items.iter().map(|i| i.pano.clone()).collect::<Vec<_>>(),
                windows.clone(),
                refinements,
                control.clone(),
            ),
        )?;
        b.metrics(grade, "nadir", |g: &NadirGrade| grade_metrics(g));
    }
    Ok(NadirHandles { windows, control })
}

/// The item label of a (recording × nadir image) node; the neighbours' orthos for the parallax check reuse the
/// neighbour's own pair nodes through it.
fn pair_label(recording_id: &str, aerial_id: &str) -> String {
    format!("rec {recording_id} × {aerial_id}")
}

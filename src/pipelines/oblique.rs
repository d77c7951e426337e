//! The oblique part of the `skytie` pipeline (thesis chapter 4) for one variant: per panorama triplet the
//! sparse cloud (`sparse_cloud`) and its façades (`facades`), per (triplet centre × candidate oblique image) the
//! patch registration (`patches`), then the global `oblique` node (median consensus: correspondences, control points,
//! `oblique.*` counts) and — on synthetic campaigns with `truth/` — the evaluation node `grade_oblique`.
//!
//! Shared work across a sweep comes from the keys: the sparse cloud's key does not depend on any façade,
//! patch or consensus parameter, so an 18-variant sweep computes it once; `facades` once per distinct plane
//! setting; `patches` once per distinct (façades, registration setting).

use super::nadir::RecordingItem;
use super::{distance_m, missing_upstream, stage, wf_err};
use crate::dag::{optional_all, DagBuilder, Handle, PipelineError, RawFile};
use crate::nodes::campaign::aerial::AerialRowNodes;
use crate::nodes::campaign::ingest::ingest_file;
use crate::nodes::campaign::load::CampaignSnapshot;
use crate::nodes::campaign::summary::SummaryParams;
use crate::nodes::oblique::consensus::{ConsensusStage, ObliqueOutput};
use crate::nodes::oblique::facades::FacadesStage;
use crate::nodes::oblique::grade::{
    GradeOblique, SCENE_TRUTH_FILE, TRUTH_AERIAL_OBLIQUE, TRUTH_RECORDINGS,
};
use crate::nodes::oblique::options::ObliqueOptions;
use crate::nodes::oblique::patches::PatchesStage;
use crate::nodes::oblique::sparse_cloud::SparseCloudStage;
use crate::workflow::Workflow;
use skytie_stages::campaign::{AerialKind, Recording};
use skytie_stages::oblique::candidates::ObliqueCandidates;
use skytie_stages::oblique::facades::FacadeParams;
use skytie_stages::oblique::patch_registration::PatchParams;
use skytie_stages::oblique::sparse_cloud::SparseCloudParams;
use skytie_stages::oblique::{PatchRegistrationSet, SparseCloud, TripletFacades};
use std::path::Path;

/// The stages of the oblique chain, in dependency order.
pub const OBLIQUE_STAGES: [&str; 5] = [
    stage::SPARSE_CLOUD,
    stage::FACADES,
    stage::PATCHES,
    stage::OBLIQUE,
    stage::GRADE_OBLIQUE,
];

/// What the oblique chain hands to later stages (the adjustment, the exports).
pub struct ObliqueHandles {
    pub clouds: Vec<Handle<SparseCloud>>,
    pub result: Option<Handle<ObliqueOutput>>,
}

/// Whether the workflow enables the oblique chain; an enabled stage whose upstream is not enabled is an error.
pub fn enabled(wf: &Workflow) -> Result<bool, PipelineError> {
    let on = |s: &str| wf.stages.iter().any(|x| x == s);
    let Some(last) = OBLIQUE_STAGES.iter().rposition(|s| on(s)) else {
        return Ok(false);
    };
    let last_needed = if OBLIQUE_STAGES[last] == stage::GRADE_OBLIQUE {
        3
    } else {
        last
    };
    let missing: Vec<&str> = OBLIQUE_STAGES[..=last_needed]
        .iter()
        .copied()
        .filter(|s| !on(s))
        .collect();
    if !missing.is_empty() {
        return Err(missing_upstream(
            wf,
            stage::OBLIQUE,
            OBLIQUE_STAGES[last],
            &missing,
            &OBLIQUE_STAGES.join(", "),
        ));
    }
    Ok(true)
}

/// Add the oblique chain for `variant`. `items` are in trajectory (time) order.
#[allow(clippy::too_many_arguments)]
pub fn add_oblique(
    b: &mut DagBuilder,
    wf: &Workflow,
    variant: &str,
    root: &Path,
    snapshot: &CampaignSnapshot,
    snap: Handle<CampaignSnapshot>,
    items: &[RecordingItem<'_>],
) -> Result<ObliqueHandles, PipelineError> {
    let on = |s: &str| wf.stages.iter().any(|x| x == s);
    let options: ObliqueOptions = wf.params(stage::OBLIQUE, variant).map_err(wf_err)?;
    let cloud_params: SparseCloudParams =
        wf.params(stage::SPARSE_CLOUD, variant).map_err(wf_err)?;
    let facade_params: FacadeParams = wf.params(stage::FACADES, variant).map_err(wf_err)?;
    let patch_params: PatchParams = wf.params(stage::PATCHES, variant).map_err(wf_err)?;
    let oblique_dir = root.join("aerial/oblique");
    let oblique_rows = &snapshot.campaign.oblique;
    let candidate_index = ObliqueCandidates::new(
        oblique_rows,
        &snapshot.campaign.recordings,
        options.max_facade_distance_m,
        options.max_facade_height_m,
    );

    let mut aerial_rows = AerialRowNodes::new(AerialKind::Oblique, snap);
    let mut all_facades: Vec<Handle<TripletFacades>> = Vec::new();
    let mut sets: Vec<Handle<PatchRegistrationSet>> = Vec::new();
    // Pass 1: the sparse cloud of every triplet (centre item index → cloud).
    let mut triplets: Vec<(usize, Handle<SparseCloud>)> = Vec::new();
    for (i, w) in items.windows(3).enumerate() {
        let (first, centre, last) = (&w[0], &w[1], &w[2]);
        if distance_m(first.recording, centre.recording) > options.max_neighbour_distance_m
            || distance_m(centre.recording, last.recording) > options.max_neighbour_distance_m
        {
            continue;
        }
        let cloud = b.add(
            SparseCloudStage,
            &format!("rec {}", centre.recording.image_id),
            cloud_params.clone(),
            (
                w.iter().map(|m| m.row).collect::<Vec<_>>(),
                w.iter().map(|m| m.pano_image).collect::<Vec<_>>(),
            ),
        )?;
        triplets.push((i + 1, cloud));
    }
    let clouds: Vec<Handle<SparseCloud>> = triplets.iter().map(|(_, c)| *c).collect();
    // Pass 2: per triplet its façades (fitted to its own and its neighbours' points) and patches.
    for (t, &(centre_idx, cloud)) in triplets.iter().enumerate() {
        if !on(stage::FACADES) {
            break;
        }
        let centre = &items[centre_idx];
        let label = format!("rec {}", centre.recording.image_id);
        let rows: Vec<Handle<Recording>> = items[centre_idx - 1..=centre_idx + 1]
            .iter()
            .map(|m| m.row)
            .collect();
        // Neighbouring triplets along the same street: consecutive, within `plane_neighbours` triplets and
        // `max_plane_distance_m` of the centre (recorded positions).
        let near = |&&(j, _): &&(usize, Handle<SparseCloud>)| {
            j.abs_diff(centre_idx) <= options.plane_neighbours
                && distance_m(items[j].recording, centre.recording) <= options.max_plane_distance_m
        };
        let neighbourhood: Vec<Handle<SparseCloud>> = std::iter::once(cloud)
            .chain(
                triplets[t.saturating_sub(options.plane_neighbours)..]
                    .iter()
                    .take(2 * options.plane_neighbours + 1)
                    .filter(near)
                    .filter(|(j, _)| *j != centre_idx)
                    .map(|(_, c)| *c),
            )
            .collect();
        let candidates = candidate_index.candidates(centre.recording);
        let mut aerials = Vec::with_capacity(candidates.len());
        for &a in &candidates {
            let row = &oblique_rows[a];
            let h = aerial_rows.get_or_add(b, a, row)?;
            aerials.push((a, h));
        }
        let facades = b.add(
            FacadesStage,
            &label,
            facade_params.clone(),
            (
                neighbourhood.clone(),
                rows,
                aerials.iter().map(|(_, h)| *h).collect::<Vec<_>>(),
            ),
        )?;
        all_facades.push(facades);
        if !on(stage::PATCHES) {
            continue;
        }
        for (a, aerial) in aerials {
            let row = &oblique_rows[a];
            let pair = format!("rec {} × {}", centre.recording.image_id, row.image_id);
            let oblique_image = ingest_file(
                b,
                &format!("oblique {}", row.image_id),
                oblique_dir.join(&row.file),
            )?;
            sets.push(b.add(
                PatchesStage,
                &pair,
                patch_params.clone(),
                (
                    centre.row,
                    centre.pano_image,
                    aerial,
                    oblique_image,
                    neighbourhood.clone(),
                    facades,
                ),
            )?);
        }
    }
    let mut out = ObliqueHandles {
        clouds: clouds.clone(),
        result: None,
    };
    if !on(stage::OBLIQUE) {
        return Ok(out);
    }
    let panos: Vec<RawFile> = items.iter().map(|i| i.pano.clone()).collect();
    let result = b.add(
        ConsensusStage,
        "",
        options.consensus.clone(),
        (
            snap,
            panos.clone(),
            optional_all(&clouds),
            optional_all(&all_facades),
            optional_all(&sets),
        ),
    )?;
    b.metrics(result, "oblique", |o: &ObliqueOutput| o.summary.metrics());
    out.result = Some(result);
    let truth = root.join(TRUTH_RECORDINGS);
    if on(stage::GRADE_OBLIQUE) && truth.is_file() {
        let mut truth_files = vec![RawFile(truth)];
        let truth_aerial = root.join(TRUTH_AERIAL_OBLIQUE);
        if truth_aerial.is_file() {
            truth_files.push(RawFile(truth_aerial));
        }
        let scene_file = root.join(SCENE_TRUTH_FILE);
        let scene_files: Vec<RawFile> = if scene_file.is_file() {
            vec![RawFile(scene_file)]
        } else {
            Vec::new()
        };
        let grade = b.add(
            GradeOblique,
            "",
            SummaryParams::default(),
            (snap, truth_files, scene_files, panos, clouds, result),
        )?;
        b.metrics(grade, "oblique", GradeOblique::metrics);
    }
    Ok(out)
}

//! The oblique part of the `skytie` pipeline (thesis chapter 4) for one variant: per panorama triplet the
//! sparse cloud (`sparse_cloud`) and its façades (`facades`), per (triplet centre × candidate oblique image) the
//! patch registration (`patches`), then the global `oblique` node (median consensus: correspondences, control points,
//! `oblique.*` counts) and — on synthetic campaigns with `truth/` — the evaluation node `grade_oblique`. With
//! `[adjust] passes = 2` the same chain runs a second time from the first adjustment's poses
//! ([`add_second_pass`], `oblique_pass2.*`).
//!
//! Shared work across a sweep comes from the keys: the sparse cloud's key does not depend on any façade,
//! patch or consensus parameter, so an 18-variant sweep computes it once; `facades` once per distinct plane
//! setting; `patches` once per distinct (façades, registration setting).

use super::variant::{RecordingItem, VariantContext};
use super::{distance_m, missing_upstream, stage};
use crate::dag::{optional_all, DagBuilder, Handle, PipelineError, RawFile};
use crate::nodes::adjust::adjustment::AdjustReport;
use crate::nodes::adjust::second_pass::{PassPriorParams, Shift, TrajectoryPrior};
use crate::nodes::campaign::aerial::AerialRowNodes;
use crate::nodes::campaign::ingest::ingest_file;
use crate::nodes::campaign::summary::SummaryParams;
use crate::nodes::oblique::consensus::{ConsensusStage, ObliqueOutput};
use crate::nodes::oblique::facades::FacadesStage;
use crate::nodes::oblique::grade::{GradeOblique, SCENE_TRUTH_FILE, TRUTH_AERIAL_OBLIQUE};
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
    let on = |s: &str| wf.enables(s);
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

/// Add the oblique chain for the variant of `cx`, its `oblique` metrics and, with `truth/`, its grade.
pub fn add_oblique(
    b: &mut DagBuilder,
    cx: &VariantContext<'_>,
) -> Result<ObliqueHandles, PipelineError> {
    let out = add_chain(b, cx, "")?;
    add_metrics(b, cx, &out, "oblique", "")?;
    Ok(out)
}

/// The oblique chain searched again around the first adjustment (`[adjust] passes = 2`): every recording's row
/// shifted by its correction (`pass_trajectory`), then the sparse clouds, façades, patches and consensus of
/// those rows; metrics and grade under `oblique_pass2`. A recording the adjustment did not move keeps its row,
/// and every node that reads only such rows is the first pass's.
pub fn add_second_pass(
    b: &mut DagBuilder,
    cx: &VariantContext<'_>,
    report: Handle<AdjustReport>,
) -> Result<ObliqueHandles, PipelineError> {
    let mut items = Vec::with_capacity(cx.items.len());
    for (index, item) in cx.items.iter().enumerate() {
        let label = format!("rec {} oblique pass 2", item.recording.image_id);
        let params = PassPriorParams {
            image_id: item.recording.image_id.clone(),
            index_hint: index,
        };
        let shift = b.add(TrajectoryPrior, &label, params, report)?;
        items.push(RecordingItem {
            recording: item.recording,
            row: Shift::add(b, &label, item.row, shift)?,
            ortho: item.ortho,
            pano: item.pano.clone(),
            pano_image: item.pano_image,
        });
    }
    let shifted = VariantContext {
        items: &items,
        ..*cx
    };
    let out = add_chain(b, &shifted, " pass 2")?;
    add_metrics(b, &shifted, &out, "oblique_pass2", "pass 2")?;
    Ok(out)
}

/// The chain's nodes; `pass` is appended to every item label (the second pass's nodes are distinct items).
fn add_chain(
    b: &mut DagBuilder,
    cx: &VariantContext<'_>,
    pass: &str,
) -> Result<ObliqueHandles, PipelineError> {
    let options: ObliqueOptions = cx.params(stage::OBLIQUE)?;
    let triplets = add_sparse_clouds(b, cx, &options, pass)?;
    let clouds: Vec<Handle<SparseCloud>> = triplets.iter().map(|(_, c)| *c).collect();
    let FacadesAndPatches {
        facades: all_facades,
        sets,
    } = match cx.on(stage::FACADES) {
        true => add_facades_and_patches(b, cx, &options, &triplets, pass)?,
        false => FacadesAndPatches::default(),
    };
    let mut out = ObliqueHandles {
        clouds: clouds.clone(),
        result: None,
    };
    if !cx.on(stage::OBLIQUE) {
        return Ok(out);
    }
    let panos: Vec<RawFile> = cx.items.iter().map(|i| i.pano.clone()).collect();
    out.result = Some(b.add(
        ConsensusStage,
        pass.trim_start(),
        options.consensus.clone(),
        (
            cx.snap,
            panos,
            optional_all(&clouds),
            optional_all(&all_facades),
            optional_all(&sets),
        ),
    )?);
    Ok(out)
}

/// The consensus counts of `out` under `namespace` in `metrics.json` and, on a campaign with `truth/`, its
/// grade (a node of item `item`).
fn add_metrics(
    b: &mut DagBuilder,
    cx: &VariantContext<'_>,
    out: &ObliqueHandles,
    namespace: &str,
    item: &str,
) -> Result<(), PipelineError> {
    let Some(result) = out.result else {
        return Ok(());
    };
    b.metrics(result, namespace, |o: &ObliqueOutput| o.summary.metrics());
    if let Some(truth_files) = cx.truth_files(stage::GRADE_OBLIQUE, &[TRUTH_AERIAL_OBLIQUE]) {
        let scene_file = cx.root.join(SCENE_TRUTH_FILE);
        let scene_files: Vec<RawFile> = if scene_file.is_file() {
            vec![RawFile(scene_file)]
        } else {
            Vec::new()
        };
        let panos: Vec<RawFile> = cx.items.iter().map(|i| i.pano.clone()).collect();
        let grade = b.add(
            GradeOblique,
            item,
            SummaryParams::default(),
            (
                cx.snap,
                truth_files,
                scene_files,
                panos,
                out.clouds.clone(),
                result,
            ),
        )?;
        b.metrics(grade, namespace, GradeOblique::metrics);
    }
    Ok(())
}

/// Pass 1 (thesis 4.4.1): the sparse cloud of every triplet of consecutive recordings close enough together,
/// as (centre item index, cloud).
fn add_sparse_clouds(
    b: &mut DagBuilder,
    cx: &VariantContext<'_>,
    options: &ObliqueOptions,
    pass: &str,
) -> Result<Vec<(usize, Handle<SparseCloud>)>, PipelineError> {
    let cloud_params: SparseCloudParams = cx.params(stage::SPARSE_CLOUD)?;
    let mut triplets = Vec::new();
    for (i, w) in cx.items.windows(3).enumerate() {
        let (first, centre, last) = (&w[0], &w[1], &w[2]);
        if distance_m(first.recording, centre.recording) > options.max_neighbour_distance_m
            || distance_m(centre.recording, last.recording) > options.max_neighbour_distance_m
        {
            continue;
        }
        let cloud = b.add(
            SparseCloudStage,
            &format!("rec {}{pass}", centre.recording.image_id),
            cloud_params.clone(),
            (
                w.iter().map(|m| m.row).collect::<Vec<_>>(),
                w.iter().map(|m| m.pano_image).collect::<Vec<_>>(),
            ),
        )?;
        triplets.push((i + 1, cloud));
    }
    Ok(triplets)
}

/// The clouds a triplet's façades are fitted to: its own, then those of the neighbouring triplets along the
/// same street (consecutive, within `plane_neighbours` triplets and `max_plane_distance_m` of the centre's
/// recorded position).
fn neighbourhood(
    items: &[RecordingItem<'_>],
    options: &ObliqueOptions,
    triplets: &[(usize, Handle<SparseCloud>)],
    t: usize,
) -> Vec<Handle<SparseCloud>> {
    let (centre_idx, cloud) = triplets[t];
    let centre = &items[centre_idx];
    let near = |&&(j, _): &&(usize, Handle<SparseCloud>)| {
        j.abs_diff(centre_idx) <= options.plane_neighbours
            && distance_m(items[j].recording, centre.recording) <= options.max_plane_distance_m
    };
    std::iter::once(cloud)
        .chain(
            triplets[t.saturating_sub(options.plane_neighbours)..]
                .iter()
                .take(2 * options.plane_neighbours + 1)
                .filter(near)
                .filter(|(j, _)| *j != centre_idx)
                .map(|(_, c)| *c),
        )
        .collect()
}

/// The façade nodes of every triplet and the patch-registration nodes of every (triplet × oblique image).
#[derive(Default)]
struct FacadesAndPatches {
    facades: Vec<Handle<TripletFacades>>,
    sets: Vec<Handle<PatchRegistrationSet>>,
}

/// Pass 2: per triplet its façades (thesis 4.4.2–4.4.4, fitted to its own and its neighbours' points) and,
/// when enabled, per candidate oblique image its patch registrations (4.4.5–4.4.6).
fn add_facades_and_patches(
    b: &mut DagBuilder,
    cx: &VariantContext<'_>,
    options: &ObliqueOptions,
    triplets: &[(usize, Handle<SparseCloud>)],
    pass: &str,
) -> Result<FacadesAndPatches, PipelineError> {
    let facade_params: FacadeParams = cx.params(stage::FACADES)?;
    let patch_params: PatchParams = cx.params(stage::PATCHES)?;
    let oblique_dir = cx.root.join("aerial/oblique");
    let oblique_rows = &cx.snapshot.campaign.oblique;
    let candidate_index = ObliqueCandidates::new(
        oblique_rows,
        &cx.snapshot.campaign.recordings,
        options.max_facade_distance_m,
        options.max_facade_height_m,
    );
    let mut aerial_rows = AerialRowNodes::new(AerialKind::Oblique, cx.snap);
    let mut all_facades = Vec::new();
    let mut sets = Vec::new();
    for (t, &(centre_idx, _)) in triplets.iter().enumerate() {
        let centre = &cx.items[centre_idx];
        let label = format!("rec {}{pass}", centre.recording.image_id);
        let rows: Vec<Handle<Recording>> = cx.items[centre_idx - 1..=centre_idx + 1]
            .iter()
            .map(|m| m.row)
            .collect();
        let neighbourhood = neighbourhood(cx.items, options, triplets, t);
        let candidates = candidate_index.candidates(centre.recording);
        let mut aerials = Vec::with_capacity(candidates.len());
        for &a in &candidates {
            aerials.push((a, aerial_rows.get_or_add(b, a, &oblique_rows[a])?));
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
        if !cx.on(stage::PATCHES) {
            continue;
        }
        for (a, aerial) in aerials {
            let row = &oblique_rows[a];
            let pair = format!("rec {} × {}{pass}", centre.recording.image_id, row.image_id);
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
    Ok(FacadesAndPatches {
        facades: all_facades,
        sets,
    })
}

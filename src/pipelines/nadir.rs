//! The nadir part of the `skytie` pipeline (thesis chapter 3) for one variant: per recording an MM matching
//! window (`mm_match`), per (recording × overlapping nadir image) the aerial-oriented ortho (`ortho_aerial`),
//! the initial transform (`transform`) and the phase-correlation refinement (`refine`), per recording the
//! aerial control points (`control`), then the global `nadir` summary and — on synthetic campaigns with
//! `truth/` — the evaluation node `grade_nadir`.

use super::orthophoto::OrthophotoRoute;
use super::variant::{RecordingItem, VariantContext};
use super::{distance_m, missing_upstream, stage, wf_err};
use crate::dag::{optional_all, DagBuilder, Handle, PipelineError};
use crate::nodes::adjust::adjustment::AdjustReport;
use crate::nodes::adjust::second_pass::{
    passes_metrics, CountPasses, PassPrior, PassPriorParams, Shift,
};
use crate::nodes::campaign::aerial::AerialRowNodes;
use crate::nodes::campaign::ingest::{ingest_file, IngestedImage};
use crate::nodes::campaign::map_frame::MapFrameStage;
use crate::nodes::campaign::summary::SummaryParams;
use crate::nodes::nadir::baseline::BaselineStage;
use crate::nodes::nadir::control::ControlStage;
use crate::nodes::nadir::grade::{grade_metrics, GradeNadir, TRUTH_AERIAL_NADIR};
use crate::nodes::nadir::mm_match::MmMatch;
use crate::nodes::nadir::options::{Matcher, NadirOptions};
use crate::nodes::nadir::ortho_aerial::OrthoForAerial;
use crate::nodes::nadir::peak_support::PeakSupportStage;
use crate::nodes::nadir::refine::RefineStage;
use crate::nodes::nadir::summary::SummarizeNadir;
use crate::nodes::nadir::transform::InitialTransformStage;
use crate::nodes::nadir::transform_agreement::TransformAgreementStage;
use crate::workflow::Workflow;
use skytie_stages::adjustment::second_pass::RegistrationPasses;
use skytie_stages::campaign::{AerialImage, AerialKind};
use skytie_stages::crs::MapFrameSpec;
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

/// What the nadir chain hands to later stages (the adjustment).
pub struct NadirHandles {
    pub windows: Vec<Handle<MmWindowMatch>>,
    pub control: Vec<Handle<RecordingControl>>,
    /// Per recording with a window, the nodes a second registration pass starts from.
    pub recordings: Vec<RecordingNadir>,
}

/// One recording's nadir nodes that a second registration pass (`add_second_pass`) translates and re-runs.
pub struct RecordingNadir {
    /// Index into the variant's items.
    item: usize,
    /// The recording's neighbours in its window (item indices).
    neighbours: Vec<usize>,
    window: Handle<MmWindowMatch>,
    pairs: Vec<PairBase>,
    /// Index of its aerial control into `NadirHandles::control`.
    control: Option<usize>,
}

/// A (recording × nadir image) pair's nodes up to its aerial-oriented ortho image.
#[derive(Clone)]
struct PairBase {
    aerial: Handle<AerialImage>,
    aerial_file: Handle<IngestedImage>,
    ortho: Handle<OrthoImage>,
    aerial_id: String,
}

/// Which nadir stages the workflow enables; an enabled stage whose upstream is not enabled is an error.
pub fn enabled(wf: &Workflow) -> Result<bool, PipelineError> {
    let on = |s: &str| wf.enables(s);
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

/// One (recording × overlapping nadir image) pair's nodes up to its initial transform.
struct AerialPair {
    aerial: Handle<AerialImage>,
    aerial_file: Handle<IngestedImage>,
    label: String,
    ortho: Handle<OrthoImage>,
    outcome: Handle<TransformOutcome>,
    aerial_id: String,
}

impl AerialPair {
    fn base(&self) -> PairBase {
        PairBase {
            aerial: self.aerial,
            aerial_file: self.aerial_file,
            ortho: self.ortho,
            aerial_id: self.aerial_id.clone(),
        }
    }
}

/// One recording's refinements and the aerial image of each.
struct Refined {
    refinements: Vec<Handle<AerialRefinement>>,
    aerials: Vec<Handle<AerialImage>>,
}

/// The nadir chain of one variant while it is being added: its parameters and the nodes added so far.
struct NadirChain<'c, 'a> {
    cx: &'c VariantContext<'a>,
    ortho_base: &'c OrthoParams,
    options: NadirOptions,
    transform_params: TransformParams,
    refine_params: RefineParams,
    control_params: ControlParams,
    /// The frame the aerial rays of the control points are intersected in.
    map_frame: Handle<MapFrameSpec>,
    aerial_rows: AerialRowNodes,
    windows: Vec<Handle<MmWindowMatch>>,
    transforms: Vec<Handle<TransformOutcome>>,
    refinements: Vec<Handle<AerialRefinement>>,
    control: Vec<Handle<RecordingControl>>,
    recordings: Vec<RecordingNadir>,
}

impl<'c, 'a> NadirChain<'c, 'a> {
    /// An empty chain for the variant of `cx`, with its nadir, transform, refine and control parameters and
    /// the map-frame node.
    fn new(
        b: &mut DagBuilder,
        cx: &'c VariantContext<'a>,
        ortho_base: &'c OrthoParams,
    ) -> Result<Self, PipelineError> {
        Ok(NadirChain {
            cx,
            ortho_base,
            options: cx.params(stage::NADIR)?,
            transform_params: cx.params(stage::TRANSFORM)?,
            refine_params: cx.params(stage::REFINE)?,
            control_params: cx.params(stage::CONTROL)?,
            map_frame: b.add(MapFrameStage, "", SummaryParams::default(), cx.snap)?,
            aerial_rows: AerialRowNodes::new(AerialKind::Nadir, cx.snap),
            windows: Vec::new(),
            transforms: Vec::new(),
            refinements: Vec::new(),
            control: Vec::new(),
            recordings: Vec::new(),
        })
    }
}

/// Add the nadir chain for the variant of `cx`.
pub fn add_nadir(
    b: &mut DagBuilder,
    cx: &VariantContext<'_>,
    ortho_base: &OrthoParams,
) -> Result<NadirHandles, PipelineError> {
    let Some(orthos) = cx.items.iter().map(|i| i.ortho).collect::<Option<Vec<_>>>() else {
        return Err(wf_err(format!(
            "{}: the nadir chain needs stage 'ortho' in `stages`",
            cx.wf.path.display()
        )));
    };
    let mut chain = NadirChain::new(b, cx, ortho_base)?;
    let mm_params: MmMatchParams = cx.params(stage::MM_MATCH)?;
    let mut photo_route = match cx.on(stage::CONTROL) {
        true => OrthophotoRoute::new(b, cx.wf, cx.variant, cx.root, cx.snapshot, ortho_base)?,
        false => None,
    };
    let campaign = &cx.snapshot.campaign;
    let overlap = NadirOverlap::new(&campaign.nadir, &campaign.recordings);
    let window_len = if chain.options.triples { 2 } else { 1 };
    let items = cx.items;
    for (i, item) in items.iter().enumerate() {
        let neighbours: Vec<&RecordingItem> = items[i + 1..]
            .iter()
            .take(window_len)
            .take_while(|n| {
                distance_m(item.recording, n.recording) <= chain.options.max_neighbour_distance_m
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
        chain.windows.push(window);
        if let Some(route) = photo_route.as_mut() {
            let handles: Vec<_> = members
                .iter()
                .map(|m| (m.recording, m.row, m.pano_image))
                .collect();
            chain
                .control
                .extend(route.add_recording(b, &handles, window)?);
        }
        if !cx.on(stage::ORTHO_AERIAL) {
            continue;
        }
        let margin_m = chain.options.overlap_margin_m;
        let pairs = chain.add_pairs(b, item, overlap.overlapping(item.recording, margin_m))?;
        let bases: Vec<PairBase> = pairs.iter().map(AerialPair::base).collect();
        let refined = chain.add_refinements(b, pairs, window, &members)?;
        chain.recordings.push(RecordingNadir {
            item: i,
            neighbours: (i + 1..i + members.len()).collect(),
            window,
            pairs: bases,
            control: cx.on(stage::CONTROL).then_some(chain.control.len()),
        });
        if cx.on(stage::CONTROL) {
            let c = chain.add_control(b, &label, window, refined)?;
            chain.control.push(c);
        }
    }
    if let Some(route) = photo_route {
        route.finish(b)?;
    }
    chain.add_summary_and_grade(b)?;
    Ok(NadirHandles {
        windows: chain.windows,
        control: chain.control,
        recordings: chain.recordings,
    })
}

impl NadirChain<'_, '_> {
    /// The recording's control points (thesis 3.4.5.4) from its tie-point `window` and its refinements.
    fn add_control(
        &self,
        b: &mut DagBuilder,
        label: &str,
        window: Handle<MmWindowMatch>,
        refined: Refined,
    ) -> Result<Handle<RecordingControl>, PipelineError> {
        let inputs = (
            window,
            optional_all(&refined.refinements),
            refined.aerials,
            self.map_frame,
        );
        Ok(b.add(ControlStage, label, self.control_params.clone(), inputs)?)
    }

    /// Per nadir image (campaign row index) overlapping `item`: the aerial-oriented ortho (thesis 3.4.5.1)
    /// and, when enabled, the initial transform (3.4.5.2).
    fn add_pairs(
        &mut self,
        b: &mut DagBuilder,
        item: &RecordingItem<'_>,
        overlapping: Vec<usize>,
    ) -> Result<Vec<AerialPair>, PipelineError> {
        let nadir_dir = self.cx.root.join("aerial/nadir");
        let mut pairs = Vec::new();
        for a in overlapping {
            let row = &self.cx.snapshot.campaign.nadir[a];
            let aerial = self.aerial_rows.get_or_add(b, a, row)?;
            let label = pair_label(&item.recording.image_id, &row.image_id);
            let aerial_file = ingest_file(
                b,
                &format!("nadir {}", row.image_id),
                nadir_dir.join(&row.file),
            )?;
            let ortho = b.add(
                OrthoForAerial,
                &label,
                self.ortho_base.clone(),
                (item.row, item.pano_image, aerial, aerial_file),
            )?;
            if !self.cx.on(stage::TRANSFORM) {
                continue;
            }
            let outcome = b.add(
                InitialTransformStage,
                &label,
                self.transform_params.clone(),
                (item.row, ortho, aerial_file, aerial),
            )?;
            pairs.push(AerialPair {
                aerial,
                aerial_file,
                label,
                ortho,
                outcome,
                aerial_id: row.image_id.clone(),
            });
        }
        Ok(pairs)
    }

    /// The recording's transforms checked against each other (`nadir::transform_agreement`), then refined
    /// (thesis 3.4.5.3) against the MM matching `window` of `members` (the recording, then its neighbours).
    /// Returns the recording's refinements with their aerial images.
    fn add_refinements(
        &mut self,
        b: &mut DagBuilder,
        pairs: Vec<AerialPair>,
        window: Handle<MmWindowMatch>,
        members: &[&RecordingItem<'_>],
    ) -> Result<Refined, PipelineError> {
        let mut rec_refinements = Vec::new();
        let mut rec_aerials = Vec::new();
        let outcomes: Vec<Handle<TransformOutcome>> = pairs.iter().map(|p| p.outcome).collect();
        for p in pairs {
            let outcome = b.add(
                TransformAgreementStage,
                &p.label,
                self.transform_params.clone(),
                (p.outcome, outcomes.clone()),
            )?;
            self.transforms.push(outcome);
            if !self.cx.on(stage::REFINE) {
                continue;
            }
            let inputs = (p.ortho, p.aerial_file, p.aerial, outcome, window);
            let refined = match self.options.matcher {
                Matcher::PhaseCorrelation => {
                    // The neighbours' orthos for this aerial image (the same nodes their own pairs use), in
                    // the window's neighbour order, for the parallax check.
                    let neighbour_orthos = members[1..]
                        .iter()
                        .map(|n| {
                            b.add(
                                OrthoForAerial,
                                &pair_label(&n.recording.image_id, &p.aerial_id),
                                self.ortho_base.clone(),
                                (n.row, n.pano_image, p.aerial, p.aerial_file),
                            )
                        })
                        .collect::<Result<Vec<_>, _>>()?;
                    let (o, f, a, t, w) = inputs;
                    b.add(
                        RefineStage,
                        &p.label,
                        self.refine_params.clone(),
                        (o, f, a, t, w, neighbour_orthos),
                    )?
                }
                Matcher::Baseline => {
                    let params: BaselineParams = self.cx.params(stage::BASELINE)?;
                    b.add(BaselineStage, &p.label, params, inputs)?
                }
            };
            rec_refinements.push((p.label, refined));
            rec_aerials.push(p.aerial);
        }
        let rec_refinements = self.add_peak_support(b, rec_refinements)?;
        self.refinements.extend(&rec_refinements);
        Ok(Refined {
            refinements: rec_refinements,
            aerials: rec_aerials,
        })
    }

    /// The recording's refinements (label, node) without their weak peaks where the recording has strong ones,
    /// and without tie points located in too few images where it has corroborated ones (`nadir::peak_support`);
    /// unchanged, with no node added, when `[control] strong_peak` is 0 and `min_aerial_images` 1.
    fn add_peak_support(
        &self,
        b: &mut DagBuilder,
        refinements: Vec<(String, Handle<AerialRefinement>)>,
    ) -> Result<Vec<Handle<AerialRefinement>>, PipelineError> {
        let all: Vec<Handle<AerialRefinement>> = refinements.iter().map(|(_, r)| *r).collect();
        let p = &self.control_params;
        if !(p.strong_peak > 0.0) && p.min_aerial_images <= 1 {
            return Ok(all);
        }
        let mut out = Vec::with_capacity(all.len());
        for (label, refined) in refinements {
            out.push(b.add(
                PeakSupportStage,
                &label,
                self.control_params.clone(),
                (refined, optional_all(&all)),
            )?);
        }
        Ok(out)
    }

    /// The global `nadir` summary and, on campaigns with `truth/`, the evaluation node `grade_nadir`.
    fn add_summary_and_grade(&self, b: &mut DagBuilder) -> Result<(), PipelineError> {
        let (cx, snap) = (self.cx, self.cx.snap);
        if cx.on(stage::NADIR) {
            let summary = b.add(
                SummarizeNadir,
                "",
                SummaryParams::default(),
                (
                    snap,
                    optional_all(&self.windows),
                    optional_all(&self.transforms),
                    optional_all(&self.refinements),
                    optional_all(&self.control),
                ),
            )?;
            b.metrics(summary, "nadir", |s: &NadirSummary| s.metrics());
        }
        if let Some(truth_files) = cx.truth_files(stage::GRADE_NADIR, &[TRUTH_AERIAL_NADIR]) {
            let grade = b.add(
                GradeNadir,
                "",
                SummaryParams::default(),
                (
                    snap,
                    truth_files,
                    cx.items.iter().map(|i| i.pano.clone()).collect::<Vec<_>>(),
                    self.windows.clone(),
                    self.refinements.clone(),
                    self.control.clone(),
                ),
            )?;
            b.metrics(grade, "nadir", |g: &NadirGrade| grade_metrics(g));
        }
        Ok(())
    }
}

/// The item label of a (recording × nadir image) node; the neighbours' orthos for the parallax check reuse the
/// neighbour's own pair nodes through it.
fn pair_label(recording_id: &str, aerial_id: &str) -> String {
    format!("rec {recording_id} × {aerial_id}")
}

/// What the second registration pass hands to the final adjustment.
pub struct SecondPass {
    /// The aerial control of every recording after the second pass (the first pass's control for the
    /// recordings it registered, found again in the cache), in the order of `NadirHandles::control`.
    pub control: Vec<Handle<RecordingControl>>,
    /// The counts of both passes.
    pub passes: Handle<RegistrationPasses>,
}

/// The second registration pass around the first adjustment `report` (`skytie_stages::adjustment::second_pass`):
/// per recording with a window, its shift (zero when the first pass registered it), its window and
/// aerial-oriented ortho images translated by it, then the initial transform, the agreement check, the
/// refinement and the control points again, with the normal search windows; the refinement's parallax check
/// reads the neighbours' first-pass ortho images with the window's untranslated neighbour views. The
/// overlapping nadir images are
/// the first pass's (`overlap_margin_m` around the recorded position; an image's footprint is far larger than
/// the shift).
pub fn add_second_pass(
    b: &mut DagBuilder,
    cx: &VariantContext<'_>,
    ortho_base: &OrthoParams,
    nadir: &NadirHandles,
    report: Handle<AdjustReport>,
) -> Result<SecondPass, PipelineError> {
    let mut chain = NadirChain::new(b, cx, ortho_base)?;
    let mut control = nadir.control.clone();
    let (mut first, mut second, mut shifts) = (Vec::new(), Vec::new(), Vec::new());
    for rec in &nadir.recordings {
        let (Some(ci), true) = (rec.control, cx.on(stage::TRANSFORM)) else {
            continue;
        };
        let item = &cx.items[rec.item];
        let label = format!("rec {} pass 2", item.recording.image_id);
        let params = PassPriorParams {
            image_id: item.recording.image_id.clone(),
            index_hint: rec.item,
        };
        let shift = b.add(
            PassPrior,
            &label,
            params,
            (report, nadir.control[ci].optional()),
        )?;
        let window = Shift::add(b, &label, rec.window, shift)?;
        let row = Shift::add(b, &label, item.row, shift)?;
        let mut pairs = Vec::new();
        for p in &rec.pairs {
            let pair_label = format!(
                "{} pass 2",
                pair_label(&item.recording.image_id, &p.aerial_id)
            );
            let ortho = Shift::add(b, &pair_label, p.ortho, shift)?;
            let outcome = b.add(
                InitialTransformStage,
                &pair_label,
                chain.transform_params.clone(),
                (row, ortho, p.aerial_file, p.aerial),
            )?;
            pairs.push(AerialPair {
                aerial: p.aerial,
                aerial_file: p.aerial_file,
                label: pair_label,
                ortho,
                outcome,
                aerial_id: p.aerial_id.clone(),
            });
        }
        let members: Vec<&RecordingItem> = std::iter::once(rec.item)
            .chain(rec.neighbours.iter().copied())
            .map(|i| &cx.items[i])
            .collect();
        let refined = chain.add_refinements(b, pairs, window, &members)?;
        let c = chain.add_control(b, &label, window, refined)?;
        first.push(nadir.control[ci]);
        second.push(c);
        shifts.push(shift);
        control[ci] = c;
    }
    let passes = b.add(
        CountPasses,
        "",
        SummaryParams::default(),
        (
            optional_all(&first),
            optional_all(&second),
            optional_all(&shifts),
        ),
    )?;
    b.metrics(passes, "registration_passes", passes_metrics);
    Ok(SecondPass { control, passes })
}

//! `peak_support`: per (recording × nadir image), the refinement without its weak peaks when the recording has
//! strong ones in any of its nadir images, and without its tie points located in too few images when the
//! recording has better corroborated ones (`skytie_stages::nadir::peak_support`, `[control] strong_peak`,
//! `min_aerial_images`). The control points, the nadir summary and its grade read these refinements.

use crate::dag::{Handle, InputsOf, NodeCtx, Optional, RunResult, Stage};
use skytie_stages::nadir::control_points::ControlParams;
use skytie_stages::nadir::peak_support::keep_supported;
use skytie_stages::nadir::AerialRefinement;

/// The peak-support node. Inputs: this pair's refinement, then all refinements of the same recording (a
/// failed one is left out).
pub struct PeakSupportStage;

impl Stage for PeakSupportStage {
    crate::nodes::stage_types!(skytie_stages::nadir::peak_support::STAGE, ControlParams => AerialRefinement,
        inputs: (Handle<AerialRefinement>, Vec<Optional<AerialRefinement>>));

    fn run(&self, p: &ControlParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (own, all) = inputs;
        let refs: Vec<&AerialRefinement> = all.iter().filter_map(|r| r.as_deref()).collect();
        Ok(keep_supported(
            &own,
            &refs,
            p.strong_peak,
            p.min_aerial_images,
        ))
    }
}

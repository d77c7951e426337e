//! The nodes of the second registration pass around the adjusted trajectory
//! (`skytie_stages::adjustment::second_pass`): per recording its shift from the first adjustment
//! (`pass_prior`), its row, tie-point window and aerial-oriented ortho images translated by it (`pass_row`, `pass_window`, `pass_ortho`), and the counts of both passes
//! (`registration_passes`). A recording the first pass registered gets a zero shift, so its translated inputs
//! equal the first pass's and every node below them is found in the cache. The oblique chain's second pass
//! shifts every recording by its whole correction (`pass_trajectory`).

use crate::codec::Artifact;
use crate::dag::{BuildError, DagBuilder, Handle, InputsOf, NodeCtx, Optional, RunResult, Stage};
use crate::nodes::adjust::adjustment::{AdjustReport, Verdict};
use crate::nodes::campaign::summary::SummaryParams;
use skytie_stages::adjustment::second_pass::{
    pass_shift, registered, trajectory_shift, PassShift, RecordingRef, RegistrationPasses,
    Shiftable, PASSES_STAGE, PRIOR_STAGE, TRAJECTORY_PRIOR_STAGE,
};
use skytie_stages::nadir::RecordingControl;
use std::marker::PhantomData;

crate::serde_artifact!(PassShift, RegistrationPasses);

skytie_stages::params! {
    /// Parameters of a recording's second-pass shift (set by the pipeline).
    pub struct PassPriorParams {
        /// The recording's `image_id`.
        image_id: String = String::new();
        /// The recording's position in the campaign: where the lookup in the first adjustment starts.
        index_hint: usize = 0;
    }
}

impl PassPriorParams {
    fn recording(&self) -> RecordingRef<'_> {
        RecordingRef {
            image_id: &self.image_id,
            index_hint: self.index_hint,
        }
    }
}

/// A recording's shift for the second pass. Inputs: the first adjustment and the recording's own first-pass
/// control (absent when its node failed: then the recording counts as not registered).
pub struct PassPrior;

impl Stage for PassPrior {
    crate::nodes::stage_types!(PRIOR_STAGE, PassPriorParams => PassShift,
        inputs: (Handle<AdjustReport>, Optional<RecordingControl>));

    fn run(&self, p: &PassPriorParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (report, control) = inputs;
        let delivered = report.verdict() == Verdict::Corrected;
        Ok(pass_shift(
            p.recording(),
            &report.run.recordings,
            registered(control.as_deref()),
            delivered,
        ))
    }
}

/// A recording's shift for the oblique chain's second pass: its whole correction by the first adjustment when
/// that was delivered. Input: the first adjustment.
pub struct TrajectoryPrior;

impl Stage for TrajectoryPrior {
    crate::nodes::stage_types!(TRAJECTORY_PRIOR_STAGE, PassPriorParams => PassShift,
        inputs: Handle<AdjustReport>);

    fn run(&self, p: &PassPriorParams, report: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let delivered = report.verdict() == Verdict::Corrected;
        Ok(trajectory_shift(
            p.recording(),
            &report.run.recordings,
            delivered,
        ))
    }
}

/// One input of a recording's registration translated by its shift: its tie-point window, its row (the second
/// pass's initial transform reads it) or an aerial-oriented ortho image. Each kind is its own stage.
pub struct Shift<T>(PhantomData<fn() -> T>);

impl<T> Shift<T> {
    /// The stage that translates a `T`.
    pub const fn new() -> Self {
        Self(PhantomData)
    }
}

impl<T: Shiftable + Artifact> Shift<T> {
    /// Adds the node that translates `input` by `shift` (item `label`).
    pub fn add(
        b: &mut DagBuilder,
        label: &str,
        input: Handle<T>,
        shift: Handle<PassShift>,
    ) -> Result<Handle<T>, BuildError> {
        b.add(Self::new(), label, SummaryParams::default(), (input, shift))
    }
}

impl<T> Default for Shift<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Shiftable + Artifact> Stage for Shift<T> {
    crate::nodes::stage_types!(T::STAGE, SummaryParams => T, inputs: (Handle<T>, Handle<PassShift>));

    fn run(&self, _: &SummaryParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (item, shift) = inputs;
        Ok(item.shifted(&shift))
    }
}

/// The counts of both passes. Inputs: per recording with a window, its first-pass control, second-pass
/// control and shift (parallel lists).
pub struct CountPasses;

impl Stage for CountPasses {
    crate::nodes::stage_types!(PASSES_STAGE, SummaryParams => RegistrationPasses,
        inputs: (Vec<Optional<RecordingControl>>, Vec<Optional<RecordingControl>>, Vec<Optional<PassShift>>));

    fn run(&self, _: &SummaryParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (first, second, shifts) = inputs;
        let first: Vec<_> = first.iter().map(|c| c.as_deref()).collect();
        let second: Vec<_> = second.iter().map(|c| c.as_deref()).collect();
        let shifts: Vec<_> = shifts.iter().map(|s| s.as_deref()).collect();
        Ok(RegistrationPasses::count(&first, &second, &shifts))
    }
}

/// The `registration_passes` metrics.
pub fn passes_metrics(p: &RegistrationPasses) -> serde_json::Value {
    serde_json::to_value(p).unwrap_or_default()
}

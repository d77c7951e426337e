//! `control`: per recording, its window's tie points gathered across all overlapping nadir images, checked for
//! consistency and triangulated from the aerial images → aerial control points (thesis 3.4.5.4,
//! `skytie_stages::nadir::control_points`).

use crate::dag::{Handle, InputsOf, NodeCtx, Optional, RunResult, Stage, StageError};
use skytie_stages::campaign::AerialImage;
use skytie_stages::crs::{MapFrame, MapFrameSpec};
use skytie_stages::nadir::control_points::{aerial_control_points_in, ControlParams};
use skytie_stages::nadir::{AerialRefinement, MmWindowMatch, RecordingControl};

crate::serde_artifact!(RecordingControl);

/// The aerial-control-point node; refinements and aerial rows are parallel lists; the rays are intersected in the
/// campaign's frame (`map_frame`).
pub struct ControlStage;

impl Stage for ControlStage {
    crate::nodes::stage_types!(skytie_stages::nadir::control_points::STAGE, ControlParams => RecordingControl,
        inputs: (Handle<MmWindowMatch>, Vec<Optional<AerialRefinement>>, Vec<Handle<AerialImage>>, Handle<MapFrameSpec>));

    fn run(&self, p: &ControlParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (window, refinements, aerials, frame) = inputs;
        let frame = MapFrame::from_spec(&frame)
            .map_err(|e| StageError::new(format!("the campaign's frame: {e}")))?;
        if refinements.len() != aerials.len() {
            return Err(StageError::new(
                "internal: control needs one aerial row per refinement",
            ));
        }
        let pairs: Vec<(&AerialImage, &AerialRefinement)> = aerials
            .iter()
            .map(|a| a.as_ref())
            .zip(&refinements)
            .filter_map(|(a, r)| r.as_deref().map(|r| (a, r)))
            .collect();
        Ok(RecordingControl {
            recording_id: window.recording_id.clone(),
            points: aerial_control_points_in(&window, &pairs, p, &frame),
        })
    }
}

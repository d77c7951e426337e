//! `orthophoto_points`: hands an `orthophoto` node's control points on to the adjustment, like the `control`
//! node's.

use crate::dag::{Handle, NodeCtx, Stage, StageError};
use crate::nodes::campaign::summary::SummaryParams;
use skytie_stages::nadir::RecordingControl;
use skytie_stages::orthophoto::OrthophotoControl;
use std::sync::Arc;

/// The control points of an `orthophoto` node, as the adjustment takes them.
pub struct OrthophotoPoints;

impl Stage for OrthophotoPoints {
    crate::nodes::stage_types!(named "orthophoto_points" version "1", SummaryParams => RecordingControl,
        inputs: Handle<OrthophotoControl>);

    fn run(
        &self,
        _: &SummaryParams,
        c: Arc<OrthophotoControl>,
        _: &NodeCtx,
    ) -> Result<RecordingControl, StageError> {
        Ok(c.control.clone())
    }
}

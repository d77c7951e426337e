//! `grade_adjust`: evaluation only — recorded and adjusted recording positions vs a synthetic campaign's
//! `truth/recordings.csv` (`adjust.<config>.recordings.{before,after}.{rmse_2d,rmse_3d,max_2d}`).
//! Added only when `truth/recordings.csv` exists.

use crate::dag::{Handle, InputsOf, NodeCtx, RawFile, RunResult, Stage, StageError};
use crate::nodes::adjust::adjustment::AdjustReport;
use crate::nodes::campaign::summary::SummaryParams;
use serde::{Deserialize, Serialize};
use skytie_stages::adjustment::trajectory_errors::{trajectory_errors, PositionErrors};
use skytie_stages::campaign::read_recordings_csv;
use skytie_stages::params::StageId;

/// The grade: errors before (recorded) and after (adjusted).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AdjustGrade {
    pub label: String,
    pub before: PositionErrors,
    pub after: PositionErrors,
}
crate::serde_artifact!(AdjustGrade);

impl AdjustGrade {
    /// `adjust.<config>.recordings` metrics.
    pub fn metrics(&self) -> serde_json::Value {
        serde_json::json!({ self.label.clone(): { "recordings": {
            "before": self.before, "after": self.after,
        }}})
    }
}

/// The stage's identity in cache keys (the computation lives in this node); bump the version whenever its
/// output for the same inputs and parameters changes.
pub const STAGE: StageId = StageId::new("grade_adjust", "1");

/// The adjustment grading node.
pub struct GradeAdjust;

impl Stage for GradeAdjust {
    crate::nodes::stage_types!(STAGE, SummaryParams => AdjustGrade, inputs: (RawFile, Handle<AdjustReport>));

    fn run(&self, _: &SummaryParams, inputs: InputsOf<Self>, _: &NodeCtx) -> RunResult<Self> {
        let (truth_file, report) = inputs;
        let (truth, problems) = read_recordings_csv(&truth_file.path);
        if let Some(p) = problems.first() {
            return Err(StageError::new(format!("truth is unreadable: {p}")));
        }
        let errors = trajectory_errors(&report.run, &truth);
        Ok(AdjustGrade {
            label: report.run.config.sources.label().to_string(),
            before: errors.before,
            after: errors.after,
        })
    }
}

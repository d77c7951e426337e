//! `grade_adjust`: evaluation only — recorded and adjusted recording positions vs a synthetic campaign's
//! `truth/recordings.csv` (`adjust.<config>.recordings.{before,after}.{rmse_2d,rmse_3d,max_2d}`).
//! Added only when `truth/recordings.csv` exists.

use crate::dag::{Handle, NodeCtx, RawFile, RawFileValue, Stage, StageError};
use crate::nodes::adjust::adjustment::AdjustReport;
use crate::nodes::campaign::summary::SummaryParams;
use serde::{Deserialize, Serialize};
use skytie_stages::campaign::read_recordings_csv;
use skytie_stages::params::StageId;
use std::collections::HashMap;
use std::sync::Arc;

/// Position errors of a set of recordings vs truth, metres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PositionErrors {
    pub rmse_2d: f64,
    pub rmse_3d: f64,
    pub max_2d: f64,
    pub count: usize,
}

impl PositionErrors {
    fn of(errors: &[[f64; 3]]) -> Self {
        if errors.is_empty() {
            return Self::default();
        }
        let n = errors.len() as f64;
        let h2: Vec<f64> = errors.iter().map(|e| e[0] * e[0] + e[1] * e[1]).collect();
        Self {
            rmse_2d: (h2.iter().sum::<f64>() / n).sqrt(),
            rmse_3d: (errors
                .iter()
                .map(|e| e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
                .sum::<f64>()
                / n)
                .sqrt(),
            max_2d: h2.iter().cloned().fold(0.0, f64::max).sqrt(),
            count: errors.len(),
        }
    }
}

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
pub const STAGE: StageId = StageId {
    name: "grade_adjust",
    version: "1",
};

/// The adjustment grading node.
pub struct GradeAdjust;

impl Stage for GradeAdjust {
    const NAME: &'static str = STAGE.name;
    const VERSION: &'static str = STAGE.version;
    type Params = SummaryParams;
    type Output = AdjustGrade;
    type Inputs = (RawFile, Handle<AdjustReport>);

    fn run(
        &self,
        _: &SummaryParams,
        (truth_file, report): (RawFileValue, Arc<AdjustReport>),
        _: &NodeCtx,
    ) -> Result<AdjustGrade, StageError> {
        let (truth, problems) = read_recordings_csv(&truth_file.path);
        if let Some(p) = problems.first() {
            return Err(StageError::new(format!("truth is unreadable: {p}")));
        }
        let truth: HashMap<&str, [f64; 3]> = truth
            .iter()
            .map(|r| (r.image_id.as_str(), [r.x, r.y, r.z]))
            .collect();
        let (mut before, mut after) = (Vec::new(), Vec::new());
        for r in &report.run.recordings {
            if let Some(t) = truth.get(r.image_id.as_str()) {
                let d = |p: [f64; 3]| [p[0] - t[0], p[1] - t[1], p[2] - t[2]];
                before.push(d(r.recorded_world));
                after.push(d(r.adjusted_world));
            }
        }
        Ok(AdjustGrade {
            label: report.run.config.sources.label().to_string(),
            before: PositionErrors::of(&before),
            after: PositionErrors::of(&after),
        })
    }
}

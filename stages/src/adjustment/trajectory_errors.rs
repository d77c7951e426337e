//! Recording positions against the truth (synthetic campaigns only: the pipeline never
//! reads `truth/`, evaluation code passes the truth rows in): RMSE 2-D and 3-D and the largest 2-D error of
//! the recorded and of the adjusted positions, for metrics `adjust.<config>.recordings.{before,after}`.

use super::from_correspondences::AdjustmentRun;
use crate::campaign::Recording;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Position errors of a set of recordings, metres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PositionErrors {
    pub rmse_2d: f64,
    pub rmse_3d: f64,
    pub max_2d: f64,
    /// Recordings compared.
    pub count: usize,
}

/// Before (recorded) and after (adjusted) errors against the truth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TrajectoryErrors {
    pub before: PositionErrors,
    pub after: PositionErrors,
    /// Adjusted recordings without a truth row (by `image_id`).
    pub missing_truth: usize,
}

fn accumulate(errors: &[[f64; 3]]) -> PositionErrors {
    if errors.is_empty() {
        return PositionErrors::default();
    }
    let (mut s2, mut s3, mut max2) = (0.0, 0.0, 0.0f64);
    for e in errors {
        let d2 = e[0] * e[0] + e[1] * e[1];
        s2 += d2;
        s3 += d2 + e[2] * e[2];
        max2 = max2.max(d2.sqrt());
    }
    let n = errors.len() as f64;
    PositionErrors {
        rmse_2d: (s2 / n).sqrt(),
        rmse_3d: (s3 / n).sqrt(),
        max_2d: max2,
        count: errors.len(),
    }
}

/// Errors of the run's recorded and adjusted positions against `truth` (matched by `image_id`).
pub fn trajectory_errors(run: &AdjustmentRun, truth: &[Recording]) -> TrajectoryErrors {
    let by_id: HashMap<&str, &Recording> = truth.iter().map(|t| (t.image_id.as_str(), t)).collect();
    let mut before = Vec::with_capacity(run.recordings.len());
    let mut after = Vec::with_capacity(run.recordings.len());
    let mut missing = 0;
    for r in &run.recordings {
        let Some(t) = by_id.get(r.image_id.as_str()) else {
            missing += 1;
            continue;
        };
        let t = [t.x, t.y, t.z];
        before.push([0, 1, 2].map(|k| r.recorded_world[k] - t[k]));
        after.push([0, 1, 2].map(|k| r.adjusted_world[k] - t[k]));
    }
    TrajectoryErrors {
        before: accumulate(&before),
        after: accumulate(&after),
        missing_truth: missing,
    }
}

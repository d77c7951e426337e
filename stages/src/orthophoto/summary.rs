//! The orthophoto route's counts over a campaign (for `metrics.json`): recordings registered or rejected
//! (with the reasons), tie points tried and located, control points and where their heights came from.

use super::control::OrthophotoControl;
use crate::nadir::TransformOutcome;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Counts of the orthophoto route.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OrthophotoSummary {
    /// Recordings the route ran for (whose node did not fail).
    pub recordings: usize,
    /// Recordings whose `orthophoto` node failed (counted by the engine too).
    pub failed: usize,
    pub registered: usize,
    /// Rejected registrations by reason (the words with numbers in a reason stripped, so that equal causes count
    /// together).
    pub rejected: BTreeMap<String, usize>,
    /// Median registration offset of the registered recordings, m.
    pub median_offset_m: Option<f64>,
    pub tie_points_tried: usize,
    pub tie_points_located: usize,
    pub control_points: usize,
    pub height_from_dtm: usize,
    /// Control points whose height is the MM ground estimate (no DTM, or none at the point).
    pub height_from_mm: usize,
}

/// The reason without its words that hold numbers ("58 matches, a consensus of 5 inliers < 6" → "matches, a
/// consensus of inliers <").
fn reason_kind(reason: &str) -> String {
    reason
        .split_whitespace()
        .filter(|w| !w.chars().any(|c| c.is_ascii_digit()))
        .collect::<Vec<_>>()
        .join(" ")
}

impl OrthophotoSummary {
    /// The counts over `results` (`None`: a failed node).
    pub fn of(results: &[Option<&OrthophotoControl>]) -> Self {
        let mut s = Self::default();
        let mut offsets = Vec::new();
        for r in results {
            let Some(r) = r else {
                s.failed += 1;
                continue;
            };
            s.recordings += 1;
            match &r.transform {
                TransformOutcome::Accepted(t) => {
                    s.registered += 1;
                    offsets.push(t.centre_offset_m);
                }
                TransformOutcome::Rejected { reason, .. } => {
                    *s.rejected.entry(reason_kind(reason)).or_default() += 1;
                }
            }
            s.tie_points_tried += r.refinement.tried;
            s.tie_points_located += r.refinement.matches.len();
            s.control_points += r.control.points.len();
            s.height_from_dtm += r.height_from_dtm;
            s.height_from_mm += r.height_from_mm;
        }
        offsets.sort_by(f64::total_cmp);
        s.median_offset_m = offsets.get(offsets.len() / 2).copied();
        s
    }

    /// `metrics.json` form.
    pub fn metrics(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or_default()
    }
}

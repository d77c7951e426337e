//! Counts of one run of the nadir pipeline (the `nadir.*` metrics that need no truth): MM pairs and
//! how they were related, MM tie points, initial transforms accepted/rejected, MM–aerial correspondences,
//! aerial control points. Truth-based grades live in `grading.rs`.

use super::registration::{
    AerialRefinement, MmWindowMatch, PairMethod, RecordingControl, RefinementMisses,
    TransformOutcome,
};
use crate::params::StageId;
use crate::ratio::ratio_or_zero;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("nadir", "7");

/// See the module documentation. Counts, not grades.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NadirSummary {
    pub recordings: usize,
    /// Adjacent pairs matched (detecting recording → neighbour) and how (thesis 3.4.4.2–3).
    pub mm_pairs: usize,
    pub mm_pairs_kaze: usize,
    pub mm_pairs_fallback: usize,
    /// Triangulated MM tie points (2- or 3-view).
    pub mm_tie_points: usize,
    pub mm_tie_points_3view: usize,
    /// (recording, nadir image) pairs tried / with an accepted initial transform (thesis 3.4.5.2).
    pub transforms_tried: usize,
    pub transforms_accepted: usize,
    /// Rejection reasons as metrics keys (see `reason_class`) → count.
    pub transforms_rejected: BTreeMap<String, usize>,
    /// MM tie point × aerial image correspondences (as Table 3-1 counts them).
    pub tie_points: usize,
    /// Tie points × aerial images not located or not kept, by reason.
    pub misses: RefinementMisses,
    /// Recordings with at least one MM–aerial correspondence.
    pub recordings_with_aerial: usize,
    /// Mean number of distinct aerial images with correspondences per such recording.
    pub mean_aerial_images_per_recording: f64,
    /// Aerial control points triangulated from ≥ 2 aerial images / located in exactly one.
    pub control_points: usize,
    pub single_aerial_points: usize,
}

/// A rejection reason as a metrics key: numbers replaced by `n`, lower case, words joined by `_`
/// ("centre offset 2.3 m > 1.5 m" → "centre_offset_n_m_n_m").
fn reason_class(reason: &str) -> String {
    let words: Vec<String> = reason
        .split_whitespace()
        .map(|w| {
            if w.chars().any(|c| c.is_ascii_digit()) {
                "n".to_string()
            } else {
                w.chars()
                    .filter(|c| c.is_alphanumeric())
                    .collect::<String>()
                    .to_lowercase()
            }
        })
        .filter(|w| !w.is_empty())
        .collect();
    if words.is_empty() {
        "other".into()
    } else {
        words.join("_")
    }
}

impl NadirSummary {
    /// Count everything. `recordings` is the campaign's number of recordings.
    pub fn from_parts(
        recordings: usize,
        windows: &[&MmWindowMatch],
        transforms: &[&TransformOutcome],
        refinements: &[&AerialRefinement],
        control: &[&RecordingControl],
    ) -> Self {
        let mut s = NadirSummary {
            recordings,
            ..Default::default()
        };
        for w in windows {
            for p in &w.pairs {
                s.mm_pairs += 1;
                match p.method {
                    PairMethod::Kaze => s.mm_pairs_kaze += 1,
                    PairMethod::Fallback { .. } => s.mm_pairs_fallback += 1,
                }
            }
            s.mm_tie_points += w.tie_points.len();
            s.mm_tie_points_3view += w
                .tie_points
                .iter()
                .filter(|t| t.observations.len() >= 3)
                .count();
        }
        for t in transforms {
            s.transforms_tried += 1;
            match t {
                TransformOutcome::Accepted(_) => s.transforms_accepted += 1,
                TransformOutcome::Rejected { reason, .. } => {
                    *s.transforms_rejected
                        .entry(reason_class(reason))
                        .or_default() += 1
                }
            }
        }
        let mut images_per_recording: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
        for r in refinements {
            s.tie_points += r.matches.len();
            s.misses.add(&r.misses);
            if !r.matches.is_empty() {
                images_per_recording
                    .entry(r.recording_id.as_str())
                    .or_default()
                    .insert(r.aerial_id.as_str());
            }
        }
        s.recordings_with_aerial = images_per_recording.len();
        if s.recordings_with_aerial > 0 {
            s.mean_aerial_images_per_recording = images_per_recording
                .values()
                .map(|v| v.len())
                .sum::<usize>() as f64
                / s.recordings_with_aerial as f64;
        }
        for c in control {
            for p in &c.points {
                if p.point_world.is_some() {
                    s.control_points += 1;
                } else {
                    s.single_aerial_points += 1;
                }
            }
        }
        s
    }

    /// The `nadir` metrics section.
    pub fn metrics(&self) -> serde_json::Value {
        let frac = ratio_or_zero(self.recordings_with_aerial, self.recordings);
        let mut m = serde_json::json!({
            "recordings": self.recordings,
            "recordings_with_aerial": self.recordings_with_aerial,
            "recordings_with_aerial_fraction": frac,
            "tie_points": self.tie_points,
            "mean_aerial_images_per_recording": self.mean_aerial_images_per_recording,
            "control_points": self.control_points,
            "single_aerial_points": self.single_aerial_points,
            "mm_pairs": self.mm_pairs,
            "mm_pairs_kaze": self.mm_pairs_kaze,
            "mm_pairs_fallback": self.mm_pairs_fallback,
            "mm_tie_points": self.mm_tie_points,
            "mm_tie_points_3view": self.mm_tie_points_3view,
            "transforms_tried": self.transforms_tried,
            "transforms_accepted": self.transforms_accepted,
            "transforms_rejected": self.transforms_rejected,
        });
        if let Some(map) = m.as_object_mut() {
            self.misses.put_metrics(map);
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::reason_class;

    #[test]
    fn reason_classes_drop_numbers() {
        assert_eq!(
            reason_class("centre offset 2.3 m > 1.5 m"),
            "centre_offset_n_m_n_m"
        );
        assert_eq!(
            reason_class("12 matches, RANSAC found 3 inliers < 6"),
            "n_matches_ransac_found_n_inliers_n"
        );
        assert_eq!(reason_class(""), "other");
    }
}

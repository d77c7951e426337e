//! Weak evidence is kept only where a recording has nothing better: weak correlation peaks (an addition to the
//! peak test of thesis 3.4.5.3) and, optionally, tie points located in too few aerial images.
//!
//! The refinement accepts a location when its phase-correlation peak reaches `[refine] min_peak`. A low
//! threshold lets recordings whose street changed since the flight, or whose templates lie beside the vehicle,
//! find aerial evidence at all; but the weakest accepted peaks are also the least precise: on the demo
//! development seeds 1–3 (five error profiles) 10.5 % of the locations with a peak of 0.70–0.72 lie more than
//! one aerial pixel from the truth, 7 % at 0.72–0.75, 3.7 % at 0.75–0.80 and under 1 % above 0.80.
//!
//! So a peak below `strong_peak` is kept only when the recording has no location at or above `strong_peak` in
//! any of its nadir images: a recording with strong evidence is registered by it alone, and one without keeps
//! its weak evidence rather than none. The test looks at all nadir images of the recording, because one
//! image's strong locations make another image's weak ones of the same recording unnecessary. Dropped
//! locations are counted with the refinement's other weak peaks (`RefinementMisses::weak_peaks`).
//!
//! The same idea for corroboration (`min_aerial_images`, off by default): a tie point located in one nadir
//! image has nothing to check it against, and two images that are off alike (an error on the MM side moves the
//! corner in every image) pass the control points' multi-image check. A tie point located in fewer images than
//! `min_aerial_images` is left out when another tie point of its recording reaches that count (counted as
//! `RefinementMisses::unconfirmed`); locations the peak rule drops do not count.

use super::registration::{AerialMatch, AerialRefinement};
use crate::params::StageId;
use std::collections::HashMap;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("peak_support", "1");

/// `own` with the two rules of the module applied against `recording` (the recording's refinements in all its
/// nadir images; `own` may be among them, other recordings' are ignored). The peak rule: when any of them has
/// a location at or above `strong_peak`, `own`'s locations below it are dropped (`misses.weak_peaks`);
/// `strong_peak ≤ 0` disables it. The image-count rule, on the locations the peak rule keeps: a tie point
/// located in fewer than `min_aerial_images` of the recording's nadir images is dropped when another tie point
/// of the recording reaches that count (`misses.unconfirmed`); `min_aerial_images ≤ 1` disables it.
pub fn keep_supported(
    own: &AerialRefinement,
    recording: &[&AerialRefinement],
    strong_peak: f64,
    min_aerial_images: usize,
) -> AerialRefinement {
    let mut out = own.clone();
    let mut mine: Vec<&AerialRefinement> = recording
        .iter()
        .copied()
        .filter(|r| r.recording_id == own.recording_id && r.aerial_id != own.aerial_id)
        .collect();
    mine.push(own);
    let has_strong = strong_peak > 0.0
        && mine
            .iter()
            .flat_map(|r| &r.matches)
            .any(|m| m.observation.score >= strong_peak);
    let kept_peak = |m: &AerialMatch| !has_strong || m.observation.score >= strong_peak;
    let before = out.matches.len();
    out.matches.retain(|m| kept_peak(m));
    out.misses.weak_peaks += before - out.matches.len();
    if min_aerial_images <= 1 {
        return out;
    }
    // Per tie point: in how many of the recording's nadir images it is located (one refinement per image).
    let mut images: HashMap<&str, usize> = HashMap::new();
    for r in &mine {
        let mut seen: Vec<&str> = r
            .matches
            .iter()
            .filter(|m| kept_peak(m))
            .map(|m| m.tie_point_id.as_str())
            .collect();
        seen.sort_unstable();
        seen.dedup();
        for id in seen {
            *images.entry(id).or_default() += 1;
        }
    }
    if !images.values().any(|&n| n >= min_aerial_images) {
        return out;
    }
    let before = out.matches.len();
    out.matches
        .retain(|m| images.get(m.tie_point_id.as_str()).copied().unwrap_or(0) >= min_aerial_images);
    out.misses.unconfirmed += before - out.matches.len();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refinement(recording: &str, aerial: &str, scores: &[f64]) -> AerialRefinement {
        let mut r = AerialRefinement::empty(recording, aerial);
        r.tried = scores.len();
        r.matches = scores
            .iter()
            .enumerate()
            .map(|(i, &s)| {
                AerialMatch::shifted(
                    &format!("{recording}#{i}"),
                    aerial,
                    (10.0, 10.0),
                    (0.0, 0.0),
                    s,
                )
            })
            .collect();
        r
    }

    fn scores(r: &AerialRefinement) -> Vec<f64> {
        r.matches.iter().map(|m| m.observation.score).collect()
    }

    #[test]
    fn weak_peaks_go_when_another_image_of_the_recording_has_a_strong_one() {
        let a = refinement("pano_1", "n1", &[0.71, 0.73]);
        let b = refinement("pano_1", "n2", &[0.72, 0.81]);
        let kept = keep_supported(&a, &[&a, &b], 0.75, 1);
        assert!(kept.matches.is_empty());
        assert_eq!(kept.misses.weak_peaks, 2);
        let kept_b = keep_supported(&b, &[&a, &b], 0.75, 1);
        assert_eq!(scores(&kept_b), vec![0.81]);
        assert_eq!(kept_b.misses.weak_peaks, 1);
    }

    #[test]
    fn a_recording_with_only_weak_peaks_keeps_them() {
        let a = refinement("pano_1", "n1", &[0.71, 0.73]);
        let b = refinement("pano_1", "n2", &[0.74]);
        // Another recording's strong peak says nothing about this one.
        let other = refinement("pano_2", "n1", &[0.95]);
        let kept = keep_supported(&a, &[&a, &b, &other], 0.75, 1);
        assert_eq!(kept, a);
    }

    #[test]
    fn single_image_tie_points_go_when_the_recording_has_a_corroborated_one() {
        // Tie point #0 is located in both images, #1 only in n1.
        let a = refinement("pano_1", "n1", &[0.90, 0.85]);
        let b = refinement("pano_1", "n2", &[0.88]);
        let kept = keep_supported(&a, &[&a, &b], 0.75, 2);
        assert_eq!(scores(&kept), vec![0.90]);
        assert_eq!(kept.misses.unconfirmed, 1);
        assert_eq!(keep_supported(&b, &[&a, &b], 0.75, 2), b);
        // Without a tie point in two images, nothing is dropped; 1 disables the rule.
        let lone = refinement("pano_1", "n1", &[0.90, 0.85]);
        assert_eq!(keep_supported(&lone, &[&lone], 0.75, 2), lone);
        assert_eq!(keep_supported(&a, &[&a, &b], 0.75, 1), a);
    }

    #[test]
    fn a_location_the_peak_rule_drops_does_not_corroborate() {
        // #0 strong in n1, weak in n2: with the peak rule, it is located in one image only.
        let a = refinement("pano_1", "n1", &[0.90, 0.86]);
        let b = refinement("pano_1", "n2", &[0.71]);
        let c = refinement("pano_1", "n3", &[0.80, 0.84]);
        let kept_b = keep_supported(&b, &[&a, &b, &c], 0.75, 2);
        assert!(kept_b.matches.is_empty());
        assert_eq!(kept_b.misses.weak_peaks, 1);
        // #0 and #1 are in n1 and n3: both kept.
        assert_eq!(keep_supported(&a, &[&a, &b, &c], 0.75, 2), a);
    }

    #[test]
    fn a_peak_exactly_at_the_threshold_is_strong_and_zero_disables() {
        let a = refinement("pano_1", "n1", &[0.75, 0.70]);
        assert_eq!(scores(&keep_supported(&a, &[&a], 0.75, 1)), vec![0.75]);
        assert_eq!(keep_supported(&a, &[&a], 0.0, 1), a);
    }
}

//! Weak correlation peaks are kept only where a recording has nothing better (an addition to the peak test of
//! thesis 3.4.5.3).
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

use super::registration::AerialRefinement;
use crate::params::StageId;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("peak_support", "1");

/// `own` without its locations whose peak is below `strong_peak` when any refinement of the same recording in
/// `recording` (its refinements in all its nadir images; `own` may be among them, other recordings' are
/// ignored) has a location at or above `strong_peak`; otherwise `own` unchanged. `strong_peak ≤ 0` keeps
/// everything.
pub fn keep_supported_peaks(
    own: &AerialRefinement,
    recording: &[&AerialRefinement],
    strong_peak: f64,
) -> AerialRefinement {
    let mut out = own.clone();
    if !(strong_peak > 0.0) {
        return out;
    }
    let has_strong = recording
        .iter()
        .chain(std::iter::once(&own))
        .filter(|r| r.recording_id == own.recording_id)
        .flat_map(|r| &r.matches)
        .any(|m| m.observation.score >= strong_peak);
    if !has_strong {
        return out;
    }
    let before = out.matches.len();
    out.matches.retain(|m| m.observation.score >= strong_peak);
    out.misses.weak_peaks += before - out.matches.len();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nadir::AerialMatch;

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
        let kept = keep_supported_peaks(&a, &[&a, &b], 0.75);
        assert!(kept.matches.is_empty());
        assert_eq!(kept.misses.weak_peaks, 2);
        let kept_b = keep_supported_peaks(&b, &[&a, &b], 0.75);
        assert_eq!(scores(&kept_b), vec![0.81]);
        assert_eq!(kept_b.misses.weak_peaks, 1);
    }

    #[test]
    fn a_recording_with_only_weak_peaks_keeps_them() {
        let a = refinement("pano_1", "n1", &[0.71, 0.73]);
        let b = refinement("pano_1", "n2", &[0.74]);
        // Another recording's strong peak says nothing about this one.
        let other = refinement("pano_2", "n1", &[0.95]);
        let kept = keep_supported_peaks(&a, &[&a, &b, &other], 0.75);
        assert_eq!(kept, a);
    }

    #[test]
    fn a_peak_exactly_at_the_threshold_is_strong_and_zero_disables() {
        let a = refinement("pano_1", "n1", &[0.75, 0.70]);
        assert_eq!(scores(&keep_supported_peaks(&a, &[&a], 0.75)), vec![0.75]);
        assert_eq!(keep_supported_peaks(&a, &[&a], 0.0), a);
    }
}

//! Agreement of one recording's initial transforms across its overlapping nadir images (an extension of the
//! plausibility check of thesis 3.4.5.2).
//!
//! Every accepted transform (recording × nadir image) implies where the recording really is: the MM ortho
//! centre mapped into the aerial image and back onto the ground, minus the recorded position
//! (`InitialTransform::centre_offset_world_m`). The nadir images are georeferenced consistently with each other,
//! so all transforms of one recording must imply the same offset, up to decimetres. A transform locked onto a
//! repetition of the road markings (a zebra crossing, parking bays) passes the per-image plausibility window of
//! `max_localisation_error_m` but implies an offset metres away from the others, and the phase correlation of
//! thesis 3.4.5.3 then confirms it at a near-zero shift on the same repeated pattern. Such a transform is
//! rejected here when at least two other accepted transforms of the recording agree with each other: its
//! offset is compared with the component-wise median of theirs. With fewer than two others nothing can be told
//! and the transform is kept.

use super::registration::{InitialTransform, TransformOutcome};
use crate::estimators::median_consensus::median_in_place;
use crate::params::StageId;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("transform_agreement", "1");

/// The transforms of one recording that agree with each other: `outcome` unchanged, or turned into a
/// rejection when its implied offset lies farther than `max_disagreement_m` from the median of the offsets
/// implied by the other accepted transforms in `recording_outcomes` (the recording's outcomes for all its nadir
/// images; `outcome` itself and other recordings' outcomes in it are ignored). `max_disagreement_m = 0`
/// disables the check.
pub fn check_agreement(
    outcome: &TransformOutcome,
    recording_outcomes: &[&TransformOutcome],
    max_disagreement_m: f64,
) -> TransformOutcome {
    let TransformOutcome::Accepted(own) = outcome else {
        return outcome.clone();
    };
    if !(max_disagreement_m > 0.0) {
        return outcome.clone();
    }
    let others: Vec<&InitialTransform> = recording_outcomes
        .iter()
        .filter_map(|o| match o {
            TransformOutcome::Accepted(t)
                if t.recording_id == own.recording_id && t.aerial_id != own.aerial_id =>
            {
                Some(t)
            }
            _ => None,
        })
        .collect();
    if others.len() < 2 {
        return outcome.clone();
    }
    let median = |axis: usize| {
        let mut v: Vec<f64> = others
            .iter()
            .map(|t| t.centre_offset_world_m[axis])
            .collect();
        median_in_place(&mut v).unwrap_or(0.0)
    };
    let (mx, my) = (median(0), median(1));
    let d = (own.centre_offset_world_m[0] - mx).hypot(own.centre_offset_world_m[1] - my);
    if d <= max_disagreement_m {
        return outcome.clone();
    }
    TransformOutcome::Rejected {
        recording_id: own.recording_id.clone(),
        aerial_id: own.aerial_id.clone(),
        reason: format!(
            "implied recording offset {d:.2} m from the median of {} other nadir images > {max_disagreement_m} m",
            others.len()
        ),
        matches: own.matches,
        inliers: own.inliers,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Similarity2;

    fn accepted(aerial: &str, offset: [f64; 2]) -> TransformOutcome {
        TransformOutcome::Accepted(InitialTransform {
            recording_id: "rec".into(),
            aerial_id: aerial.into(),
            ortho_to_aerial: Similarity2::identity(),
            matches: 20,
            inliers: 12,
            centre_offset_m: offset[0].hypot(offset[1]),
            centre_offset_world_m: offset,
            reused_from: None,
        })
    }

    fn rejected(o: &TransformOutcome) -> bool {
        matches!(o, TransformOutcome::Rejected { .. })
    }

    #[test]
    fn a_transform_two_metres_off_the_others_is_rejected_and_they_are_kept() {
        // The recording is really 0.8 m east and 0.3 m south of its recorded position; image "c" locked onto a
        // repetition 1.9 m away.
        let all = [
            accepted("a", [0.80, -0.30]),
            accepted("b", [0.85, -0.25]),
            accepted("c", [-1.00, 0.40]),
            accepted("d", [0.75, -0.35]),
        ];
        let refs: Vec<&TransformOutcome> = all.iter().collect();
        let checked: Vec<TransformOutcome> = all
            .iter()
            .map(|o| check_agreement(o, &refs, 0.75))
            .collect();
        assert!(!rejected(&checked[0]) && !rejected(&checked[1]) && !rejected(&checked[3]));
        match &checked[2] {
            TransformOutcome::Rejected {
                reason, aerial_id, ..
            } => {
                assert_eq!(aerial_id, "c");
                assert!(reason.contains("3 other nadir images"), "{reason}");
            }
            other => panic!("expected a rejection, got {other:?}"),
        }
    }

    #[test]
    fn with_fewer_than_two_others_or_the_check_off_everything_is_kept() {
        let two = [accepted("a", [0.8, 0.0]), accepted("b", [-1.5, 0.0])];
        let refs: Vec<&TransformOutcome> = two.iter().collect();
        assert!(two
            .iter()
            .all(|o| !rejected(&check_agreement(o, &refs, 0.75))));
        let three = [
            accepted("a", [0.8, 0.0]),
            accepted("b", [0.8, 0.1]),
            accepted("c", [-1.5, 0.0]),
        ];
        let refs: Vec<&TransformOutcome> = three.iter().collect();
        assert!(rejected(&check_agreement(&three[2], &refs, 0.75)));
        assert!(!rejected(&check_agreement(&three[2], &refs, 0.0)));
    }

    #[test]
    fn rejected_outcomes_and_other_recordings_are_not_votes() {
        let mut other_rec = accepted("x", [-1.5, 0.0]);
        if let TransformOutcome::Accepted(t) = &mut other_rec {
            t.recording_id = "other".into();
        }
        let none = TransformOutcome::Rejected {
            recording_id: "rec".into(),
            aerial_id: "y".into(),
            reason: "no matches".into(),
            matches: 0,
            inliers: 0,
        };
        let all = [
            accepted("a", [-1.5, 0.0]),
            accepted("b", [0.8, 0.0]),
            other_rec,
            none.clone(),
        ];
        let refs: Vec<&TransformOutcome> = all.iter().collect();
        // "a" has one other vote ("b") only: kept.
        assert!(!rejected(&check_agreement(&all[0], &refs, 0.75)));
        assert_eq!(check_agreement(&none, &refs, 0.75), none);
    }
}

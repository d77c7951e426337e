//! Recordings beyond the first or last recording with control (a control point or aerial image observations of
//! a tie point it observes), tied to that recording's correction.
//!
//! A stretch of trajectory before the first or after the last recording that observes control has no
//! correction of its own: the adjustment carries one into it through the panorama tie points and the relative
//! constraints between consecutive recordings. The tie points fix each recording relative to the next to
//! centimetres, but their small errors add up along the chain — a slight scale or heading drift that took a
//! stretch of eight recordings of the orthophoto route from 0.12 to 0.25 m off — and the consecutive relative
//! constraints, whose σ_rel allows the stretch's end to wander by σ_rel · √k after k recordings, are too weak
//! against the tie points to hold it.
//!
//! The recorded trajectory's error is mostly common to neighbouring recordings, so the best guess for a
//! recording k recordings beyond the nearest recording with control (its anchor) is the anchor's correction.
//! With `extrapolation_anchor` each such recording is also tied directly to its anchor: the recorded
//! difference between the two is kept with σ_rel · k^`growth` (a relative constraint from the anchor to it,
//! under the relative constraints' robust loss), so the correction is carried into the stretch with less
//! weight the farther a recording is from its anchor, and the tie points keep the stretch's shape. The
//! recordings stay flagged `extrapolated` in the outputs ([`crate::correction::support`]). A stretch ends at
//! a gap in the trajectory (consecutive recordings farther apart than `relative_max_gap_m`, as for the
//! relative constraints).

use super::config::AdjustConfig;
use super::problem::{Block, RelativeConstraint};
use super::tie_point_heights::controlled_recordings;
use crate::campaign::Recording;

/// The anchor constraints of `block` (its control points and aerial observations already chosen): a recording
/// has control when it observes a control point or a tie point observed in an aerial image; consecutive `recordings` (the block's, in time order) are linked when at most
/// `relative_max_gap_m` apart; σ from `relative_sigma_m` and `extrapolation_anchor_growth`.
pub fn tail_anchors(
    block: &Block,
    recordings: &[Recording],
    config: &AdjustConfig,
    relative_sigma_m: f64,
) -> Vec<RelativeConstraint> {
    let controlled = controlled_recordings(block);
    let linked: Vec<bool> = (0..recordings.len())
        .map(|i| {
            i > 0 && {
                let (a, b) = (&recordings[i - 1], &recordings[i]);
                (a.x - b.x).hypot(a.y - b.y) <= config.relative_max_gap_m
            }
        })
        .collect();
    anchor_constraints(
        &controlled,
        &linked,
        relative_sigma_m,
        config.extrapolation_anchor_growth,
    )
}

/// The constraints from each recording beyond the first or last recording with control (`controlled`, one
/// flag per recording in time order) to that recording: σ = `sigma_m` · k^`growth` for a recording k
/// recordings away. `linked_to_previous[i]` says whether recording i is linked to recording i − 1 (no gap);
/// a stretch stops at the first unlinked recording. Nothing without any recording with control.
pub fn anchor_constraints(
    controlled: &[bool],
    linked_to_previous: &[bool],
    sigma_m: f64,
    growth: f64,
) -> Vec<RelativeConstraint> {
    let n = controlled.len();
    let (Some(first), Some(last)) = (
        controlled.iter().position(|&c| c),
        controlled.iter().rposition(|&c| c),
    ) else {
        return Vec::new();
    };
    let linked = |i: usize| linked_to_previous.get(i).copied().unwrap_or(false);
    let constraint = |anchor: usize, to: usize| {
        RelativeConstraint::new(
            anchor,
            to,
            sigma_m * (anchor.abs_diff(to) as f64).powf(growth),
        )
    };
    let mut out = Vec::new();
    // Before the first: recordings first − 1, first − 2, … while each is linked to the next one.
    let mut i = first;
    while i > 0 && linked(i) {
        i -= 1;
        out.push(constraint(first, i));
    }
    // After the last.
    let mut i = last;
    while i + 1 < n && linked(i + 1) {
        i += 1;
        out.push(constraint(last, i));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tails_are_tied_to_their_anchor_with_a_growing_sigma() {
        let mut controlled = vec![false; 10];
        controlled[2] = true;
        controlled[5] = true;
        let mut linked = vec![true; 10];
        linked[0] = false;
        linked[9] = false; // a gap before the last recording: it is not tied
        let c = anchor_constraints(&controlled, &linked, 0.15, 0.5);
        let pairs: Vec<(usize, usize)> = c.iter().map(|c| (c.from, c.to)).collect();
        assert_eq!(pairs, [(2, 1), (2, 0), (5, 6), (5, 7), (5, 8)]);
        assert!((c[1].sigma_m - 0.15 * 2f64.sqrt()).abs() < 1e-12);
        assert!((c[4].sigma_m - 0.15 * 3f64.sqrt()).abs() < 1e-12);
        // The bridged recordings 3 and 4 are not tied.
        assert!(c.iter().all(|c| !(3..=4).contains(&c.to)));
        // Without control nothing is tied.
        assert!(anchor_constraints(&[false; 4], &[true; 4], 0.15, 0.5).is_empty());
    }
}

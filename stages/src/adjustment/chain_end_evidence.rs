//! Aerial evidence at the end of a chain of recordings that nothing can check.
//!
//! Inside a chain, the aerial evidence of one recording is checked from both sides: the relative constraints
//! carry the corrections of the controlled recordings before and after it, and a wrong observation leaves a
//! residual that the robust loss and the rejection see. The first (last) piece of evidence of a chain has
//! neighbours on one side only, and when it is a single aerial observation — one pixel of one aerial image,
//! with no second image and no other aerial point of the same recordings to agree or disagree with it — its
//! residual is zero whatever it says: the recordings between the chain's end and the next evidence simply
//! follow it. A wrong match there moves the whole end of the street by its error.
//!
//! So an aerial point at a chain end with fewer than `chain_end_min_aerial_observations` aerial observations
//! in the block is left out when it stands alone: no recording from the chain's end up to the last (first)
//! recording that observes it observes any other aerial evidence. Its point stays a tie point, and the
//! recordings it would have moved follow the chain's other evidence (they are `extrapolated`). Ground
//! control (triangulated from two or more aerial images, or read from an orthophoto) counts as two
//! observations. Chains are the runs of recordings linked by relative constraints; without relative
//! constraints nothing is checked here.

use super::block_point::{BlockPoint, PointKind};
use super::build_counts::BuildCounts;
use super::problem::{Block, RelativeConstraint};

/// The aerial observations of each point that the block uses: aerial image observations, and 2 for a
/// ground control point (at least two aerial images or an orthophoto).
fn observations_per_point(block: &Block, n_points: usize) -> Vec<usize> {
    let mut n = vec![0usize; n_points];
    for o in &block.aerial_observations {
        n[o.point] += 1;
    }
    for c in &block.control_points {
        n[c.point] += 2;
    }
    n
}

/// The chains of `n` recordings: maximal runs `first..=last` linked by relative constraints between
/// consecutive recordings.
fn chains(n: usize, constraints: &[RelativeConstraint]) -> Vec<(usize, usize)> {
    let mut linked_to_previous = vec![false; n];
    for c in constraints {
        if c.to == c.from + 1 {
            linked_to_previous[c.to] = true;
        } else if c.from == c.to + 1 {
            linked_to_previous[c.from] = true;
        }
    }
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..=n {
        if i == n || !linked_to_previous[i] {
            out.push((start, i - 1));
            start = i;
        }
    }
    out
}

/// The aerial point that alone anchors the end of the chain reached by walking `order` (recording indices
/// from the chain's end inwards): the evidence point of the first recording with evidence, when that
/// recording and every recording up to the point's innermost observer see no other evidence. `None` when the
/// chain has no evidence or its end is anchored by more than one point.
fn lone_end_point(
    order: &[usize],
    evidence_of: &[Vec<usize>],
    points: &[BlockPoint],
) -> Option<usize> {
    let mut walk = order.iter().map(|&r| (r, &evidence_of[r]));
    let (_, first) = walk.by_ref().find(|(_, e)| !e.is_empty())?;
    let &[p] = first.as_slice() else {
        return None;
    };
    let observers = points[p].recordings();
    let mut unseen = observers.len();
    // The recordings before the first with evidence saw none; the first saw `p` only.
    unseen -= 1;
    for (r, e) in walk {
        if unseen == 0 {
            break;
        }
        if e.iter().any(|&q| q != p) {
            return None;
        }
        if observers.binary_search(&r).is_ok() {
            unseen -= 1;
        }
    }
    Some(p)
}

/// The points that alone anchor a chain end (in chains of `n_recordings` linked by `constraints`) with fewer
/// than `min_observations` aerial observations (`observations`, per point), ascending.
fn lone_ends_below(
    n_recordings: usize,
    constraints: &[RelativeConstraint],
    points: &[BlockPoint],
    observations: &[usize],
    min_observations: usize,
) -> Vec<usize> {
    let mut evidence_of: Vec<Vec<usize>> = vec![Vec::new(); n_recordings];
    for (p, point) in points
        .iter()
        .enumerate()
        .filter(|(p, _)| observations[*p] > 0)
    {
        for r in point.recordings() {
            if let Some(e) = evidence_of.get_mut(r) {
                e.push(p);
            }
        }
    }
    let mut dropped: Vec<usize> = Vec::new();
    for (first, last) in chains(n_recordings, constraints) {
        let forward: Vec<usize> = (first..=last).collect();
        let backward: Vec<usize> = (first..=last).rev().collect();
        for order in [forward, backward] {
            if let Some(p) = lone_end_point(&order, &evidence_of, points) {
                if observations[p] < min_observations && !dropped.contains(&p) {
                    dropped.push(p);
                }
            }
        }
    }
    dropped.sort_unstable();
    dropped
}

/// Leaves out of `block` the aerial evidence that alone anchors a chain end with fewer than
/// `min_observations` aerial observations (module doc); such points become tie points again, and `counts`
/// says so (`chain_end_evidence_dropped`, and the aerial observations and ground control taken out).
/// `min_observations` ≤ 1 checks nothing.
pub fn drop_lone_chain_end_evidence(
    block: &mut Block,
    points: &mut [BlockPoint],
    min_observations: usize,
    counts: &mut BuildCounts,
) {
    if min_observations <= 1 || block.relative_constraints.is_empty() {
        return;
    }
    let observations = observations_per_point(block, points.len());
    let dropped = lone_ends_below(
        block.recordings.len(),
        &block.relative_constraints,
        points,
        &observations,
        min_observations,
    );
    if dropped.is_empty() {
        return;
    }
    let (aerial_before, ground_before) =
        (block.aerial_observations.len(), block.control_points.len());
    for &p in &dropped {
        if block.aerial_observations.iter().any(|o| o.point == p) {
            counts.control_as_aerial_observations -= 1;
        }
    }
    block
        .aerial_observations
        .retain(|o| !dropped.contains(&o.point));
    block.control_points.retain(|c| !dropped.contains(&c.point));
    counts.aerial_observations -= aerial_before - block.aerial_observations.len();
    counts.control_as_gcp -= ground_before - block.control_points.len();
    for &p in &dropped {
        points[p].kind = PointKind::Tie;
    }
    counts.chain_end_evidence_dropped = dropped.len();
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points observed by the given recordings with the given number of aerial observations each.
    fn points(pts: &[(&[usize], usize)]) -> (Vec<BlockPoint>, Vec<usize>) {
        let points = pts
            .iter()
            .enumerate()
            .map(|(p, (recs, _))| BlockPoint {
                id: format!("p{p}"),
                kind: PointKind::SingleAerial,
                pano: recs.iter().map(|&r| (r, 0.0, 0.0)).collect(),
                aerial: Vec::new(),
            })
            .collect();
        (points, pts.iter().map(|p| p.1).collect())
    }

    /// Constraints linking `n` consecutive recordings, except across a gap after `gap_after`.
    fn linked(n: usize, gap_after: Option<usize>) -> Vec<RelativeConstraint> {
        (1..n)
            .filter(|&i| gap_after != Some(i - 1))
            .map(|i| RelativeConstraint::new(i - 1, i, 0.05))
            .collect()
    }

    fn lone(
        n: usize,
        gap_after: Option<usize>,
        pts: &[(&[usize], usize)],
        min: usize,
    ) -> Vec<usize> {
        let (points, observations) = points(pts);
        lone_ends_below(n, &linked(n, gap_after), &points, &observations, min)
    }

    #[test]
    fn a_single_observation_alone_at_a_chain_end_is_found_at_both_ends() {
        // Point 0 (one observation) anchors recordings 0-2 alone; points 1, 2 anchor the middle; point 3 (one
        // observation) anchors the last recordings alone; point 4 is a tie point.
        let pts: &[(&[usize], usize)] = &[
            (&[0, 1, 2], 1),
            (&[8, 9], 2),
            (&[10], 1),
            (&[17, 18], 1),
            (&[1, 5], 0),
        ];
        assert_eq!(lone(20, None, pts, 2), [0, 3]);
        // A chain anchored by one point alone: it is both ends.
        assert_eq!(lone(20, None, &[(&[5, 6], 1)], 2), [0]);
    }

    #[test]
    fn end_evidence_with_company_or_enough_observations_stays() {
        // Two single observations share the end: they check each other.
        assert!(lone(20, None, &[(&[0, 1, 2], 1), (&[2, 3], 1), (&[10], 2)], 2).is_empty());
        // Another point is observed by a recording before the end point's innermost observer.
        assert!(lone(20, None, &[(&[0, 1, 4], 1), (&[3], 1), (&[10], 2)], 2).is_empty());
        // Two aerial observations are enough at 2; not at 3.
        let pts: &[(&[usize], usize)] = &[(&[0, 1], 2), (&[10], 2)];
        assert!(lone(20, None, pts, 2).is_empty());
        assert_eq!(lone(20, None, pts, 3), [0, 1]);
    }

    #[test]
    fn chains_end_at_gaps() {
        // A gap after recording 9: point 1 starts the second chain alone; point 0 ends the first alone but
        // has enough observations.
        assert_eq!(
            lone(20, Some(9), &[(&[2], 3), (&[10, 11], 1), (&[15], 3)], 2),
            [1]
        );
        assert_eq!(chains(6, &linked(6, Some(2))), [(0, 2), (3, 5)]);
        assert_eq!(chains(3, &[]), [(0, 0), (1, 1), (2, 2)]);
        assert!(chains(0, &[]).is_empty());
    }
}

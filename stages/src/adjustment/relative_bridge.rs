//! Relative constraints across a stretch of recordings without aerial evidence of their own, widened to the
//! drift their anchors show.
//!
//! The release ([`super::relative_release`]) tests only steps between two recordings with aerial evidence of
//! their own: a recording without it (a bridged recording) is placed by tie points alone in the solution
//! without relative constraints, and that placement cannot judge its steps. Left at the trajectory's σ,
//! those steps carry the recorded (drifted) shape of the stretch: once the anchors on both sides are
//! corrected, the robust loss lets one end of the chain go and the stretch follows the other anchor, or its
//! own tie points, instead of both.
//!
//! A chain of such steps is tested as a whole instead. For a path of `n` constraints from an anchor `a`
//! (aerial evidence of its own) through bridged recordings only to a second anchor `b`, the solution's change
//! of the chain, `Δ = ĉ_b − ĉ_a` (horizontal, ĉ = adjusted − recorded position), has under the constraints
//! the covariance `Σσ_k²·I + Q` with `Q = V_a + V_b` (the solution's covariance of the two anchors; the
//! cross block is taken as 0, which only makes the test more cautious). When `Δᵀ(Σσ_k²·I + Q)⁻¹Δ` exceeds
//! the release's threshold, the chain is contradicted and the variance `S²` that brings the statistic to its
//! expectation 2 ([`super::relative_release::added_variance`]) is shared equally by its steps: each gets
//! `σ_k' = √(σ_k² + S²/n)`. Equal weights along the chain put the bridged recordings on the straight
//! interpolation of the anchors' corrections (where their own tie points say nothing else), and the chain's
//! σ as a whole covers the change, so it no longer pulls the anchors back toward the recorded shape.
//!
//! Only simple chains are widened: a stretch of bridged recordings that branches (a junction) or that
//! reaches only one anchor (the ends of the trajectory; see [`super::extrapolation_anchor`]) keeps its σ.

use super::problem::RelativeConstraint;
use super::relative_release::{added_variance, Evidence};
use nalgebra::{Matrix2, Vector2};

/// A path of constraints from one anchor through bridged recordings to another.
struct Chain {
    /// Indices into the constraint list, in path order.
    constraints: Vec<usize>,
    /// The anchors at its two ends (recordings with aerial evidence of their own).
    anchors: (usize, usize),
}

/// Widens the constraints of every contradicted chain of bridged recordings in `constraints` (module
/// documentation); `threshold` is the χ² (2 degrees of freedom) value above which a chain is contradicted.
/// Returns how many constraints were widened.
pub fn widen_bridges(
    constraints: &mut [RelativeConstraint],
    evidence: &Evidence,
    threshold: f64,
) -> usize {
    let mut widened = 0;
    for chain in chains(constraints, evidence.aerial) {
        let (delta, q) = anchor_change(chain.anchors, evidence);
        let sigma2: f64 = chain
            .constraints
            .iter()
            .map(|&k| constraints[k].sigma_m * constraints[k].sigma_m)
            .sum();
        let n = chain.constraints.len() as f64;
        let whole = added_variance(delta, q, sigma2, threshold).map_or(0.0, |s2| s2 / n);
        let local = tested_sigma2_at(constraints, evidence.aerial, chain.anchors);
        for &k in &chain.constraints {
            let rc = &mut constraints[k];
            let s2 = rc.sigma_m * rc.sigma_m;
            let widened_s2 = (s2 + whole).max(local);
            if widened_s2 > s2 {
                rc.sigma_m = widened_s2.sqrt();
                widened += 1;
            }
            rc.held = true;
        }
    }
    widened
}

/// The largest σ² among the tested constraints (both ends with aerial evidence) at either anchor, after the
/// release: how fast the trajectory's error changes per step next to the chain, m².
fn tested_sigma2_at(
    constraints: &[RelativeConstraint],
    aerial: &[bool],
    anchors: (usize, usize),
) -> f64 {
    constraints
        .iter()
        .filter(|rc| aerial[rc.from] && aerial[rc.to])
        .filter(|rc| {
            [rc.from, rc.to]
                .iter()
                .any(|&r| r == anchors.0 || r == anchors.1)
        })
        .map(|rc| rc.sigma_m * rc.sigma_m)
        .fold(0.0, f64::max)
}

/// The solution's horizontal change between the two anchors and its covariance, m and m².
fn anchor_change(anchors: (usize, usize), evidence: &Evidence) -> (Vector2<f64>, Matrix2<f64>) {
    let correction =
        |c: usize| evidence.state.centers_local[c] - evidence.recorded.centers_local[c];
    let d = correction(anchors.1) - correction(anchors.0);
    let horizontal = |c: usize| evidence.covariance[c].fixed_view::<2, 2>(0, 0).into_owned();
    let q = (horizontal(anchors.0) + horizontal(anchors.1)) * evidence.variance_scale;
    (Vector2::new(d.x, d.y), q)
}

/// The simple chains of bridged recordings (`!aerial`) between two distinct anchors, each once.
fn chains(constraints: &[RelativeConstraint], aerial: &[bool]) -> Vec<Chain> {
    let n = aerial.len();
    let mut incident: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (k, rc) in constraints.iter().enumerate() {
        if rc.from < n && rc.to < n && rc.from != rc.to {
            incident[rc.from].push(k);
            incident[rc.to].push(k);
        }
    }
    let other = |k: usize, r: usize| {
        let rc = &constraints[k];
        if rc.from == r {
            rc.to
        } else {
            rc.from
        }
    };
    let mut seen = vec![false; n];
    let mut out = Vec::new();
    for start in 0..n {
        if aerial[start] || seen[start] {
            continue;
        }
        // The connected stretch of bridged recordings around `start`.
        let mut stretch = vec![start];
        seen[start] = true;
        let mut i = 0;
        while i < stretch.len() {
            let r = stretch[i];
            i += 1;
            for &k in &incident[r] {
                let o = other(k, r);
                if !aerial[o] && !seen[o] {
                    seen[o] = true;
                    stretch.push(o);
                }
            }
        }
        if let Some(chain) = simple_chain(&stretch, &incident, aerial, other) {
            out.push(chain);
        }
    }
    out
}

/// The stretch as a path from one anchor to another, when every bridged recording in it has exactly two
/// constraints and exactly two of them reach (distinct) anchors.
fn simple_chain(
    stretch: &[usize],
    incident: &[Vec<usize>],
    aerial: &[bool],
    other: impl Fn(usize, usize) -> usize,
) -> Option<Chain> {
    if stretch.iter().any(|&r| incident[r].len() != 2) {
        return None;
    }
    let ends: Vec<(usize, usize)> = stretch
        .iter()
        .flat_map(|&r| incident[r].iter().map(move |&k| (r, k)))
        .filter(|&(r, k)| aerial[other(k, r)])
        .collect();
    let [(first, k0), (last, k1)] = ends[..] else {
        return None;
    };
    let anchors = (other(k0, first), other(k1, last));
    if anchors.0 == anchors.1 {
        return None;
    }
    // Walk from the first anchor's constraint through the stretch to the other anchor.
    let mut path = vec![k0];
    let (mut at, mut via) = (first, k0);
    while !aerial[at] {
        let next = *incident[at].iter().find(|&&k| k != via)?;
        path.push(next);
        via = next;
        at = other(next, at);
        if path.len() > stretch.len() + 1 {
            return None;
        }
    }
    (at == anchors.1).then_some(Chain {
        constraints: path,
        anchors,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rc(from: usize, to: usize) -> RelativeConstraint {
        RelativeConstraint::new(from, to, 0.02)
    }

    #[test]
    fn a_stretch_between_two_anchors_is_one_chain_in_path_order() {
        // 0 1 [2 3 4] 5 6: recordings 2–4 bridged.
        let constraints: Vec<_> = (0..6).map(|i| rc(i, i + 1)).collect();
        let aerial = [true, true, false, false, false, true, true];
        let found = chains(&constraints, &aerial);
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].constraints, vec![1, 2, 3, 4]);
        assert_eq!(found[0].anchors, (1, 5));
    }

    #[test]
    fn ends_and_junctions_are_not_chains() {
        // A stretch at the start reaches one anchor only.
        let constraints: Vec<_> = (0..4).map(|i| rc(i, i + 1)).collect();
        assert!(chains(&constraints, &[false, false, true, true, true]).is_empty());
        // A junction: bridged recording 1 has three constraints.
        let constraints = vec![rc(0, 1), rc(1, 2), rc(1, 3)];
        assert!(chains(&constraints, &[true, false, true, true]).is_empty());
    }
}

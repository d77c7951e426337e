//! Relative constraints across a stretch of recordings without aerial evidence of their own, given the σ of
//! the drift next to it.
//!
//! The release ([`super::relative_release`]) tests only steps between two recordings with aerial evidence of
//! their own: a recording without it (a bridged recording) is placed by tie points alone in the solution
//! without relative constraints, and that placement cannot judge its steps. Left at the trajectory's σ under
//! the robust loss, the steps of a drifted stretch carry its recorded shape: once the recordings with
//! evidence on both sides (its anchors) are corrected, the loss lets one end of the chain go and the stretch
//! follows the other anchor instead of both.
//!
//! A drift changes slowly along the trajectory, so the steps next to the stretch say how much its own steps
//! are off: for a path of constraints from an anchor `a` through bridged recordings only to a second anchor
//! `b`, every step of the path takes at least the largest σ of the tested steps at `a` and `b` after the
//! release, and the widened path is held by least squares instead of the robust loss. Equal weights along the
//! path put the bridged recordings on the straight interpolation of the anchors' corrections where their own
//! tie points say nothing else. A path whose anchors' tested steps were not released is left as it is (σ and
//! robust loss): nothing says that it drifted, and holding its recorded shape by least squares against its
//! own tie points moved stretches next to wrong aerial evidence by metres on rendered campaigns
//! (measured in docs/evaluation.md).
//!
//! The path keeps that σ even when the anchors' corrections differ by more than it allows: widening it
//! further to cover the whole difference lets the bridged recordings' own tie points, which are few and
//! undetectable when wrong (each seen by two or three bridged recordings), carry them away — measured on
//! rendered campaigns in the method's documentation. A stretch that branches (a junction) or that reaches
//! only one anchor (the ends of the trajectory; see [`super::extrapolation_anchor`]) keeps its σ and loss.

use super::problem::RelativeConstraint;

/// A path of constraints from one anchor through bridged recordings to another.
struct Chain {
    /// Indices into the constraint list, in path order.
    constraints: Vec<usize>,
    /// The anchors at its two ends (recordings with aerial evidence of their own).
    anchors: (usize, usize),
}

/// Gives the constraints of every chain of bridged recordings in `constraints` the σ of the tested steps at
/// its anchors and holds the widened ones by least squares (module documentation). Returns how many
/// constraints were widened.
pub fn widen_bridges(constraints: &mut [RelativeConstraint], aerial: &[bool]) -> usize {
    let tested = tested_sigma2(constraints, aerial);
    let mut widened = 0;
    for chain in chains(constraints, aerial) {
        let local = tested[chain.anchors.0].max(tested[chain.anchors.1]);
        for &k in &chain.constraints {
            let rc = &mut constraints[k];
            if local > rc.sigma_m * rc.sigma_m {
                rc.sigma_m = local.sqrt();
                rc.held = true;
                widened += 1;
            }
        }
    }
    widened
}

/// Per recording, the largest σ² among its tested constraints (both ends with aerial evidence) after the
/// release, 0 without any: how fast the trajectory's error changes per step there, m².
fn tested_sigma2(constraints: &[RelativeConstraint], aerial: &[bool]) -> Vec<f64> {
    let mut out = vec![0.0_f64; aerial.len()];
    for rc in constraints {
        if aerial.get(rc.from) == Some(&true) && aerial.get(rc.to) == Some(&true) {
            let s2 = rc.sigma_m * rc.sigma_m;
            out[rc.from] = out[rc.from].max(s2);
            out[rc.to] = out[rc.to].max(s2);
        }
    }
    out
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
    fn a_chain_is_widened_and_held_only_next_to_a_released_step() {
        // 0 1 [2 3 4] 5 6, nothing released: the chain keeps its σ and the robust loss.
        let aerial = [true, true, false, false, false, true, true];
        let mut constraints: Vec<_> = (0..6).map(|i| rc(i, i + 1)).collect();
        let before = constraints.clone();
        assert_eq!(widen_bridges(&mut constraints, &aerial), 0);
        assert_eq!(constraints, before);
        // Step 0→1 released to σ 0.3 m: the chain from anchor 1 takes it and is held.
        constraints[0].sigma_m = 0.3;
        assert_eq!(widen_bridges(&mut constraints, &aerial), 4);
        for k in 1..5 {
            assert_eq!(constraints[k].sigma_m, 0.3);
            assert!(constraints[k].held);
        }
        assert!(!constraints[5].held && constraints[5].sigma_m == 0.02);
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

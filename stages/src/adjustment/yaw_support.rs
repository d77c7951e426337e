//! Whether the evidence supports one heading correction for a chain of recordings.
//!
//! With relative yaw terms ([`AdjustOptions::yaw_relative_sigma_deg`]) the recordings linked by relative
//! constraints share one zero yaw prior, so their common yaw correction is set by the evidence: what an
//! inertial heading bias shared by the whole drive needs. Where the evidence of the chain's heading is weak (a
//! short street, few aerial points, all on one side of it) the common correction is set by the noise of that
//! evidence and turns the whole chain. A chain therefore keeps its tie only when its common correction is
//! significant, `|ψ̄| ≥ k·σ_ψ̄` (a test of an additional parameter, as in geodetic network adjustment); otherwise
//! its constraints are untied ([`RelativeConstraint::ties_yaw`]) and each of its recordings keeps its own yaw
//! prior, as without relative yaw terms.
//!
//! `ψ̄` is the mean yaw correction of the chain and `σ_ψ̄` the mean of its recordings' posterior σ of yaw (the
//! a-priori σ scaled by [`super::adjust::posterior_scale`]): an upper bound of the σ of the mean whatever the
//! correlations, so the test keeps a tie only on evidence.

use super::problem::{AdjustOptions, RelativeConstraint};
use nalgebra::Matrix4;

/// The common yaw correction of one chain of recordings, as the tied solve found it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChainYaw {
    /// Recordings of the chain (indices into the block), ascending.
    pub recordings: Vec<usize>,
    /// Mean yaw correction ψ̄, radians.
    pub correction_rad: f64,
    /// Mean posterior σ of the recordings' yaw corrections, radians.
    pub sigma_rad: f64,
    /// Whether the chain kept its tie in the final solve (its correction passed the significance test).
    pub tied: bool,
}

impl ChainYaw {
    /// Whether `|ψ̄| ≥ k·σ_ψ̄`.
    pub fn is_significant(&self, k: f64) -> bool {
        self.correction_rad.abs() >= k * self.sigma_rad
    }
}

/// The chains of recordings linked by yaw-tying relative constraints (connected components of more than
/// one recording), each ascending, ordered by their first recording.
pub fn yaw_chains(n_recordings: usize, relative: &[RelativeConstraint]) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..n_recordings).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for rc in relative.iter().filter(|rc| rc.ties_yaw) {
        let (a, b) = (root(&mut parent, rc.from), root(&mut parent, rc.to));
        if a != b {
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); n_recordings];
    for c in 0..n_recordings {
        let r = root(&mut parent, c);
        members[r].push(c);
    }
    members.into_iter().filter(|m| m.len() > 1).collect()
}

/// [`ChainYaw`] of each chain from the solved yaw corrections (radians), the recordings' a-priori covariance
/// blocks over (x, y, z, ψ) and the factor from a-priori to a-posteriori σ.
pub fn chain_yaws(
    chains: &[Vec<usize>],
    yaw_correction_rad: &[f64],
    covariance: &[Matrix4<f64>],
    posterior_scale: f64,
) -> Vec<ChainYaw> {
    chains
        .iter()
        .map(|chain| {
            let n = chain.len() as f64;
            let correction_rad = chain.iter().map(|&c| yaw_correction_rad[c]).sum::<f64>() / n;
            let sigma_rad = chain
                .iter()
                .map(|&c| covariance[c][(3, 3)].max(0.0).sqrt())
                .sum::<f64>()
                / n
                * posterior_scale;
            ChainYaw {
                recordings: chain.clone(),
                correction_rad,
                sigma_rad,
                tied: true,
            }
        })
        .collect()
}

/// `relative` with the yaw terms of the chains in `untie` removed; `None` when `untie` is empty.
pub fn untied(
    relative: &[RelativeConstraint],
    untie: &[&ChainYaw],
) -> Option<Vec<RelativeConstraint>> {
    if untie.is_empty() {
        return None;
    }
    let mut in_untied = std::collections::BTreeSet::new();
    for chain in untie {
        in_untied.extend(chain.recordings.iter().copied());
    }
    Some(
        relative
            .iter()
            .map(|rc| RelativeConstraint {
                ties_yaw: rc.ties_yaw && !in_untied.contains(&rc.from),
                ..*rc
            })
            .collect(),
    )
}

/// Whether `options` ask for relative yaw terms (and so for this test).
pub fn applies(options: &AdjustOptions) -> bool {
    options.estimate_yaw && options.yaw_relative_sigma_deg.is_some()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rc(from: usize, to: usize) -> RelativeConstraint {
        RelativeConstraint::new(from, to, 0.05)
    }

    #[test]
    fn chains_are_the_linked_recordings_and_skip_untied_steps() {
        let mut relative = vec![rc(0, 1), rc(1, 2), rc(4, 5), rc(5, 6)];
        assert_eq!(yaw_chains(8, &relative), vec![vec![0, 1, 2], vec![4, 5, 6]]);
        relative[2].ties_yaw = false;
        assert_eq!(yaw_chains(8, &relative), vec![vec![0, 1, 2], vec![5, 6]]);
        assert!(yaw_chains(3, &[]).is_empty());
    }

    #[test]
    fn the_common_correction_is_the_mean_with_the_mean_sigma() {
        let mut cov = vec![Matrix4::zeros(); 3];
        for (c, s) in cov.iter_mut().zip([0.01f64, 0.02, 0.03]) {
            c[(3, 3)] = s * s;
        }
        let yaws = chain_yaws(&[vec![0, 1, 2]], &[0.02, 0.04, 0.06], &cov, 2.0);
        assert!((yaws[0].correction_rad - 0.04).abs() < 1e-15);
        assert!((yaws[0].sigma_rad - 0.04).abs() < 1e-15);
        assert!(yaws[0].is_significant(1.0));
        assert!(!yaws[0].is_significant(1.01));
    }

    #[test]
    fn untying_a_chain_removes_only_its_yaw_terms() {
        let relative = vec![rc(0, 1), rc(1, 2), rc(3, 4)];
        assert!(untied(&relative, &[]).is_none());
        let weak = ChainYaw {
            recordings: vec![3, 4],
            correction_rad: 0.0,
            sigma_rad: 1.0,
            tied: false,
        };
        let out = untied(&relative, &[&weak]).unwrap();
        assert_eq!(
            out.iter().map(|r| r.ties_yaw).collect::<Vec<_>>(),
            vec![true, true, false]
        );
        assert_eq!(out[2].sigma_m, relative[2].sigma_m);
    }
}

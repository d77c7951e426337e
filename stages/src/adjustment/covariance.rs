//! Posterior precision of the adjusted recordings (per-recording posterior standard deviations).
//!
//! The covariance of the recording parameters is the inverse of the reduced camera matrix
//! `S = U − W·V⁻¹·Wᵀ` (the Schur complement is exactly the inverse of the camera block of the full inverse
//! normal matrix), evaluated undamped at the solution with the final robust weights. Because all residuals
//! are whitened by their a-priori σ, `S⁻¹` is the **a-priori** covariance (σ0 = 1); the **a-posteriori**
//! covariance is `σ̂0²·S⁻¹` with the variance factor `σ̂0² = Σr² / (n − u)` (n residual components, u
//! unknowns). Only the blocks of S⁻¹ on the structure of the sparse Cholesky factor are computed, by
//! selected inversion ([`super::sparse::selected_inverse`]), never the dense inverse: the diagonal 4 × 4 block
//! of each recording is read from them.

use super::error::AdjustError;
use super::linearization::linearize;
use super::prepared::Prepared;
use super::residuals::State;
use super::schur::{ReduceError, ReducedSystem};
use super::sparse::SelectedInverse;
use nalgebra::Matrix4;

/// A-priori covariance blocks over (x in m, y in m, z in m, ψ in rad) per recording (rows/columns of fixed
/// parameters are zero), and the variance factor σ̂0² (`None` without redundancy).
#[derive(Clone, Debug, PartialEq)]
pub struct RecordingCovariances {
    pub a_priori: Vec<Matrix4<f64>>,
    pub variance_factor: Option<f64>,
    /// Redundancy n − u.
    pub redundancy: i64,
}

/// A-priori cross-covariance blocks over (x, y, z, ψ) of pairs of recordings, `None` where not computed.
pub type CrossCovariances = Vec<Option<Matrix4<f64>>>;

/// Computes [`RecordingCovariances`] at the solution `state`.
pub fn recording_covariances(
    prep: &Prepared,
    state: &State,
) -> Result<RecordingCovariances, AdjustError> {
    recording_covariances_with_pairs(prep, state, &[]).map(|(cov, _)| cov)
}

/// [`recording_covariances`] and, for each pair `(a, b)` of recordings, the a-priori cross-covariance block
/// Cov(a, b) over (x, y, z, ψ) when it lies on the factor's structure (recordings that share tie points or are
/// linked by a constraint), else `None`.
pub fn recording_covariances_with_pairs(
    prep: &Prepared,
    state: &State,
    pairs: &[(usize, usize)],
) -> Result<(RecordingCovariances, CrossCovariances), AdjustError> {
    let lin = linearize(prep, state);
    let mut system = ReducedSystem::new(prep);
    system.reduce(prep, &lin, 0.0).map_err(|e| match e {
        ReduceError::Pivot(p) => AdjustError::Singular {
            recording: p.block,
            parameter: p.component,
        },
        ReduceError::Point(_) => AdjustError::Singular {
            recording: 0,
            parameter: 0,
        },
    })?;
    drop(lin);
    let symbolic = &prep.structure.symbolic;
    let inverse = SelectedInverse::new(symbolic, &system.factor);
    let active = &prep.parameterization.active;
    let n_rec = prep.recorded_local.len();
    let masked = |z: Matrix4<f64>| {
        Matrix4::from_fn(|i, j| {
            if active.contains(&i) && active.contains(&j) {
                z[(i, j)]
            } else {
                0.0
            }
        })
    };
    let a_priori: Vec<Matrix4<f64>> = (0..n_rec)
        .map(|c| masked(inverse.diagonal(symbolic, c)))
        .collect();
    let cross = pairs
        .iter()
        .map(|&(a, b)| inverse.get(symbolic, a, b).map(masked))
        .collect();
    let n = n_rec * active.len();
    let (sum_sq, components) = prep.plain_sum_of_squares(state);
    let unknowns = n + 3 * prep.point_active.iter().filter(|&&a| a).count();
    let redundancy = components as i64 - unknowns as i64;
    let variance_factor = (redundancy > 0).then(|| sum_sq / redundancy as f64);
    let cov = RecordingCovariances {
        a_priori,
        variance_factor,
        redundancy,
    };
    Ok((cov, cross))
}

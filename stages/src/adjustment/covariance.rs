//! Posterior precision of the adjusted recordings (issue 6: per-recording posterior standard deviations).
//!
//! The covariance of the recording parameters is the inverse of the reduced camera matrix
//! `S = U − W·V⁻¹·Wᵀ` (the Schur complement is exactly the inverse of the camera block of the full inverse
//! normal matrix), evaluated undamped at the solution with the final robust weights. Because all residuals
//! are whitened by their a-priori σ, `S⁻¹` is the **a-priori** covariance (σ0 = 1); the **a-posteriori**
//! covariance is `σ̂0²·S⁻¹` with the variance factor `σ̂0² = Σr² / (n − u)` (n residual components, u
//! unknowns). Only the 3 × 3/4 × 4 diagonal blocks of S⁻¹ are computed (one solve per parameter with the
//! envelope factor, recordings in parallel with an ordered collect).

use super::prepared::Prepared;
use super::problem::AdjustError;
use super::residuals::State;
use super::solver::factorized_reduced_matrix;
use nalgebra::Matrix4;
use rayon::prelude::*;

/// A-priori covariance blocks over (x [m], y [m], z [m], ψ [rad]) per recording (rows/columns of fixed
/// parameters are zero), and the variance factor σ̂0² (`None` without redundancy).
#[derive(Clone, Debug, PartialEq)]
pub struct RecordingCovariances {
    pub a_priori: Vec<Matrix4<f64>>,
    pub variance_factor: Option<f64>,
    /// Redundancy n − u.
    pub redundancy: i64,
}

/// Computes [`RecordingCovariances`] at the solution `state`.
pub fn recording_covariances(
    prep: &Prepared,
    state: &State,
) -> Result<RecordingCovariances, AdjustError> {
    let factor = factorized_reduced_matrix(prep, state)?;
    let active = &prep.parameterization.active;
    let k = active.len();
    let n = factor.dim();
    let n_rec = prep.recorded_local.len();
    let a_priori: Vec<Matrix4<f64>> = (0..n_rec)
        .into_par_iter()
        .map(|c| {
            let mut block = Matrix4::zeros();
            let mut column = vec![0.0; n];
            for (s1, &f1) in active.iter().enumerate() {
                column.iter_mut().for_each(|v| *v = 0.0);
                column[c * k + s1] = 1.0;
                factor.solve_in_place(&mut column);
                for (s2, &f2) in active.iter().enumerate() {
                    block[(f2, f1)] = column[c * k + s2];
                }
            }
            block
        })
        .collect();
    let (sum_sq, components) = prep.plain_sum_of_squares(state);
    let unknowns = n + 3 * prep.point_active.iter().filter(|&&a| a).count();
    let redundancy = components as i64 - unknowns as i64;
    let variance_factor = (redundancy > 0).then(|| sum_sq / redundancy as f64);
    Ok(RecordingCovariances {
        a_priori,
        variance_factor,
        redundancy,
    })
}

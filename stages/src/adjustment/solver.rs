//! Levenberg–Marquardt with the tie points eliminated by a Schur complement (thesis 5.4; issue 6 "Solver").
//!
//! Normal equations `[U W; Wᵀ V]·[δc; δp] = [b_c; b_p]` (Marquardt damping: diagonals of U and V scaled by
//! 1 + λ). V is block-diagonal (3 × 3 per point), so the reduced camera system
//! `S·δc = b_c − W·V⁻¹·b_p`, `S = U − W·V⁻¹·Wᵀ`, is formed point by point and factorised in envelope storage
//! ([`super::skyline`]); then `δp_j = V_j⁻¹·(b_p,j − W_jᵀ·δc)`.
//!
//! Convergence (reported as [`Termination`]): an accepted step whose largest component is below
//! `step_tolerance`, or whose relative cost decrease is below `relative_cost_tolerance`; a zero cost; the
//! iteration limit; or the damping limit (no decreasing step found: the estimate is at a minimum to machine
//! precision).

use super::prepared::{Linearization, Prepared};
use super::problem::{AdjustError, LmOptions};
use super::residuals::State;
use super::skyline::SkylineMatrix;
use nalgebra::{Matrix3, Vector3};

/// Largest damping before giving up on finding a decreasing step.
const MAX_LAMBDA: f64 = 1e16;
/// Smallest damping kept after successful steps.
const MIN_LAMBDA: f64 = 1e-12;

/// Why a solve stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Termination {
    /// The largest parameter update fell below `step_tolerance`.
    StepSize,
    /// The relative cost decrease fell below `relative_cost_tolerance`.
    CostChange,
    /// The cost is exactly zero.
    ZeroCost,
    /// `max_iterations` linearisations were used.
    MaxIterations,
    /// No decreasing step even with the largest damping (minimum reached to machine precision).
    DampingLimit,
}

/// Outcome of one LM solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveReport {
    /// Accepted steps.
    pub iterations: usize,
    pub initial_cost: f64,
    pub final_cost: f64,
    pub termination: Termination,
}

/// A factorised reduced camera system and the per-point inverses used to form it.
struct ReducedSystem {
    factor: SkylineMatrix,
    rhs: Vec<f64>,
    point_inverse: Vec<Matrix3<f64>>,
}

/// Row envelope of the reduced camera matrix in parameter indices.
pub fn parameter_envelope(prep: &Prepared) -> Vec<usize> {
    let k = prep.parameterization.per_recording();
    let mut first = Vec::with_capacity(prep.first_recording.len() * k);
    for &f in &prep.first_recording {
        for _ in 0..k {
            first.push(f * k);
        }
    }
    first
}

/// Forms and factorises the damped reduced camera system. `Err(row)` on a non-positive pivot (parameter row),
/// `Err(usize::MAX)` on a singular point block.
fn reduce(
    prep: &Prepared,
    lin: &Linearization,
    lambda: f64,
    envelope: &[usize],
) -> Result<ReducedSystem, usize> {
    let active = &prep.parameterization.active;
    let k = active.len();
    let n_rec = prep.first_recording.len();
    let mut s = SkylineMatrix::zeros(envelope);
    let mut rhs = vec![0.0; n_rec * k];
    for c in 0..n_rec {
        let u = &lin.camera_diag[c];
        for (s1, &f1) in active.iter().enumerate() {
            rhs[c * k + s1] = lin.camera_rhs[c][f1];
            for (s2, &f2) in active.iter().enumerate().take(s1 + 1) {
                let mut v = u[(f1, f2)];
                if s1 == s2 {
                    v *= 1.0 + lambda;
                }
                s.add(c * k + s1, c * k + s2, v);
            }
        }
    }
    for &(row, col, ref block) in &lin.camera_off {
        for (s1, &f1) in active.iter().enumerate() {
            for (s2, &f2) in active.iter().enumerate() {
                s.add(row * k + s1, col * k + s2, block[(f1, f2)]);
            }
        }
    }
    let mut point_inverse = vec![Matrix3::zeros(); prep.point_active.len()];
    for (p, obs) in prep.point_observations.iter().enumerate() {
        if !prep.point_active[p] {
            continue;
        }
        let mut v = lin.point_diag[p];
        for d in 0..3 {
            v[(d, d)] *= 1.0 + lambda;
        }
        let inv = v.cholesky().ok_or(usize::MAX)?.inverse();
        point_inverse[p] = inv;
        let y = inv * lin.point_rhs[p];
        for &a in obs {
            let ca = prep.pano[a].recording;
            let wy = lin.couplings[a] * y;
            let wa_vinv = lin.couplings[a] * inv;
            for (s1, &f1) in active.iter().enumerate() {
                rhs[ca * k + s1] -= wy[f1];
            }
            for &b in obs {
                let cb = prep.pano[b].recording;
                if ca < cb {
                    continue;
                }
                let m = wa_vinv * lin.couplings[b].transpose();
                for (s1, &f1) in active.iter().enumerate() {
                    for (s2, &f2) in active.iter().enumerate() {
                        let (row, col) = (ca * k + s1, cb * k + s2);
                        if row >= col {
                            s.add(row, col, -m[(f1, f2)]);
                        }
                    }
                }
            }
        }
    }
    s.factorize()?;
    Ok(ReducedSystem {
        factor: s,
        rhs,
        point_inverse,
    })
}

/// Solves the damped normal equations: (camera step, point steps).
fn step(
    prep: &Prepared,
    lin: &Linearization,
    lambda: f64,
    envelope: &[usize],
) -> Result<(Vec<f64>, Vec<Vector3<f64>>), usize> {
    let ReducedSystem {
        factor,
        mut rhs,
        point_inverse,
    } = reduce(prep, lin, lambda, envelope)?;
    factor.solve_in_place(&mut rhs);
    let camera_step = rhs;
    let active = &prep.parameterization.active;
    let k = active.len();
    let mut point_step = vec![Vector3::zeros(); prep.point_active.len()];
    for (p, obs) in prep.point_observations.iter().enumerate() {
        if !prep.point_active[p] {
            continue;
        }
        let mut b = lin.point_rhs[p];
        for &a in obs {
            let c = prep.pano[a].recording;
            let w = &lin.couplings[a];
            for (slot, &f) in active.iter().enumerate() {
                let dc = camera_step[c * k + slot];
                for d in 0..3 {
                    b[d] -= w[(f, d)] * dc;
                }
            }
        }
        point_step[p] = point_inverse[p] * b;
    }
    Ok((camera_step, point_step))
}

/// The undamped reduced camera matrix at `state`, factorised (for the posterior covariance).
pub fn factorized_reduced_matrix(
    prep: &Prepared,
    state: &State,
) -> Result<SkylineMatrix, AdjustError> {
    let lin = prep.linearize(state);
    let envelope = parameter_envelope(prep);
    let k = prep.parameterization.per_recording();
    match reduce(prep, &lin, 0.0, &envelope) {
        Ok(r) => Ok(r.factor),
        Err(row) => Err(AdjustError::Singular {
            recording: if row == usize::MAX { 0 } else { row / k },
            parameter: if row == usize::MAX {
                0
            } else {
                prep.parameterization.active[row % k]
            },
        }),
    }
}

/// Minimises the cost of `prep` from `state` (updated in place).
pub fn solve(
    prep: &Prepared,
    state: &mut State,
    lm: &LmOptions,
) -> Result<SolveReport, AdjustError> {
    let envelope = parameter_envelope(prep);
    let k = prep.parameterization.per_recording();
    let mut lambda = lm.initial_lambda;
    let mut cost = prep.cost(state);
    let initial_cost = cost;
    let mut iterations = 0usize;
    let mut last_singular_row = None;
    let termination = 'outer: loop {
        if cost == 0.0 {
            break Termination::ZeroCost;
        }
        if iterations >= lm.max_iterations {
            break Termination::MaxIterations;
        }
        let lin = prep.linearize(state);
        loop {
            match step(prep, &lin, lambda, &envelope) {
                Ok((camera_step, point_step)) => {
                    let candidate = state.apply(&prep.parameterization, &camera_step, &point_step);
                    let new_cost = prep.cost(&candidate);
                    if new_cost < cost {
                        let step_max = camera_step
                            .iter()
                            .map(|v| v.abs())
                            .chain(point_step.iter().map(|v| v.amax()))
                            .fold(0.0, f64::max);
                        let relative_decrease = (cost - new_cost) / cost;
                        *state = candidate;
                        cost = new_cost;
                        iterations += 1;
                        lambda = (lambda * 0.1).max(MIN_LAMBDA);
                        if step_max < lm.step_tolerance {
                            break 'outer Termination::StepSize;
                        }
                        if relative_decrease < lm.relative_cost_tolerance {
                            break 'outer Termination::CostChange;
                        }
                        break;
                    }
                    lambda *= 10.0;
                }
                Err(row) => {
                    last_singular_row = Some(row);
                    lambda *= 10.0;
                }
            }
            if lambda > MAX_LAMBDA {
                if iterations == 0 {
                    if let Some(row) = last_singular_row.filter(|&r| r != usize::MAX) {
                        return Err(AdjustError::Singular {
                            recording: row / k,
                            parameter: prep.parameterization.active[row % k],
                        });
                    }
                }
                break 'outer Termination::DampingLimit;
            }
        }
    };
    Ok(SolveReport {
        iterations,
        initial_cost,
        final_cost: cost,
        termination,
    })
}

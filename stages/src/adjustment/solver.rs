//! Levenberg–Marquardt with the tie points eliminated by a Schur complement (thesis 5.4):
//! each step solves the damped normal equations through the sparse reduced camera system
//! ([`super::schur`]).
//!
//! Convergence (reported as [`Termination`]): an accepted step whose largest component is below
//! `step_tolerance`, or whose relative cost decrease is below `relative_cost_tolerance`; a rejected step that
//! raises the cost by less than `relative_cost_tolerance` (the estimate is at the minimum to the precision of
//! the cost: the previous estimate is kept); a zero cost; the iteration limit; or the damping limit (no
//! decreasing step found). A rejected step raises the damping tenfold and at least to its initial value.

use super::error::AdjustError;
use super::linearization::linearize;
use super::prepared::Prepared;
use super::problem::LmOptions;
use super::residuals::State;
use super::schur::{ReduceError, ReducedSystem};

/// Largest damping before giving up on finding a decreasing step.
const MAX_LAMBDA: f64 = 1e16;
/// Smallest damping kept after successful steps.
const MIN_LAMBDA: f64 = 1e-12;

/// The damping after a rejected step: ten times larger, and at least the initial damping. A damping far
/// below the initial one barely changes the step (the diagonal is scaled by 1 + λ), so raising it tenfold
/// from there would repeat nearly the same rejected step several times over.
fn raised(lambda: f64, initial_lambda: f64) -> f64 {
    (lambda * 10.0).max(initial_lambda)
}

/// Why a solve stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Termination {
    /// The largest parameter update fell below `step_tolerance`.
    StepSize,
    /// The relative cost change of a step fell below `relative_cost_tolerance` (a decrease, or an increase
    /// within it: then the step was not taken).
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

/// Minimises the cost of `prep` from `state` (updated in place).
pub fn solve(
    prep: &Prepared,
    state: &mut State,
    lm: &LmOptions,
) -> Result<SolveReport, AdjustError> {
    let mut lambda = lm.initial_lambda;
    let mut cost = prep.cost(state);
    let initial_cost = cost;
    let mut iterations = 0usize;
    let mut last_failure = None;
    let mut system = ReducedSystem::new(prep);
    let termination = 'outer: loop {
        if cost == 0.0 {
            break Termination::ZeroCost;
        }
        if iterations >= lm.max_iterations {
            break Termination::MaxIterations;
        }
        let lin = linearize(prep, state);
        loop {
            match system.reduce(prep, &lin, lambda) {
                Ok(()) => {
                    let (camera_step, point_step) = system.step(prep, &lin);
                    let candidate = state.apply(&camera_step, &point_step);
                    let new_cost = prep.cost(&candidate);
                    if new_cost < cost {
                        let step_max = camera_step
                            .iter()
                            .map(|v| v.amax())
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
                    if new_cost - cost <= lm.relative_cost_tolerance * cost {
                        // The step changes the cost by less than the tolerance, only upwards: the estimate
                        // is at the minimum to the precision of the cost; more damping would only repeat this.
                        break 'outer Termination::CostChange;
                    }
                    lambda = raised(lambda, lm.initial_lambda);
                }
                Err(failure) => {
                    last_failure = Some(failure);
                    lambda = raised(lambda, lm.initial_lambda);
                }
            }
            if lambda > MAX_LAMBDA {
                if iterations == 0 {
                    if let Some(ReduceError::Pivot(p)) = last_failure {
                        return Err(AdjustError::Singular {
                            recording: p.block,
                            parameter: p.component,
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

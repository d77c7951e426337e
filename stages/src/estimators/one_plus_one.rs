//! The (1+1) evolution strategy of ITK's `OnePlusOneEvolutionaryOptimizer` (Styner et al. 2000),
//! the optimiser of the fine MI patch registration (thesis 4.4.6, Droste et al. 2002).
//!
//! Parameters `x ∈ Rⁿ` with scales `s_i`; the search matrix starts as `A = diag(r0 / s_i)`. Each iteration draws
//! `z ~ N(0, I)`, evaluates the child `y = x + A·z`, keeps it if it improves (minimisation) and picks the
//! factor `a = growth` (success) or `a = shrink` (failure); then it stops if `‖A‖_F ≤ ε`, else it updates
//! `A ← A + ((a − 1)/‖z‖²)·(A z) zᵀ`, which stretches `A` along successful directions and shrinks it otherwise.
//! The cost function returns `None` for an invalid parameter vector (e.g. too little image overlap); such a
//! child counts as a failure. The normal deviates come from a [`SplitMix64`] seeded by the params, so a run is
//! reproducible bit for bit.

use crate::rng::SplitMix64;

crate::params! {
    /// Settings of the (1+1)-ES (ITK class defaults).
    pub struct OnePlusOneParams {
        /// Iteration limit (ITK: 100).
        max_iterations: usize = 100, min 1, max 10_000_000;
        /// Stop when the Frobenius norm of the search matrix falls to this (ITK: 1.5e-4), in parameter units.
        epsilon: f64 = 1.5e-4, above 0.0;
        /// Initial search radius r0 (ITK: 1.01), in parameter units (divided by the scales); larger than
        /// `epsilon`.
        initial_radius: f64 = 1.01;
        /// Search-matrix factor after a success (ITK: 1.05).
        growth_factor: f64 = 1.05, above 1.0;
        /// Search-matrix factor after a failure (ITK: 1.05^(−1/4) ≈ 0.98788).
        shrink_factor: f64 = 1.05f64.powf(-0.25), above 0.0, below 1.0;
        /// Seed of the normal generator.
        seed: u64 = 0;
        /// Record every iteration's parent vector and value in [`OnePlusOneResult::trace`].
        record_trace: bool = false;
    }
    check(p, v) {
        let bound = ("epsilon", p.epsilon);
        crate::params::check_above_field("initial_radius", p.initial_radius, bound, "", v);
    }
}

/// Outcome of a (1+1)-ES run.
#[derive(Clone, Debug, PartialEq)]
pub struct OnePlusOneResult {
    /// Best parameters found.
    pub x: Vec<f64>,
    /// Cost at `x` (the minimum found).
    pub value: f64,
    /// Iterations run (children evaluated).
    pub iterations: usize,
    /// Stopped by the ε rule (`‖A‖_F ≤ ε`) rather than the iteration limit.
    pub converged: bool,
    /// Children accepted.
    pub successes: usize,
    /// Per iteration (when `record_trace`): the parent after the iteration and its cost.
    pub trace: Vec<(Vec<f64>, f64)>,
}

/// Minimise `cost` from `x0` with per-parameter `scales` (same length as `x0`, finite and > 0; a wrong length
/// or scale makes the run return `None`, as does an invalid (`None`) or non-finite cost at `x0`).
pub fn minimize<F>(
    mut cost: F,
    x0: &[f64],
    scales: &[f64],
    p: &OnePlusOneParams,
) -> Option<OnePlusOneResult>
where
    F: FnMut(&[f64]) -> Option<f64>,
{
    let n = x0.len();
    if n == 0 || scales.len() != n || !scales.iter().all(|s| s.is_finite() && *s > 0.0) {
        return None;
    }
    let mut parent = x0.to_vec();
    let mut parent_value = cost(&parent).filter(|v| v.is_finite())?;
    // Search matrix A, row-major n × n.
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        a[i * n + i] = p.initial_radius / scales[i];
    }
    let mut rng = SplitMix64::new(p.seed);
    let mut z = vec![0.0; n];
    let mut delta = vec![0.0; n];
    let mut child = vec![0.0; n];
    let mut iterations = 0;
    let mut successes = 0;
    let mut converged = false;
    let mut trace = Vec::new();
    while iterations < p.max_iterations {
        iterations += 1;
        for zi in z.iter_mut() {
            *zi = rng.next_gaussian();
        }
        for i in 0..n {
            delta[i] = (0..n).map(|j| a[i * n + j] * z[j]).sum();
            child[i] = parent[i] + delta[i];
        }
        let improved = match cost(&child) {
            Some(v) if v.is_finite() && v < parent_value => {
                parent.copy_from_slice(&child);
                parent_value = v;
                true
            }
            _ => false,
        };
        if improved {
            successes += 1;
        }
        if p.record_trace {
            trace.push((parent.clone(), parent_value));
        }
        let alpha = if improved {
            p.growth_factor
        } else {
            p.shrink_factor
        };
        let frobenius = a.iter().map(|v| v * v).sum::<f64>().sqrt();
        if frobenius <= p.epsilon {
            converged = true;
            break;
        }
        let z_norm_sq: f64 = z.iter().map(|v| v * v).sum();
        if z_norm_sq > 0.0 {
            let k = (alpha - 1.0) / z_norm_sq;
            for i in 0..n {
                for j in 0..n {
                    a[i * n + j] += k * delta[i] * z[j];
                }
            }
        }
    }
    Some(OnePlusOneResult {
        x: parent,
        value: parent_value,
        iterations,
        converged,
        successes,
        trace,
    })
}

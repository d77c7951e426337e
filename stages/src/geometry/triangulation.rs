//! Multi-view ray triangulation with a covariance (Hartley & Zisserman 2004, ch. 12; thesis 3.4.4.5 and 3.4.5.4): the point
//! minimising the weighted sum of squared perpendicular distances to n ≥ 2 rays.
//!
//! Model: ray k has origin c_k, unit direction d_k and angular precision σ_k (radians). Its perpendicular
//! error at range r_k is r_k·σ_k, so its weight is `w_k = 1/(r_k σ_k)²`. With `P_k = I − d_k d_kᵀ` the
//! normal equations are `N·X = Σ w_k P_k c_k`, `N = Σ w_k P_k`. All sums are taken after shifting to a local
//! origin (the mean of the ray origins), because world coordinates are ≈ 10⁵ m. Ranges come from the
//! previous solution (first solution with range 1), iterated until the point moves less than 1e-12 of the
//! ray span (at most [`MAX_REWEIGHT_ITERATIONS`] times).
//!
//! Covariance: the weights are absolute (σ_k given a priori), so [`Triangulation::covariance_m2`] is the
//! **a-priori** covariance `N⁻¹` (σ0 = 1). The a-posteriori estimate is `σ̂0²·N⁻¹` with the variance factor
//! `σ̂0² = Σ w_k ‖P_k (X − c_k)‖² / (2n − 3)` (each ray gives two independent equations), reported in
//! [`Triangulation::variance_factor`]; σ̂0² ≈ 1 on average when the σ_k are right.

use super::local_frame::LocalOrigin;
use super::ray::Ray;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// The result of [`triangulate_rays`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Triangulation {
    /// The estimated point, world frame, metres.
    pub point_world: Vector3<f64>,
    /// A-priori covariance `N⁻¹` of the point (σ0 = 1), m². Multiply by `variance_factor` for a posteriori.
    pub covariance_m2: Matrix3<f64>,
    /// Perpendicular distance of the point from each ray, metres (same order as the input).
    pub residuals_m: Vec<f64>,
    /// Largest angle between any two ray directions, degrees (the best intersection angle).
    pub max_angle_deg: f64,
    /// A-posteriori variance factor σ̂0² = Σ w_k e_k² / (2n − 3).
    pub variance_factor: f64,
}

impl Triangulation {
    /// A-posteriori covariance `σ̂0²·N⁻¹`, m².
    pub fn covariance_a_posteriori_m2(&self) -> Matrix3<f64> {
        self.covariance_m2 * self.variance_factor
    }
}

/// Why a set of rays could not be triangulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TriangulationError {
    #[error("triangulation needs at least 2 rays, got {0}")]
    TooFewRays(usize),
    #[error("got {rays} rays but {sigmas} angular sigmas; pass one sigma per ray")]
    SigmaCountMismatch { rays: usize, sigmas: usize },
    #[error("ray {index}: angular sigma {sigma_rad} rad must be finite and > 0")]
    InvalidSigma { index: usize, sigma_rad: f64 },
    #[error("ray {index}: origin or direction is not finite, or the direction is not unit length")]
    InvalidRay { index: usize },
    #[error("rays are (nearly) parallel: condition number of the normal matrix {condition:.3e} is too large")]
    IllConditioned { condition: f64 },
    #[error("ray {index}: the intersection lies behind its origin (depth {depth_m:.3} m)")]
    BehindRay { index: usize, depth_m: f64 },
}

/// Largest accepted condition number of the normal matrix (≈ 1e-5 rad between two rays).
pub const MAX_CONDITION: f64 = 1e10;

/// Re-weighting iterations after the first solution (weights depend on the ranges).
pub const MAX_REWEIGHT_ITERATIONS: usize = 5;

/// Smallest range used in a weight, metres (a point at a ray origin would get an infinite weight).
const MIN_RANGE_M: f64 = 1e-6;

/// Triangulates `rays` (unit directions) with per-ray angular standard deviations `sigma_rad` (see the module
/// documentation for the weighting and the meaning of the covariance).
pub fn triangulate_rays(
    rays: &[Ray],
    sigma_rad: &[f64],
) -> Result<Triangulation, TriangulationError> {
    let n = rays.len();
    if n < 2 {
        return Err(TriangulationError::TooFewRays(n));
    }
    if sigma_rad.len() != n {
        return Err(TriangulationError::SigmaCountMismatch {
            rays: n,
            sigmas: sigma_rad.len(),
        });
    }
    for (index, (ray, &sigma)) in rays.iter().zip(sigma_rad).enumerate() {
        if !(sigma > 0.0 && sigma.is_finite()) {
            return Err(TriangulationError::InvalidSigma {
                index,
                sigma_rad: sigma,
            });
        }
        let finite = ray
            .origin_world
            .iter()
            .chain(ray.dir_world.iter())
            .all(|v| v.is_finite());
        if !finite || (ray.dir_world.norm() - 1.0).abs() > 1e-6 {
            return Err(TriangulationError::InvalidRay { index });
        }
    }
    let local = LocalOrigin::at_mean(rays.iter().map(|r| &r.origin_world))
        .ok_or(TriangulationError::TooFewRays(0))?;
    let span_m = rays
        .iter()
        .map(|r| local.to_local(&r.origin_world).norm())
        .fold(0.0, f64::max)
        .max(1.0);

    // First solution: unit ranges; then re-weight with the ranges of the current solution.
    let (mut x_local, mut n_inv) = solve(rays, sigma_rad, &local, |_| 1.0)?;
    for _ in 0..MAX_REWEIGHT_ITERATIONS {
        let ranges = |k: usize| {
            (x_local - local.to_local(&rays[k].origin_world))
                .norm()
                .max(MIN_RANGE_M)
        };
        let (x_new, n_inv_new) = solve(rays, sigma_rad, &local, ranges)?;
        let moved = (x_new - x_local).norm();
        x_local = x_new;
        n_inv = n_inv_new;
        if moved <= 1e-12 * span_m {
            break;
        }
    }

    let mut residuals_m = Vec::with_capacity(n);
    let mut weighted_sq = 0.0;
    for (k, (ray, &sigma)) in rays.iter().zip(sigma_rad).enumerate() {
        let to_point = x_local - local.to_local(&ray.origin_world);
        let depth_m = to_point.dot(&ray.dir_world);
        if !(depth_m > 0.0) {
            return Err(TriangulationError::BehindRay { index: k, depth_m });
        }
        let perpendicular = to_point - ray.dir_world * depth_m;
        let e = perpendicular.norm();
        let range_m = to_point.norm().max(MIN_RANGE_M);
        weighted_sq += (e / (range_m * sigma)).powi(2);
        residuals_m.push(e);
    }
    let variance_factor = weighted_sq / (2 * n - 3) as f64;

    Ok(Triangulation {
        point_world: local.to_world(&x_local),
        covariance_m2: n_inv,
        residuals_m,
        max_angle_deg: max_pairwise_angle_deg(rays),
        variance_factor,
    })
}

/// One weighted least-squares solve in the local frame; returns (X_local, N⁻¹).
fn solve(
    rays: &[Ray],
    sigma_rad: &[f64],
    local: &LocalOrigin,
    range_m: impl Fn(usize) -> f64,
) -> Result<(Vector3<f64>, Matrix3<f64>), TriangulationError> {
    let mut normal = Matrix3::zeros();
    let mut rhs = Vector3::zeros();
    for (k, (ray, &sigma)) in rays.iter().zip(sigma_rad).enumerate() {
        let d = &ray.dir_world;
        let projector = Matrix3::identity() - d * d.transpose();
        let sigma_m = range_m(k) * sigma;
        let w = 1.0 / (sigma_m * sigma_m);
        normal += projector * w;
        rhs += projector * local.to_local(&ray.origin_world) * w;
    }
    let eigen = normal.symmetric_eigen();
    let max_ev = eigen.eigenvalues.max();
    let min_ev = eigen.eigenvalues.min();
    let condition = if min_ev > 0.0 {
        max_ev / min_ev
    } else {
        f64::INFINITY
    };
    if !(condition <= MAX_CONDITION) {
        return Err(TriangulationError::IllConditioned { condition });
    }
    let chol = normal
        .cholesky()
        .ok_or(TriangulationError::IllConditioned { condition })?;
    Ok((chol.solve(&rhs), chol.inverse()))
}

/// Largest angle between two ray directions, degrees.
fn max_pairwise_angle_deg(rays: &[Ray]) -> f64 {
    let mut best = 0.0f64;
    for (i, a) in rays.iter().enumerate() {
        for b in &rays[i + 1..] {
            let angle = a
                .dir_world
                .cross(&b.dir_world)
                .norm()
                .atan2(a.dir_world.dot(&b.dir_world));
            best = best.max(angle);
        }
    }
    best.to_degrees()
}

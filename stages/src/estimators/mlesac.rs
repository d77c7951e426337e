//! MLESAC plane fitting (Torr & Zisserman 2000; Torr & Zisserman 2000), used to find façade planes in a triplet's
//! sparse cloud (thesis 4.4.2).
//!
//! Hypotheses come from three random points; each is scored by the negative log-likelihood of a mixture of a
//! Gaussian inlier error (σ fixed) and a uniform outlier density 1/ν (ν = bounding-box diagonal of the
//! points), the mixing weight γ estimated by a few EM iterations. Samples that are (nearly) collinear or whose
//! normal violates the angular constraint against a reference normal are rejected before scoring (cheap, and
//! it removes ground and roof planes early). The best hypothesis' inliers (|e| ≤ band) are refitted by total
//! least squares (smallest eigenvector of their covariance), twice, then once more on the "core" of the band
//! (|e| ≤ 2.5 robust σ from the MAD of the inlier residuals) so that points the wide band takes in at the
//! plane's edge (ground at a façade's foot) do not tilt it; the angular constraint is re-checked last.
//!
//! Stopping: the adaptive trial count N = ⌈ln(1 − p) / ln(1 − w³)⌉ (w = band-inlier fraction of the best
//! hypothesis) is compared with the number of *scored* hypotheses, so samples rejected by the angular
//! constraint do not end the search early; `max_trials` caps all samples drawn.
//!
//! Points are in the caller's local frame (subtract a [`crate::geometry::local_frame::LocalOrigin`] first:
//! world coordinates are ≈ 10⁵ m). Deterministic for a given `seed`.

use super::ransac::required_iterations;
use crate::geometry::bounding_box;
use crate::params::Params;
use crate::rng::SplitMix64;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};

crate::params! {
    /// Everything MLESAC plane fitting can be told.
    pub struct PlaneFitParams {
        /// Points with |n·p + d| at most this are inliers of the final plane (façade relief, thesis 4.4.2).
        inlier_band_m: f64 = 0.5, unit "m", above 0.0;
        /// σ of the Gaussian inlier error of the likelihood (the band is about 2σ).
        sigma_m: f64 = 0.25, unit "m", above 0.0;
        /// Hard cap on the 3-point samples drawn (as PCL).
        max_trials: usize = 10_000, min 1;
        /// Probability of drawing at least one all-inlier sample.
        confidence: f64 = 0.99, above 0.0, below 1.0;
        /// EM iterations for the mixing weight γ per hypothesis (as PCL).
        em_iterations: usize = 3, min 1, max 100;
        /// If set, the plane normal must lie within `max_angle_deg` of this vector (sign-free: n and −n are the
        /// same plane). Need not be unit length; must be finite and nonzero.
        reference_normal: Option<[f64; 3]> = None;
        /// Maximum angle between the normal and `±reference_normal` (thesis 4.4.2): a cone around the
        /// reference, so it bounds yaw and pitch together.
        max_angle_deg: f64 = 5.0, unit "deg", above 0.0, max 90.0;
        /// Seed of the sampling RNG.
        seed: u64 = 0;
    }
    check(p, v) {
        if let Some(r) = p.reference_normal {
            let norm = Vector3::from(r).norm();
            if !(norm.is_finite() && norm > 0.0) {
                v.push(crate::params::Violation::new(
                    "reference_normal",
                    format!("must be a finite nonzero vector or absent, got {r:?}"),
                ));
            }
        }
    }
}

/// A fitted plane `normal · p + d = 0` (in the caller's frame) with its inliers and the likelihood figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlaneFit {
    /// Unit normal; with a reference normal it points to the reference's side (n · ref ≥ 0).
    pub normal: [f64; 3],
    pub d: f64,
    /// Indices (ascending) into the input of the points within the inlier band of the final plane.
    pub inliers: Vec<usize>,
    /// EM mixing weight (estimated inlier fraction) for the final plane.
    pub gamma: f64,
    /// −log-likelihood of all points under the final plane's mixture model.
    pub neg_log_likelihood: f64,
    /// Samples drawn (degenerate and angle-rejected ones included).
    pub trials: usize,
}

/// Relative threshold on |(p2 − p1) × (p3 − p1)| / (|p2 − p1|·|p3 − p1|) (the sine of the sample's angle)
/// below which a sample counts as collinear.
const MIN_SAMPLE_SINE: f64 = 1e-6;

/// At most this many core refits (see the module documentation).
const CORE_REFITS: usize = 10;

/// EM stops when γ changes by less than this (Torr & Zisserman 2000).
const EM_TOLERANCE: f64 = 1e-4;

/// Cap on the EM iterations for the final plane's reported γ.
const FINAL_EM_MAX_ITERATIONS: usize = 200;

/// The plane through three points, `(unit normal, d)`; `None` if they are (nearly) collinear or coincide.
pub fn plane_from_three(
    p1: &[f64; 3],
    p2: &[f64; 3],
    p3: &[f64; 3],
) -> Option<(Vector3<f64>, f64)> {
    let a = Vector3::from(*p1);
    let e1 = Vector3::from(*p2) - a;
    let e2 = Vector3::from(*p3) - a;
    let cross = e1.cross(&e2);
    let scale = e1.norm() * e2.norm();
    let c = cross.norm();
    if !(scale > 0.0) || !(c > MIN_SAMPLE_SINE * scale) {
        return None;
    }
    let n = cross / c;
    Some((n, -n.dot(&a)))
}

/// Sign-free angle between a normal and a reference direction, degrees.
pub fn axis_angle_deg(normal: &Vector3<f64>, reference: &Vector3<f64>) -> f64 {
    let c = normal.dot(reference).abs() / (normal.norm() * reference.norm());
    c.clamp(0.0, 1.0).acos().to_degrees()
}

/// Total-least-squares plane through `points[idx]`: (unit normal = smallest eigenvector of the covariance
/// about the centroid, d); `None` for fewer than 3 points or a degenerate set.
pub fn fit_plane_tls(points: &[[f64; 3]], idx: &[usize]) -> Option<(Vector3<f64>, f64)> {
    if idx.len() < 3 {
        return None;
    }
    let mut centroid = Vector3::zeros();
    for &i in idx {
        centroid += Vector3::from(points[i]);
    }
    centroid /= idx.len() as f64;
    let mut cov = Matrix3::zeros();
    for &i in idx {
        let q = Vector3::from(points[i]) - centroid;
        cov += q * q.transpose();
    }
    let eig = SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    // A plane needs two clearly nonzero in-plane spreads.
    if !(eig.eigenvalues[order[1]] > 1e-12 * eig.eigenvalues[order[2]].max(1e-300)) {
        return None;
    }
    let n: Vector3<f64> = eig.eigenvectors.column(order[0]).into_owned();
    let norm = n.norm();
    if !(norm > 0.0) || !norm.is_finite() {
        return None;
    }
    let n = n / norm;
    Some((n, -n.dot(&centroid)))
}

/// EM estimate of the mixing weight γ (σ fixed, start 0.5) from the Gaussian densities `g[k]` of the
/// residuals and the outlier density `outlier_density` (1/ν): at most `iterations` steps, stopping early when
/// γ changes by less than `tolerance`; returns (γ, −log-likelihood).
fn em_score(g: &[f64], outlier_density: f64, iterations: usize, tolerance: f64) -> (f64, f64) {
    let n = g.len() as f64;
    let mut gamma: f64 = 0.5;
    for _ in 0..iterations {
        let previous = gamma;
        let mut sum_z = 0.0;
        for &gk in g {
            let inl = gamma * gk;
            let denom = inl + (1.0 - gamma) * outlier_density;
            if denom > 0.0 {
                sum_z += inl / denom;
            }
        }
        gamma = (sum_z / n).clamp(0.0, 1.0);
        if (gamma - previous).abs() < tolerance {
            break;
        }
    }
    let mut nll = 0.0;
    for &gk in g {
        let l = gamma * gk + (1.0 - gamma) * outlier_density;
        nll -= l.max(f64::MIN_POSITIVE).ln();
    }
    (gamma, nll)
}

/// Fills `g` with the Gaussian densities of the residuals of plane (n, d) and returns the number of points
/// within `band`.
fn gaussian_densities(
    points: &[[f64; 3]],
    n: &Vector3<f64>,
    d: f64,
    sigma: f64,
    band: f64,
    g: &mut [f64],
) -> usize {
    let inv_two_var = 1.0 / (2.0 * sigma * sigma);
    let norm = 1.0 / ((2.0 * std::f64::consts::PI).sqrt() * sigma);
    let mut within = 0;
    for (gk, p) in g.iter_mut().zip(points) {
        let e = n.x * p[0] + n.y * p[1] + n.z * p[2] + d;
        *gk = norm * (-e * e * inv_two_var).exp();
        if e.abs() <= band {
            within += 1;
        }
    }
    within
}

fn band_inliers(points: &[[f64; 3]], n: &Vector3<f64>, d: f64, band: f64) -> Vec<usize> {
    points
        .iter()
        .enumerate()
        .filter(|(_, p)| (n.dot(&Vector3::from(**p)) + d).abs() <= band)
        .map(|(i, _)| i)
        .collect()
}

/// Fits a plane to `points` (local frame, metres) by MLESAC (module documentation). `None` if the parameters
/// are invalid, there are fewer than 3 points or non-finite coordinates, no sample gave a valid hypothesis
/// (all collinear, or none within the angular constraint), or the refitted plane leaves the constraint.
pub fn fit_plane_mlesac(points: &[[f64; 3]], p: &PlaneFitParams) -> Option<PlaneFit> {
    if p.validate().is_err() || points.len() < 3 {
        return None;
    }
    if !points.iter().all(|q| q.iter().all(|c| c.is_finite())) {
        return None;
    }
    let reference = p.reference_normal.map(|r| Vector3::from(r).normalize());
    let angle_ok = |n: &Vector3<f64>| {
        reference
            .as_ref()
            .is_none_or(|r| axis_angle_deg(n, r) <= p.max_angle_deg)
    };
    // Outlier density 1/ν, ν = bounding-box diagonal (PCL).
    let (lo, hi) = bounding_box(points);
    let nu = Vector3::new(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]).norm();
    if !(nu > 0.0) {
        return None;
    }
    let outlier_density = 1.0 / nu;

    let mut rng = SplitMix64::new(p.seed);
    let mut g = vec![0.0; points.len()];
    let mut sample = [0usize; 3];
    let mut best: Option<(Vector3<f64>, f64, f64)> = None; // (n, d, nll)
    let mut needed = p.max_trials;
    let mut scored = 0usize;
    let mut trials = 0usize;
    while trials < p.max_trials && scored < needed {
        trials += 1;
        rng.sample_distinct(points.len(), &mut sample);
        let Some((n, d)) =
            plane_from_three(&points[sample[0]], &points[sample[1]], &points[sample[2]])
        else {
            continue;
        };
        if !angle_ok(&n) {
            continue;
        }
        scored += 1;
        let within = gaussian_densities(points, &n, d, p.sigma_m, p.inlier_band_m, &mut g);
        let (_, nll) = em_score(&g, outlier_density, p.em_iterations, EM_TOLERANCE);
        if best.as_ref().is_none_or(|b| nll < b.2) {
            best = Some((n, d, nll));
            let w = within as f64 / points.len() as f64;
            needed = required_iterations(p.confidence, w, 3).min(p.max_trials);
        }
    }
    let (mut n, mut d, _) = best?;
    // Total-least-squares refit on the band inliers, twice (the second pass uses the refitted plane's band).
    for _ in 0..2 {
        let inl = band_inliers(points, &n, d, p.inlier_band_m);
        let (n2, d2) = fit_plane_tls(points, &inl)?;
        n = n2;
        d = d2;
    }
    // Core refit: the band tolerates façade relief (and takes in e.g. ground points at the façade's foot,
    // which tilt a plain band refit); refit on the band inliers within 2.5 robust σ (1.4826·MAD of their
    // residuals) of the plane, so the plane follows the dominant surface.
    // Repeated (the core of a tilted plane still holds some edge points) until the core set is stable.
    let mut previous_core: Vec<usize> = Vec::new();
    for _ in 0..CORE_REFITS {
        let inl = band_inliers(points, &n, d, p.inlier_band_m);
        let mut abs_res: Vec<f64> = inl
            .iter()
            .map(|&i| (n.dot(&Vector3::from(points[i])) + d).abs())
            .collect();
        abs_res.sort_by(f64::total_cmp);
        let Some(&mad) = abs_res.get(abs_res.len() / 2) else {
            break;
        };
        let core_band = (2.5 * 1.4826 * mad).clamp(0.01 * p.inlier_band_m, p.inlier_band_m);
        let core: Vec<usize> = inl
            .iter()
            .copied()
            .filter(|&i| (n.dot(&Vector3::from(points[i])) + d).abs() <= core_band)
            .collect();
        if core == previous_core {
            break;
        }
        let Some((n2, d2)) = fit_plane_tls(points, &core) else {
            break;
        };
        n = n2;
        d = d2;
        previous_core = core;
    }
    if !angle_ok(&n) {
        return None;
    }
    if let Some(r) = reference {
        if n.dot(&r) < 0.0 {
            n = -n;
            d = -d;
        }
    }
    let inliers = band_inliers(points, &n, d, p.inlier_band_m);
    gaussian_densities(points, &n, d, p.sigma_m, p.inlier_band_m, &mut g);
    // The reported γ is EM run to convergence (the scoring used `em_iterations` steps).
    let (gamma, neg_log_likelihood) =
        em_score(&g, outlier_density, FINAL_EM_MAX_ITERATIONS, EM_TOLERANCE);
    Some(PlaneFit {
        normal: [n.x, n.y, n.z],
        d,
        inliers,
        gamma,
        neg_log_likelihood,
        trials,
    })
}

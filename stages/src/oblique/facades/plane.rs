//! Plane fitting per side of the trajectory (thesis 4.4.2) and the plane's local frame (thesis eq. 4/7).
//!
//! The side's sparse points (local frame around the centre recording) are fitted by MLESAC with the side's
//! reference vector; a plane needs `min_points` inliers. Up to `max_planes_per_side` planes are found by
//! removing each plane's inliers and fitting again. The normal is oriented towards the centre recording; a
//! plane that passes within the inlier band of the recording is not a façade beside the street and ends the
//! search on that side.

use crate::estimators::mlesac::{fit_plane_mlesac, PlaneFitParams};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// A plane found on one side, in the local frame (origin at the centre recording).
#[derive(Clone, Debug, PartialEq)]
pub struct LocalPlane {
    /// Unit normal pointing towards the centre recording.
    pub normal: Vector3<f64>,
    /// Centroid of the inliers (p_avg), local frame, m.
    pub centroid: Vector3<f64>,
    /// In-plane axes (eq. 4/7): `axis_u` roughly horizontal, `axis_v` roughly up, `axis_u × axis_v = normal`.
    pub axis_u: Vector3<f64>,
    pub axis_v: Vector3<f64>,
    /// Indices into the caller's point list (ascending).
    pub inliers: Vec<usize>,
}

/// The local patch frame of thesis eq. 4/7: the covariance of the inliers about their centroid, its two
/// largest eigenvectors projected into the plane and orthonormalised. Of the two, the one closer to
/// horizontal becomes `axis_u` (along the façade), the other `axis_v` with a non-negative up component, and
/// `axis_u = axis_v × normal` so that `axis_u × axis_v = normal` (right-handed). `None` if the inliers do not
/// span the plane.
pub fn plane_axes(
    points: &[Vector3<f64>],
    centroid: &Vector3<f64>,
    normal: &Vector3<f64>,
) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let mut cov = Matrix3::zeros();
    for p in points {
        let q = p - centroid;
        cov += q * q.transpose();
    }
    let eig = SymmetricEigen::new(cov);
    let largest = (0..3).max_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]))?;
    let e: Vector3<f64> = eig.eigenvectors.column(largest).into_owned();
    let projected = e - normal * e.dot(normal);
    let norm = projected.norm();
    if !(norm > 1e-9) {
        return None;
    }
    let a = projected / norm;
    let b = normal.cross(&a);
    let mut v = if a.z.abs() > b.z.abs() { a } else { b };
    if v.z < 0.0 {
        v = -v;
    }
    let u = v.cross(normal);
    Some((u, v))
}

/// Settings of [`fit_side_planes`] (taken from `FacadeParams`).
#[derive(Clone, Debug, PartialEq)]
pub struct SidePlaneSettings {
    pub reference: Vector3<f64>,
    pub max_angle_deg: f64,
    pub inlier_band_m: f64,
    pub min_points: usize,
    pub max_planes: usize,
    pub max_trials: usize,
    pub confidence: f64,
    pub em_iterations: usize,
}

/// Fits up to `max_planes` planes to `points` (local frame; the centre recording at `recording`), each with
/// its own seed from `seed_of(plane index)`. Planes come in the order found.
pub fn fit_side_planes(
    points: &[Vector3<f64>],
    recording: &Vector3<f64>,
    s: &SidePlaneSettings,
    seed_of: impl Fn(usize) -> u64,
) -> Vec<LocalPlane> {
    let mut remaining: Vec<usize> = (0..points.len()).collect();
    let mut planes = Vec::new();
    let mut sub: Vec<[f64; 3]> = Vec::with_capacity(points.len());
    for k in 0..s.max_planes {
        if remaining.len() < s.min_points.max(3) {
            break;
        }
        sub.clear();
        sub.extend(
            remaining
                .iter()
                .map(|&i| [points[i].x, points[i].y, points[i].z]),
        );
        let params = PlaneFitParams {
            inlier_band_m: s.inlier_band_m,
            sigma_m: 0.5 * s.inlier_band_m,
            max_trials: s.max_trials,
            confidence: s.confidence,
            em_iterations: s.em_iterations,
            reference_normal: Some([s.reference.x, s.reference.y, s.reference.z]),
            max_angle_deg: s.max_angle_deg,
            seed: seed_of(k),
        };
        let Some(fit) = fit_plane_mlesac(&sub, &params) else {
            break;
        };
        if fit.inliers.len() < s.min_points {
            break;
        }
        let inliers: Vec<usize> = fit.inliers.iter().map(|&j| remaining[j]).collect();
        let mut normal = Vector3::from(fit.normal);
        let inlier_points: Vec<Vector3<f64>> = inliers.iter().map(|&i| points[i]).collect();
        let centroid = inlier_points.iter().sum::<Vector3<f64>>() / inlier_points.len() as f64;
        let recording_distance = normal.dot(&(recording - centroid));
        if !(recording_distance.abs() > s.inlier_band_m) {
            break;
        }
        if recording_distance < 0.0 {
            normal = -normal;
        }
        let Some((axis_u, axis_v)) = plane_axes(&inlier_points, &centroid, &normal) else {
            break;
        };
        // Remove the inliers (both lists ascending) before looking for the next plane.
        let mut next = Vec::with_capacity(remaining.len() - inliers.len());
        let mut it = inliers.iter().peekable();
        for &i in &remaining {
            if it.peek() == Some(&&i) {
                it.next();
            } else {
                next.push(i);
            }
        }
        remaining = next;
        planes.push(LocalPlane {
            normal,
            centroid,
            axis_u,
            axis_v,
            inliers,
        });
    }
    planes
}

//! The positions of a triplet's outer recordings relative to its centre, measured from the triplet's own
//! three-view tracks.
//!
//! The thesis (4.4.1) takes the relative orientation of a panorama triplet from the recorded poses, which the
//! mobile-mapping system's relative accuracy makes good to centimetres in open sky. In a GNSS outage, or
//! where the signal returns, consecutive recorded positions can be off relative to each other by decimetres:
//! a 0.4 m error between recordings 5 m apart moves the image of a façade point 10 m away by 2.3°, 13 pixels
//! of a 512-px, 90° view, and the trifocal check (2 px) then rejects the right tracks with the wrong ones. The
//! recorded rotations are kept (an INS holds them to hundredths of a degree from one recording to the next);
//! the two outer camera centres are estimated.
//!
//! The estimate minimises, over the corrections δ₁ and δ₃ of the outer centres (the centre recording stays
//! where it was recorded: the absolute error is the adjustment's business), the robust sum over the tracks of
//! their rays' angular misses from the track's least-squares point, plus a prior `|δ|² / σ²` that holds what
//! the tracks cannot tell (the triplet's scale, and directions the façade's geometry leaves weak) at the
//! recorded positions. Robust: Cauchy weights whose scale shrinks from `scales_rad[0]` to the last entry
//! (graduated non-convexity), so the wrong tracks of a wide first matching fall away as the geometry
//! sharpens. Gauss–Newton with a numerical Jacobian of the six unknowns; deterministic.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// One three-view track: its unit bearings from the three cameras, world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseTrack {
    pub bearings_world: [Vector3<f64>; 3],
}

/// How the relative positions are estimated.
#[derive(Clone, Debug, PartialEq)]
pub struct RelativePoseSettings {
    /// σ of the prior on each outer centre's correction, per axis, metres.
    pub prior_sigma_m: f64,
    /// σ of one ray's direction, rad (the weight of the tracks against the prior).
    pub ray_sigma_rad: f64,
    /// Cauchy scales of the graduated robust fit, rad, largest first; the last one is also the inlier bound.
    pub scales_rad: Vec<f64>,
    /// Fewest tracks within the last scale for the estimate to be used.
    pub min_tracks: usize,
    /// A correction larger than this (either outer centre) is not believed: the recorded positions are kept.
    pub max_correction_m: f64,
}

/// The estimated corrections.
#[derive(Clone, Debug, PartialEq)]
pub struct RelativePose {
    /// Corrections of the three camera centres, world frame, metres (the centre's is zero).
    pub corrections_m: [Vector3<f64>; 3],
    /// Tracks whose every ray misses the track's point by at most the last scale.
    pub inliers: usize,
}

/// Gauss–Newton iterations per robust scale.
const ITERATIONS_PER_SCALE: usize = 4;
/// Step of the numerical derivative, metres.
const STEP_M: f64 = 1e-4;

/// Each ray's angular miss of the least-squares point of three rays from `centres` along `bearings` (unit):
/// the vector `(X − C) × d / |X − C|`, perpendicular to the ray, of length the sine of the miss (9 smooth
/// residuals per track); `None` when the rays are (nearly) parallel or the point lies behind a camera.
fn track_residuals(
    centres: &[Vector3<f64>; 3],
    bearings: &[Vector3<f64>; 3],
) -> Option<SVector<f64, 9>> {
    let mut a = Matrix3::zeros();
    let mut b = Vector3::zeros();
    for (c, d) in centres.iter().zip(bearings) {
        let p = Matrix3::identity() - d * d.transpose();
        a += p;
        b += p * c;
    }
    let x = a.try_inverse()? * b;
    let mut r = SVector::<f64, 9>::zeros();
    for (k, (c, d)) in centres.iter().zip(bearings).enumerate() {
        let v = x - c;
        if !(v.dot(d) > 0.0) {
            return None;
        }
        r.fixed_rows_mut::<3>(3 * k)
            .copy_from(&(v.cross(d) / v.norm()));
    }
    Some(r)
}

/// Every track's residuals ([`track_residuals`]), `None` where it cannot be triangulated.
fn all_residuals(
    centres: &[Vector3<f64>; 3],
    tracks: &[PoseTrack],
) -> Vec<Option<SVector<f64, 9>>> {
    tracks
        .iter()
        .map(|t| track_residuals(centres, &t.bearings_world))
        .collect()
}

/// The largest squared miss of one track's rays, rad².
fn worst_miss2(r: &SVector<f64, 9>) -> f64 {
    (0..3)
        .map(|k| r.fixed_rows::<3>(3 * k).norm_squared())
        .fold(0.0, f64::max)
}

/// The six unknowns applied to the recorded centres.
fn centres_with(recorded: &[Vector3<f64>; 3], x: &SVector<f64, 6>) -> [Vector3<f64>; 3] {
    [
        recorded[0] + Vector3::new(x[0], x[1], x[2]),
        recorded[1],
        recorded[2] + Vector3::new(x[3], x[4], x[5]),
    ]
}

/// Estimates the corrections of the outer centres of `recorded` (trajectory order, world frame; any common
/// origin, e.g. the centre recording) from `tracks`. `None` when too few tracks agree or the correction is
/// larger than `max_correction_m`.
pub fn estimate_relative_pose(
    recorded: &[Vector3<f64>; 3],
    tracks: &[PoseTrack],
    s: &RelativePoseSettings,
) -> Option<RelativePose> {
    let last_scale = *s.scales_rad.last()?;
    if tracks.len() < s.min_tracks {
        return None;
    }
    let mut x = SVector::<f64, 6>::zeros();
    let prior_w = 1.0 / (s.prior_sigma_m * s.prior_sigma_m);
    let ray_w = 1.0 / (s.ray_sigma_rad * s.ray_sigma_rad);
    for &scale in &s.scales_rad {
        for _ in 0..ITERATIONS_PER_SCALE {
            let base = all_residuals(&centres_with(recorded, &x), tracks);
            // Numerical Jacobian of every track's residuals by each unknown.
            let shifted: Vec<Vec<Option<SVector<f64, 9>>>> = (0..6)
                .map(|j| {
                    let mut xj = x;
                    xj[j] += STEP_M;
                    all_residuals(&centres_with(recorded, &xj), tracks)
                })
                .collect();
            let mut n = SMatrix::<f64, 6, 6>::identity() * prior_w;
            let mut g = -x * prior_w;
            for (i, r) in base.iter().enumerate() {
                let Some(r) = r else { continue };
                // Cauchy weight of the track by its squared misses summed.
                let w = ray_w / (1.0 + r.norm_squared() / (scale * scale));
                let mut jac = SMatrix::<f64, 9, 6>::zeros();
                let mut complete = true;
                for (j, sh) in shifted.iter().enumerate() {
                    match &sh[i] {
                        Some(rj) => jac.set_column(j, &((rj - r) / STEP_M)),
                        None => complete = false,
                    }
                }
                if !complete {
                    continue;
                }
                n += jac.transpose() * jac * w;
                g -= jac.transpose() * r * w;
            }
            let step = n.cholesky()?.solve(&g);
            if !step.iter().all(|v| v.is_finite()) {
                return None;
            }
            x += step;
            if step.norm() < 1e-5 {
                break;
            }
        }
    }
    let corrections_m = [
        Vector3::new(x[0], x[1], x[2]),
        Vector3::zeros(),
        Vector3::new(x[3], x[4], x[5]),
    ];
    if corrections_m
        .iter()
        .any(|c| !(c.norm() <= s.max_correction_m))
    {
        return None;
    }
    let bound = last_scale * last_scale;
    let inliers = all_residuals(&centres_with(recorded, &x), tracks)
        .iter()
        .filter(|r| r.is_some_and(|r| worst_miss2(&r) <= bound))
        .count();
    (inliers >= s.min_tracks).then_some(RelativePose {
        corrections_m,
        inliers,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> RelativePoseSettings {
        let px = (90.0f64 / 512.0).to_radians();
        RelativePoseSettings {
            prior_sigma_m: 0.5,
            ray_sigma_rad: 0.5 * px,
            scales_rad: vec![16.0 * px, 8.0 * px, 4.0 * px, 2.0 * px],
            min_tracks: 12,
            max_correction_m: 2.0,
        }
    }

    /// Façade points on both sides of a street along +y: 5–12 m to the left and right, 1–10 m up.
    fn facades(n: usize) -> Vec<Vector3<f64>> {
        (0..n)
            .map(|i| {
                let f = i as f64;
                let side = if i % 2 == 0 { -1.0 } else { 1.0 };
                Vector3::new(
                    side * (5.0 + (f * 0.37).rem_euclid(7.0)),
                    -6.0 + (f * 1.13).rem_euclid(17.0),
                    1.0 + (f * 0.71).rem_euclid(9.0),
                )
            })
            .collect()
    }

    fn tracks(centres: &[Vector3<f64>; 3], points: &[Vector3<f64>]) -> Vec<PoseTrack> {
        points
            .iter()
            .map(|p| PoseTrack {
                bearings_world: std::array::from_fn(|k| (p - centres[k]).normalize()),
            })
            .collect()
    }

    #[test]
    fn recorded_positions_off_by_decimetres_are_corrected() {
        let truth = [
            Vector3::new(0.0, -5.0, 2.5),
            Vector3::new(0.0, 0.0, 2.5),
            Vector3::new(0.0, 5.0, 2.5),
        ];
        // Recorded: the outer recordings off by 0.4 m across and 0.3 m along / 0.1 m up and 0.35 m across.
        let recorded = [
            truth[0] + Vector3::new(0.4, 0.3, 0.0),
            truth[1],
            truth[2] + Vector3::new(-0.35, 0.0, 0.1),
        ];
        let pts = facades(120);
        let mut data = tracks(&truth, &pts);
        // A fifth of the tracks are wrong: view 3 saw a window 1.2 m along the façade.
        for i in (0..data.len()).step_by(5) {
            let wrong = pts[i] + Vector3::new(0.0, 1.2, 0.0);
            data[i].bearings_world[2] = (wrong - truth[2]).normalize();
        }
        let r = estimate_relative_pose(&recorded, &data, &settings()).unwrap();
        let fixed = [
            recorded[0] + r.corrections_m[0],
            recorded[1],
            recorded[2] + r.corrections_m[2],
        ];
        // The baseline directions come back to well within a pixel (0.18°); the triplet's scale is what the
        // prior holds, so lengths are compared as a ratio.
        for (a, b) in [(0, 1), (2, 1)] {
            let est = (fixed[a] - fixed[b]).normalize();
            let tru = (truth[a] - truth[b]).normalize();
            let angle = est.dot(&tru).clamp(-1.0, 1.0).acos().to_degrees();
            assert!(angle < 0.05, "{a}: {angle}°");
        }
        let len_ratio = (fixed[0] - fixed[1]).norm() / (fixed[2] - fixed[1]).norm();
        let true_ratio = (truth[0] - truth[1]).norm() / (truth[2] - truth[1]).norm();
        assert!((len_ratio / true_ratio - 1.0).abs() < 0.01, "{len_ratio}");
        assert_eq!(r.inliers, 96);
    }

    #[test]
    fn exact_recorded_positions_stay_and_too_few_tracks_give_nothing() {
        let truth = [
            Vector3::new(100.0, 195.0, 2.5),
            Vector3::new(100.0, 200.0, 2.5),
            Vector3::new(100.2, 205.0, 2.5),
        ];
        let data = tracks(&truth, &facades(40));
        let r = estimate_relative_pose(&truth, &data, &settings()).unwrap();
        assert!(
            r.corrections_m.iter().all(|c| c.norm() < 1e-6),
            "{:?}",
            r.corrections_m
        );
        assert_eq!(r.inliers, 40);
        assert!(estimate_relative_pose(&truth, &data[..11], &settings()).is_none());
    }
}

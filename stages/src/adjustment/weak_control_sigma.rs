//! The σ of weak orthophoto control estimated from the campaign's own recordings that observe strong and weak
//! control alike.
//!
//! An orthophoto control point's stated σ is the orthophoto's stated accuracy and the matching σ of a peak
//! (`orthophoto::control`). A weak peak — one that passed only because several weak peaks of its recording
//! agree (`orthophoto::corroborate`) — can be displaced by more than that: under tree crowns and where the
//! shadows of the two epochs differ, the weak peaks of a recording are displaced alike, by decimetres, and they
//! agree with each other because they are displaced alike. Their scatter about the truth is not known from the
//! peak, but the campaign measures it: two control points observed from the same recording imply the same
//! correction of it up to their own errors (the recording's error is common to both), so where a recording
//! observes strong and weak control, each weak point's correction minus the median correction of the strong
//! points of its recordings is a sample of the weak points' error (plus the strong median's, small, and the
//! part of the recordings' relative errors by which two points triangulated from different recordings differ,
//! which the adjustment removes and so makes the estimate an upper bound). The RMS of those differences per
//! axis is the weak points' σ ([`estimate`]).
//!
//! With it, each weak point's horizontal σ becomes at least that σ; and because a recording's weak peaks are
//! displaced alike, the weak points observed first from one recording count together as one observation of
//! that σ: each one's σ is multiplied by √(their number) ([`weak_covariances`]). A recording controlled only by
//! weak peaks then holds its correction with about the measured σ, and the panorama tie points and the strong
//! control of the recordings around it weigh against it, instead of a dozen agreeing weak peaks outweighing
//! everything near them.

use super::weak_control::{median2, ControlEvidence};
use nalgebra::{Matrix3, Vector2};
use serde::{Deserialize, Serialize};

/// Fewest weak points with strong control in their recordings for an estimate: fewer say too little about
/// the weak peaks' scatter, and the stated σ is kept.
pub const MIN_SAMPLES: usize = 5;

/// What the estimate found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WeakSigmaEstimate {
    /// Weak control points whose recordings also observe strong control (the samples).
    pub samples: usize,
    /// The weak points' horizontal σ per axis, m; `None` with fewer than [`MIN_SAMPLES`] samples.
    pub sigma_m: Option<f64>,
}

/// The weak points' σ per axis from the points `keep` still uses: each kept weak point whose recordings
/// observe kept strong control gives a sample (its correction minus the median correction of those strong
/// points); σ = √(Σ|sample|² / (2n)).
pub fn estimate(points: &[ControlEvidence], keep: &[bool]) -> WeakSigmaEstimate {
    let strong: Vec<&ControlEvidence> = points
        .iter()
        .zip(keep)
        .filter(|(p, &k)| k && !p.weak)
        .map(|(p, _)| p)
        .collect();
    let samples: Vec<Vector2<f64>> = points
        .iter()
        .zip(keep)
        .filter(|(p, &k)| k && p.weak)
        .filter_map(|(p, _)| {
            let shared: Vec<Vector2<f64>> = strong
                .iter()
                .filter(|s| s.recordings.iter().any(|r| p.recordings.contains(r)))
                .map(|s| s.correction_m)
                .collect();
            (!shared.is_empty()).then(|| p.correction_m - median2(&shared))
        })
        .collect();
    let n = samples.len();
    let sigma_m = (n >= MIN_SAMPLES).then(|| {
        let sum_sq: f64 = samples.iter().map(|s| s.norm_squared()).sum();
        (sum_sq / (2.0 * n as f64)).sqrt()
    });
    WeakSigmaEstimate {
        samples: n,
        sigma_m,
    }
}

/// The recording a weak point is grouped by: the first (in time) of the recordings observing it.
fn group_of(p: &ControlEvidence) -> Option<usize> {
    p.recordings.iter().min().copied()
}

/// The covariances of the control points (parallel to `points`, `covariances_m2` on entry) with the weak
/// points' horizontal σ raised to at least `sigma_m`, times √(the number of kept weak points grouped with it:
/// observed first from the same recording). Strong and dropped points keep theirs.
pub fn weak_covariances(
    points: &[ControlEvidence],
    keep: &[bool],
    covariances_m2: &[Matrix3<f64>],
    sigma_m: f64,
) -> Vec<Matrix3<f64>> {
    let mut per_group = std::collections::HashMap::new();
    for (p, _) in points.iter().zip(keep).filter(|(p, &k)| k && p.weak) {
        *per_group.entry(group_of(p)).or_insert(0usize) += 1;
    }
    points
        .iter()
        .zip(keep)
        .zip(covariances_m2)
        .map(|((p, &k), c)| {
            if !(k && p.weak) {
                return *c;
            }
            let count = per_group.get(&group_of(p)).copied().unwrap_or(1) as f64;
            let mut out = *c;
            for axis in 0..2 {
                out[(axis, axis)] = c[(axis, axis)].max(sigma_m * sigma_m) * count;
            }
            out
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjustment::weak_control::test_point as point;

    #[test]
    fn the_weak_points_scatter_about_the_strong_control_of_their_recordings_is_measured() {
        // Recordings 0–9 share the correction (0.8, 0.0); strong control exact, weak control 0.2 m north
        // (recordings 0–4) or 0.2 m east (5–9) of it — |sample| = 0.2 m, so σ = 0.2 / √2 per axis.
        let mut pts = Vec::new();
        for r in 0..10usize {
            pts.push(point([0.8, 0.0], &[r, r + 1], false));
            let c = if r < 5 { [0.8, 0.2] } else { [1.0, 0.0] };
            pts.push(point(c, &[r, r + 1], true));
        }
        // A weak point whose recordings observe no strong control gives no sample.
        pts.push(point([3.0, 3.0], &[20, 21], true));
        let keep = vec![true; pts.len()];
        let e = estimate(&pts, &keep);
        assert_eq!(e.samples, 10);
        assert!((e.sigma_m.unwrap() - 0.2 / 2f64.sqrt()).abs() < 1e-12);
        // Dropped points are neither samples nor strong references: without strong control nothing is
        // estimated.
        let strong_dropped: Vec<bool> = pts.iter().map(|p| p.weak).collect();
        assert_eq!(estimate(&pts, &strong_dropped).sigma_m, None);
        // Fewer than MIN_SAMPLES samples: no estimate.
        let few: Vec<bool> = (0..pts.len()).map(|i| i < 2 * (MIN_SAMPLES - 1)).collect();
        assert_eq!(estimate(&pts, &few).samples, MIN_SAMPLES - 1);
        assert_eq!(estimate(&pts, &few).sigma_m, None);
    }

    #[test]
    fn weak_points_of_one_recording_count_as_one_observation_of_the_measured_sigma() {
        let pts = [
            point([0.8, 0.0], &[3, 4], false),
            point([0.8, 0.1], &[3, 4], true),
            point([0.8, 0.1], &[3, 4], true),
            point([0.8, 0.1], &[3, 4, 5], true),
            point([0.8, 0.1], &[6, 7], true),
            point([0.8, 0.1], &[8, 9], true),
        ];
        let stated = Matrix3::from_diagonal(&nalgebra::Vector3::new(
            0.03f64.powi(2),
            0.03f64.powi(2),
            0.0025,
        ));
        let mut keep = vec![true; pts.len()];
        keep[5] = false;
        let c = weak_covariances(&pts, &keep, &[stated; 6], 0.1);
        // The strong point and the dropped one keep the stated covariance.
        assert_eq!(c[0], stated);
        assert_eq!(c[5], stated);
        // Three weak points first seen from recording 3: σ² = 0.1² × 3 each; the height's untouched.
        for k in 1..=3 {
            assert!((c[k][(0, 0)] - 0.03).abs() < 1e-12 && (c[k][(1, 1)] - 0.03).abs() < 1e-12);
            assert_eq!(c[k][(2, 2)], 0.0025);
        }
        // Alone in its recording: σ = 0.1.
        assert!((c[4][(0, 0)] - 0.01).abs() < 1e-12);
        // A measured σ below the stated one leaves the stated one (times the group).
        let c = weak_covariances(&pts, &keep, &[stated; 6], 0.01);
        assert!((c[4][(0, 0)] - 0.03f64.powi(2)).abs() < 1e-15);
    }
}

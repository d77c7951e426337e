//! Orthophoto control from weak correlation peaks checked against the strong control along the trajectory.
//!
//! An orthophoto route keeps a tie point whose phase-correlation peak is weak when several weak peaks of its
//! recording agree on one correction (`orthophoto::corroborate`). Under one tree crown, weak peaks can agree
//! with each other and still be wrong together, by decimetres; in a stretch where nothing else is measured,
//! the adjustment follows them. Every control point implies a correction of the recordings that observe it:
//! its control XY minus the XY its panorama rays give with the recorded poses. The recorded trajectory's error
//! changes little between neighbouring recordings (its relative accuracy, `relative_sigma_m`), so the
//! corrections strong control gives before and after a weak point, interpolated to the weak point's place
//! along the trajectory, predict its correction. A weak point whose correction differs from that prediction
//! by more than `weak_control_tolerance_m` is not used as control (it stays a tie point); a recording left
//! without control is then flagged as bridged, extrapolated or uncorrected like any other
//! ([`crate::correction::support`]) instead of being "corrected" on weak evidence.
//!
//! Strong control is frame control (triangulated from aerial images) and orthophoto control whose peak is
//! at least `weak_control_below`. Without strong control anywhere, nothing is checked.

use nalgebra::{Matrix2, Vector2};

/// One control point as the check sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlEvidence {
    /// Correction it implies: control XY minus the XY triangulated with the recorded poses, metres.
    pub correction_m: Vector2<f64>,
    /// Indices (time order) of the recordings that observe it.
    pub recordings: Vec<usize>,
    /// Whether it is weak (an orthophoto peak below the threshold).
    pub weak: bool,
    /// How the recordings' own errors spread this correction, relative to one recording's error (per axis,
    /// σ²): Σᵢ JᵢJᵢᵀ, Jᵢ the horizontal change of the triangulated point per metre of horizontal shift of
    /// recording i (the identity for a point fixed by one recording; stretched along the rays for two nearly
    /// parallel rays, whose intersection moves farther than either recording).
    pub spread: Matrix2<f64>,
}

/// Component-wise median of `v` (not empty).
pub(crate) fn median2(v: &[Vector2<f64>]) -> Vector2<f64> {
    let med = |mut xs: Vec<f64>| {
        xs.sort_by(f64::total_cmp);
        let n = xs.len();
        match n % 2 {
            1 => xs[n / 2],
            _ => 0.5 * (xs[n / 2 - 1] + xs[n / 2]),
        }
    };
    Vector2::new(
        med(v.iter().map(|c| c.x).collect()),
        med(v.iter().map(|c| c.y).collect()),
    )
}

/// Per recording (of `n_recordings`), the median correction of the strong control points it observes.
fn strong_corrections(
    points: &[ControlEvidence],
    n_recordings: usize,
) -> Vec<Option<Vector2<f64>>> {
    let mut per: Vec<Vec<Vector2<f64>>> = vec![Vec::new(); n_recordings];
    for p in points.iter().filter(|p| !p.weak) {
        for &r in p.recordings.iter().filter(|&&r| r < n_recordings) {
            per[r].push(p.correction_m);
        }
    }
    per.iter()
        .map(|v| (!v.is_empty()).then(|| median2(v)))
        .collect()
}

/// The correction strong control predicts at `station` (a fractional recording index): linear between the
/// nearest recordings with strong control before and after it, the nearer one's beyond the last or first;
/// `None` without strong control.
fn predicted(strong: &[Option<Vector2<f64>>], station: f64) -> Option<Vector2<f64>> {
    let before = (0..strong.len())
        .rev()
        .find(|&r| r as f64 <= station && strong[r].is_some());
    let after = (0..strong.len()).find(|&r| r as f64 >= station && strong[r].is_some());
    match (before, after) {
        (Some(a), Some(b)) if a != b => {
            let w = (station - a as f64) / (b - a) as f64;
            Some(strong[a]? * (1.0 - w) + strong[b]? * w)
        }
        (Some(a), _) => strong[a],
        (None, Some(b)) => strong[b],
        (None, None) => None,
    }
}

/// Which control points to keep: every strong one, and every weak one whose correction lies within
/// `tolerance_m` of what the strong control predicts at its place (the mean index of its recordings).
pub fn keep_consistent(
    points: &[ControlEvidence],
    n_recordings: usize,
    tolerance_m: f64,
) -> Vec<bool> {
    let strong = strong_corrections(points, n_recordings);
    points
        .iter()
        .map(|p| {
            if !p.weak || p.recordings.is_empty() {
                return true;
            }
            let station = p.recordings.iter().sum::<usize>() as f64 / p.recordings.len() as f64;
            predicted(&strong, station).is_none_or(|c| (p.correction_m - c).norm() <= tolerance_m)
        })
        .collect()
}

/// A control point with correction `c` (m) observed by `recordings`, for the tests of this check and of
/// `control_consistency`.
#[cfg(test)]
pub(crate) fn test_point(c: [f64; 2], recordings: &[usize], weak: bool) -> ControlEvidence {
    ControlEvidence {
        correction_m: Vector2::new(c[0], c[1]),
        recordings: recordings.to_vec(),
        weak,
        spread: Matrix2::identity(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use super::test_point as point;

    #[test]
    fn weak_points_far_from_the_interpolated_strong_correction_are_dropped() {
        let pts = [
            point([0.80, 0.00], &[0, 1], false),
            point([0.82, 0.02], &[1, 2], false),
            point([1.00, 0.00], &[10, 11], false),
            // Between the strong ones: predicted ≈ (0.91, 0.01) at station 5.5.
            point([0.95, 0.05], &[5, 6], true),
            point([0.40, 0.01], &[5, 6], true),
            // Beyond the last strong recording: predicted = recording 11's (1.00, 0.00).
            point([1.10, 0.10], &[14, 15], true),
            point([1.00, 0.60], &[14, 15], true),
        ];
        let keep = keep_consistent(&pts, 16, 0.45);
        assert_eq!(keep, [true, true, true, true, false, true, false]);
        // Without strong control nothing is checked.
        let weak_only: Vec<_> = pts[3..].to_vec();
        assert!(keep_consistent(&weak_only, 16, 0.45).iter().all(|&k| k));
        // Interpolation between two strong recordings.
        let strong = strong_corrections(&pts, 16);
        let at = predicted(&strong, 5.5).unwrap();
        assert!(
            (at.x - (0.82 + (1.0 - 0.82) * 3.5 / 8.0)).abs() < 1e-12,
            "{at}"
        );
    }
}

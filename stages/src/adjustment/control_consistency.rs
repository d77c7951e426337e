//! Control checked against the control of the neighbouring recordings, strong or weak alike.
//!
//! Every control point implies a correction of the recordings that observe it: its control XY minus the XY
//! its panorama rays give with the recorded poses ([`ControlEvidence`]). The recorded trajectory's error
//! changes little from one recording to the next: consecutive recordings' errors differ by the relative
//! accuracy `relative_sigma_m` (σ_rel, per axis), so each recording's correction scatters about the local
//! common correction with σ_rel / √2 per axis. An orthophoto template matched at a wrong place can still give
//! a strong, unique-looking peak, and two or three recordings matching the same wrongly placed content agree
//! with each other; the weak-peak check ([`super::weak_control`]) trusts such strong control. This check
//! compares each control point's correction with the median correction of the *other* recordings with control
//! within `window` recordings before and after it — the recordings observing the point itself left out, so a
//! wrong cluster cannot vouch for itself — and does not use it as control when the two differ by more than
//! the 99.9 % quantile of the point's own scatter about the common correction ([`normalised_deviation`]):
//! a 2-D normal with covariance σ_rel² / 2 · S, where S says how the recordings' errors move the point's
//! triangulated position ([`ControlEvidence::spread`], at least the identity: a point seen along two nearly
//! parallel rays moves farther than either recording, along the rays, and its correction scatters more in
//! that direction only). For a point of one recording the bound is √χ²₂(0.999) · σ_rel / √2 ≈ 2.63 σ_rel
//! (0.39 m for σ_rel = 0.15 m) in every direction. The control point's own σ is not added: the check is
//! meant for orthophoto control, whose stated σ (a few centimetres) is small against σ_rel / √2. A correct
//! recording is rejected about once in a thousand; a wrong one whose error exceeds the bound is not used, and
//! its recordings are flagged like any other without control.
//!
//! The point deviating most goes first, and the deviations are measured again without it, until none exceeds
//! the tolerance: a wrong recording near a correct one would otherwise, as its neighbour, pull the median
//! towards itself. Without at least [`MIN_NEIGHBOURS`] other recordings with control in the window, a point is
//! not checked.

use super::config::AdjustConfig;
use super::weak_control::{keep_consistent, median2, ControlEvidence};
use nalgebra::{Matrix2, Vector2};

/// Fewest other recordings with control in the window for a point to be checked (a median of fewer does not
/// outvote a wrong pair).
pub const MIN_NEIGHBOURS: usize = 3;

/// √χ²₂(0.999) = √(−2 ln 0.001): the 99.9 % quantile of the norm of a 2-D standard normal vector.
pub const QUANTILE_999_2D: f64 = 3.716_922;

/// The tolerance on a correction's difference from its neighbours' median, metres, for the relative σ
/// `relative_sigma_m` (per axis, between consecutive recordings).
pub fn tolerance_m(relative_sigma_m: f64) -> f64 {
    QUANTILE_999_2D * relative_sigma_m / std::f64::consts::SQRT_2
}

/// Point `p`'s deviation `d` (its correction minus its neighbours' median, m) in units of the 99.9 % bound:
/// √(dᵀ C⁻¹ d) / √χ²₂(0.999), C = σ_rel² / 2 · S, S = `p.spread` with its eigenvalues raised to at least 1 (a
/// point never scatters less than one recording). Above 1: beyond the bound.
pub fn normalised_deviation(p: &ControlEvidence, d: Vector2<f64>, relative_sigma_m: f64) -> f64 {
    let eig = nalgebra::SymmetricEigen::new(p.spread);
    let floored = eig
        .eigenvalues
        .map(|l| if l.is_finite() { l.max(1.0) } else { 1.0 });
    let s = eig.eigenvectors * Matrix2::from_diagonal(&floored) * eig.eigenvectors.transpose();
    let c = s * (relative_sigma_m * relative_sigma_m / 2.0);
    let m2 = c
        .try_inverse()
        .map_or(f64::INFINITY, |inv| (d.transpose() * inv * d)[(0, 0)]);
    m2.max(0.0).sqrt() / QUANTILE_999_2D
}

/// Per recording (of `n_recordings`), the median correction of the control points it observes (those with
/// `keep` true).
fn recording_corrections(
    points: &[ControlEvidence],
    keep: &[bool],
    n_recordings: usize,
) -> Vec<Option<Vector2<f64>>> {
    let mut per: Vec<Vec<Vector2<f64>>> = vec![Vec::new(); n_recordings];
    for (p, _) in points.iter().zip(keep).filter(|(_, &k)| k) {
        for &r in p.recordings.iter().filter(|&&r| r < n_recordings) {
            per[r].push(p.correction_m);
        }
    }
    per.iter()
        .map(|v| (!v.is_empty()).then(|| median2(v)))
        .collect()
}

/// Point `p`'s correction minus the median correction of the other recordings with control within `window`
/// recordings of its own (`per_recording`), metres; `None` with fewer than [`MIN_NEIGHBOURS`] of them or
/// without recordings.
fn deviation_m(
    p: &ControlEvidence,
    per_recording: &[Option<Vector2<f64>>],
    window: usize,
) -> Option<Vector2<f64>> {
    let (&first, &last) = (p.recordings.iter().min()?, p.recordings.iter().max()?);
    let lo = first.saturating_sub(window);
    let hi = (last + window).min(per_recording.len().saturating_sub(1));
    let neighbours: Vec<Vector2<f64>> = (lo..=hi)
        .filter(|r| !p.recordings.contains(r))
        .filter_map(|r| per_recording.get(r).copied().flatten())
        .collect();
    (neighbours.len() >= MIN_NEIGHBOURS).then(|| p.correction_m - median2(&neighbours))
}

/// Which of `points` to keep (`keep` on entry: the ones still used; a point already dropped stays dropped
/// and does not count as a neighbour). A point's deviation is the distance of its correction from the median
/// correction of the other recordings with control within `window` recordings of its own (the recordings
/// observing it excluded), given at least [`MIN_NEIGHBOURS`] of them. The point deviating most beyond its
/// bound ([`normalised_deviation`] for `relative_sigma_m`) is
/// dropped, then the deviations are measured again without it — so a wrong recording does not, as a
/// neighbour, take correct ones down with it.
pub fn keep_locally_consistent(
    points: &[ControlEvidence],
    keep: &[bool],
    n_recordings: usize,
    window: usize,
    relative_sigma_m: f64,
) -> Vec<bool> {
    let mut keep = keep.to_vec();
    loop {
        let per_recording = recording_corrections(points, &keep, n_recordings);
        let worst = points
            .iter()
            .enumerate()
            .filter(|&(i, _)| keep[i])
            .filter_map(|(i, p)| {
                deviation_m(p, &per_recording, window)
                    .map(|d| (i, normalised_deviation(p, d, relative_sigma_m)))
            })
            .filter(|&(_, ratio)| ratio > 1.0)
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)));
        match worst {
            Some((i, _)) => keep[i] = false,
            None => return keep,
        }
    }
}

/// Which control points the checks of `config` keep, with the number each check dropped.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlSelection {
    /// One flag per control point (parallel to the evidence).
    pub keep: Vec<bool>,
    /// Dropped by this check (`control_consistency_window`).
    pub inconsistent: usize,
    /// Weak points dropped by the weak-peak check (`weak_control_tolerance_m`) among those this check kept.
    pub weak: usize,
}

/// Runs this check (when `control_consistency_window` is set), then the weak-peak check on what it kept
/// (when `weak_control_tolerance_m` is set), for `n_recordings` recordings whose relative σ is
/// `relative_sigma_m`.
pub fn select_control(
    evidence: &[ControlEvidence],
    n_recordings: usize,
    config: &AdjustConfig,
    relative_sigma_m: f64,
) -> ControlSelection {
    let mut keep = vec![true; evidence.len()];
    if let Some(window) = config.control_consistency_window {
        keep = keep_locally_consistent(evidence, &keep, n_recordings, window, relative_sigma_m);
    }
    let inconsistent = keep.iter().filter(|&&k| !k).count();
    let mut weak = 0;
    if let Some(tolerance_m) = config.weak_control_tolerance_m {
        let kept: Vec<usize> = (0..evidence.len()).filter(|&i| keep[i]).collect();
        let subset: Vec<ControlEvidence> = kept.iter().map(|&i| evidence[i].clone()).collect();
        for (&i, k) in kept
            .iter()
            .zip(keep_consistent(&subset, n_recordings, tolerance_m))
        {
            if !k {
                keep[i] = false;
                weak += 1;
            }
        }
    }
    ControlSelection {
        keep,
        inconsistent,
        weak,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::adjustment::weak_control::test_point as point;

    #[test]
    fn tolerance_is_the_999_quantile_of_the_scatter_about_the_common_correction() {
        assert!((tolerance_m(0.15) - 0.3942).abs() < 1e-3);
        // P(|N(0, s²I₂)| > q s) = exp(−q²/2) = 0.001.
        assert!(((-QUANTILE_999_2D * QUANTILE_999_2D / 2.0).exp() - 0.001).abs() < 1e-7);
    }

    #[test]
    fn a_strong_pair_that_agrees_with_itself_but_not_with_its_neighbours_is_dropped() {
        // Common correction (0.27, 0.77) with centimetre scatter; recordings 11 and 12 share control 0.45 m
        // off, strong, and agree with each other.
        let mut pts = Vec::new();
        for r in [2usize, 3, 15, 16, 17, 18] {
            let d = 0.01 * (r % 3) as f64;
            pts.push(point([0.27 + d, 0.77 - d], &[r, r + 1], false));
        }
        pts.push(point([0.56, 1.11], &[11, 12], false));
        pts.push(point([0.60, 1.15], &[11, 12], false));
        pts.push(point([0.59, 1.12], &[12], true));
        let all = vec![true; pts.len()];
        // Within 10 recordings, recording 2's point has only recordings 4, 11 and 12 as neighbours, two of
        // them wrong: it deviates from their median as much as the wrong ones from theirs, and goes too.
        let keep = keep_locally_consistent(&pts, &all, 30, 10, 0.15);
        assert_eq!(
            keep,
            [false, true, true, true, true, true, false, false, false]
        );
        // Within 20 the correct recordings outvote the pair.
        let keep = keep_locally_consistent(&pts, &all, 30, 20, 0.15);
        assert_eq!(keep[..6], [true; 6]);
        assert_eq!(keep[6..], [false, false, false]);
        // A point 0.30 m off (within 0.39 m) is kept.
        pts.push(point([0.45, 1.00], &[10], false));
        let all = vec![true; pts.len()];
        let keep = keep_locally_consistent(&pts, &all, 30, 20, 0.15);
        assert!(keep[9]);
        // Already dropped points stay dropped and are nobody's neighbours.
        let mut given = vec![true; pts.len()];
        given[0] = false;
        let keep = keep_locally_consistent(&pts, &given, 30, 20, 0.15);
        assert!(!keep[0] && keep[1]);
    }

    #[test]
    fn a_point_spread_along_its_rays_is_bounded_along_them_only() {
        // Two nearly parallel rays along x: the recordings' errors move the point 3 × as far along x.
        let mut p = point([0.0, 0.0], &[4, 5], false);
        p.spread = Matrix2::from_diagonal(&Vector2::new(9.0, 0.5));
        let bound = tolerance_m(0.15);
        // Along the rays the bound is 3 × wider; across them it stays one recording's (the 0.5 is raised to 1).
        let along = normalised_deviation(&p, Vector2::new(2.5 * bound, 0.0), 0.15);
        let across = normalised_deviation(&p, Vector2::new(0.0, 1.1 * bound), 0.15);
        assert!((along - 2.5 / 3.0).abs() < 1e-9, "{along}");
        assert!((across - 1.1).abs() < 1e-9, "{across}");
    }

    #[test]
    fn a_point_with_too_few_neighbours_is_not_checked() {
        let pts = [
            point([0.0, 0.0], &[0], false),
            point([0.0, 0.0], &[1], false),
            point([2.0, 2.0], &[5], false),
            point([0.0, 0.0], &[20], false),
        ];
        let all = vec![true; pts.len()];
        // Recording 5 has only two neighbours with control within 5 recordings.
        assert!(keep_locally_consistent(&pts, &all, 25, 5, 0.15)
            .iter()
            .all(|&k| k));
        // With a window reaching recording 20 it has three, which outvote it.
        let keep = keep_locally_consistent(&pts, &all, 25, 15, 0.15);
        assert_eq!(keep, [true, true, false, true]);
    }
}

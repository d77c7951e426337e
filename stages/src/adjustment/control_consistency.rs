//! Aerial control that disagrees with the control of its neighbours along the trajectory.
//!
//! Every control point implies a correction of the recordings that observe it: its aerial XY minus the XY its
//! panorama rays give with the recorded poses. A recording's correction is the median of its points'. The
//! recorded trajectory's error changes slowly between consecutive recordings, so the corrections of the
//! nearest controlled recordings before and after a recording, interpolated to it, predict its own. A
//! registration that locked onto the wrong place in the aerial image — typically one consistent with a drifted
//! recorded pose, which implies almost no correction in the middle of a drifted stretch — stands out against
//! that prediction, while a drift that its neighbours' control shares does not.
//!
//! How far a prediction may miss is derived from σ, never from a fixed distance: between neighbours `a` and `b`
//! steps away, a trajectory error that changes by σ per axis per step (a random walk) misses the linear
//! interpolation by σ·√(a·b/(a+b)) per axis. Only a recording with controlled neighbours on both sides is
//! checked. σ is the larger of the relative constraints' σ
//! and the scatter the campaign's own corrections show about their predictions (robust: the median normalised
//! miss), so a trajectory whose error changes faster than its noise (a smooth drift) widens the tolerance by
//! itself. The recording that misses by the most σ beyond `k` is left out, the predictions are formed again
//! without it, and so on until every remaining recording fits; the control points observed by the left-out
//! recordings are then not used as control.

use nalgebra::Vector2;

/// The median of a 2-D Gaussian vector's norm is σ·√(2 ln 2) for σ per axis.
const RAYLEIGH_MEDIAN: f64 = 1.177_410_022_515_474_7;

/// One recording as the check sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordingCorrection {
    /// Median correction of the control points it observes; `None` without control.
    pub correction_m: Option<Vector2<f64>>,
    /// Whether it is linked to the previous recording (same chain: no gap in the trajectory).
    pub linked_to_previous: bool,
}

/// The correction predicted for recording `r` of `recs` from the nearest active controlled recordings of its
/// chain before and after it, with its variance factor in units of σ² per axis (a·b/(a+b)); `None` without a
/// neighbour on both sides (beyond the last one, the trend of the error is not known: a drift that sets in
/// would look like an outlier).
fn prediction(
    recs: &[RecordingCorrection],
    active: &[bool],
    r: usize,
) -> Option<(Vector2<f64>, f64)> {
    let usable = |i: usize| active[i] && recs[i].correction_m.is_some();
    let mut before = None;
    let mut i = r;
    while i > 0 && recs[i].linked_to_previous {
        i -= 1;
        if usable(i) {
            before = Some(i);
            break;
        }
    }
    let mut after = None;
    let mut j = r + 1;
    while j < recs.len() && recs[j].linked_to_previous {
        if usable(j) {
            after = Some(j);
            break;
        }
        j += 1;
    }
    let c = |i: usize| recs[i].correction_m.unwrap_or_default();
    match (before, after) {
        (Some(a), Some(b)) => {
            let (da, db) = ((r - a) as f64, (b - r) as f64);
            let w = da / (da + db);
            Some((c(a) * (1.0 - w) + c(b) * w, da * db / (da + db)))
        }
        _ => None,
    }
}

/// Per recording: its miss against the prediction in units of √(variance factor), metres (`None` when it has
/// no control, is not active, or has no neighbour to be predicted from).
fn normalised_misses(recs: &[RecordingCorrection], active: &[bool]) -> Vec<Option<f64>> {
    (0..recs.len())
        .map(|r| {
            let c = recs[r].correction_m.filter(|_| active[r])?;
            let (p, factor) = prediction(recs, active, r)?;
            Some((c - p).norm() / factor.max(f64::MIN_POSITIVE).sqrt())
        })
        .collect()
}

/// The σ per axis and step the check uses: the larger of `sigma_rel_m` and the misses' robust scale.
fn step_sigma(misses: &[Option<f64>], sigma_rel_m: f64) -> f64 {
    let mut m: Vec<f64> = misses.iter().flatten().copied().collect();
    if m.is_empty() {
        return sigma_rel_m;
    }
    m.sort_by(f64::total_cmp);
    let median = match m.len() % 2 {
        1 => m[m.len() / 2],
        _ => 0.5 * (m[m.len() / 2 - 1] + m[m.len() / 2]),
    };
    sigma_rel_m.max(median / RAYLEIGH_MEDIAN)
}

/// Which recordings' control disagrees with their neighbours' by more than `k` σ (see the module
/// documentation); at least three controlled recordings must take part for any to be left out, and never more
/// than a third of them.
pub fn inconsistent_recordings(
    recs: &[RecordingCorrection],
    sigma_rel_m: f64,
    k: f64,
) -> Vec<bool> {
    let mut active = vec![true; recs.len()];
    let controlled = recs.iter().filter(|r| r.correction_m.is_some()).count();
    let mut left_out = 0;
    while controlled >= 3 && 3 * (left_out + 1) <= controlled {
        let misses = normalised_misses(recs, &active);
        let sigma = step_sigma(&misses, sigma_rel_m);
        let worst = misses
            .iter()
            .enumerate()
            .filter_map(|(r, m)| m.map(|m| (r, m / sigma)))
            .filter(|&(_, z)| z > k)
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)));
        let Some((r, _)) = worst else { break };
        active[r] = false;
        left_out += 1;
    }
    active
        .iter()
        .zip(recs)
        .map(|(a, r)| !a && r.correction_m.is_some())
        .collect()
}

/// Component-wise median of `v` (not empty).
pub fn median2(v: &[Vector2<f64>]) -> Vector2<f64> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn chain(corrections: &[Option<[f64; 2]>]) -> Vec<RecordingCorrection> {
        corrections
            .iter()
            .enumerate()
            .map(|(i, c)| RecordingCorrection {
                correction_m: c.map(|c| Vector2::new(c[0], c[1])),
                linked_to_previous: i > 0,
            })
            .collect()
    }

    /// A drift rising smoothly to 1.5 m and back over 20 recordings, sampled with 1 cm noise, with two
    /// neighbouring recordings in its middle whose control agrees with the drifted pose (≈ no correction).
    #[test]
    fn control_agreeing_with_a_drifted_pose_is_found_and_the_drift_is_kept() {
        let noise = [
            0.01, -0.008, 0.004, -0.01, 0.007, 0.0, -0.005, 0.009, -0.003, 0.006,
        ];
        let mut c: Vec<Option<[f64; 2]>> = (0..20)
            .map(|i| {
                let drift = 1.5 * (std::f64::consts::PI * i as f64 / 19.0).sin();
                Some([drift + noise[i % 10], 0.3 * drift - noise[(i + 3) % 10]])
            })
            .collect();
        c[9] = Some([0.05, 0.02]);
        c[10] = Some([0.30, 0.10]);
        c[4] = None;
        c[15] = None;
        let flagged = inconsistent_recordings(&chain(&c), 0.04, 3.0);
        let which: Vec<usize> = (0..20).filter(|&i| flagged[i]).collect();
        assert_eq!(which, [9, 10]);
    }

    #[test]
    fn consistent_control_and_too_little_control_are_kept() {
        let c: Vec<Option<[f64; 2]>> = (0..10)
            .map(|i| Some([0.8 + 0.01 * (i % 3) as f64, 0.1]))
            .collect();
        assert!(inconsistent_recordings(&chain(&c), 0.04, 3.0)
            .iter()
            .all(|f| !f));
        let two = [Some([0.0, 0.0]), None, Some([1.0, 0.0])];
        assert!(inconsistent_recordings(&chain(&two), 0.04, 3.0)
            .iter()
            .all(|f| !f));
    }

    #[test]
    fn a_gap_separates_the_chains() {
        // Two streets, each consistent on its own, with different corrections.
        let mut recs = chain(&[Some([0.0, 0.0]); 8]);
        for r in recs.iter_mut().skip(4) {
            r.correction_m = Some(Vector2::new(2.0, 0.0));
        }
        recs[4].linked_to_previous = false;
        assert!(inconsistent_recordings(&recs, 0.04, 3.0).iter().all(|f| !f));
    }

    #[test]
    fn the_interpolation_and_its_variance_factor() {
        let recs = chain(&[
            Some([0.0, 0.0]),
            None,
            None,
            Some([3.0, 0.0]),
            Some([9.0, 9.0]),
        ]);
        let active = [true; 5];
        let (p, f) = prediction(&recs, &active, 1).unwrap();
        assert!((p.x - 1.0).abs() < 1e-12 && (f - 2.0 / 3.0).abs() < 1e-12);
        assert!(prediction(&recs, &active, 4).is_none());
    }
}

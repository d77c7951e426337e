//! The σ of recordings corrected without aerial control of their own.
//!
//! A recording that observes no aerial control point is moved by the adjustment through its neighbours (tie
//! points and relative constraints, thesis 3.4.2): it receives, roughly, the correction of the nearest
//! controlled recordings. The least-squares covariance of such a recording only knows the model's noise — the
//! white noise of the relative constraints — not how much the trajectory's real error changes between a
//! controlled recording and this one (an error that turns with the vehicle, drifts during an outage, or is
//! white noise of the recording itself). So the covariance alone understates what is left.
//!
//! This module measures that change from the adjustment's own result: the corrections of the controlled
//! recordings form samples of the trajectory's error along the street, and their empirical semivariogram
//! `γ(h) = ½·E[(c(s) − c(s + h))²]` (per axis, horizontal and vertical apart, robust median estimates, binned by
//! distance along the trajectory) says how different the corrections of two recordings `h` metres apart are.
//! A recording `d` metres along the trajectory from its nearest controlled recording then gets
//! `σ² = σ²_adjustment + 2·γ(d)`: the variance of taking the neighbour's correction for its own. `γ` is made
//! non-decreasing in `h` (an error does not become more alike farther away), held at its first bin below the
//! first lag (the white noise between neighbours) and grows linearly in `h` beyond the last lag (a random walk).
//! With too few controlled recordings for a variogram, such a recording's σ is at least its recorded prior σ:
//! nothing better is known about it.
//!
//! The variogram pools the whole campaign, so it describes the typical change of the error; a GNSS outage
//! drifts by metres where no recording is controlled, and the controlled recordings around it say so only by
//! their two corrections. A bridged recording (controlled recordings on both sides along the trajectory, its
//! anchors `a` and `b`, `L` metres apart, the recording `d_a` and `d_b` metres from them) therefore also gets
//! the local evidence of its anchors, for a trajectory error that wanders like a random walk between them:
//! the rate per axis estimated from the anchors' difference `Δ = c_b − c_a`, `q = Δ²/L` (horizontally
//! `|Δ_xy|²/(2L)` per axis), gives the variance of the random walk pinned at both anchors (a Brownian bridge),
//! `q·d_a·d_b/L`, around the straight interpolation of the anchors' corrections. Where the adjustment put the
//! recording elsewhere than that interpolation (its own tie points, or the robust loss letting one anchor go
//! and the stretch keep its recorded shape), the distance between the two adds to the variance per axis: one
//! of the two is off by about that much, and nothing in the adjustment says which. A bridged recording thus
//! gets `σ² = σ²_adjustment + max(2·γ(d), q·d_a·d_b/L) + (c − c_interpolated)²` per axis.

use super::support::{recording_support, Support};
use crate::adjustment::AdjustmentRun;
use crate::estimators::median_consensus::median_in_place;
use serde::{Deserialize, Serialize};

/// Bins of the variogram hold at least this many pairs of controlled recordings (smaller bins merge).
pub const MIN_PAIRS_PER_BIN: usize = 8;
/// The variogram is estimated up to this many bins (each two median recording spacings wide).
pub const MAX_BINS: usize = 20;
/// Median of a χ² variable with 1 and with 2 degrees of freedom.
const CHI2_1_MEDIAN: f64 = 0.454_936;
const CHI2_2_MEDIAN: f64 = std::f64::consts::LN_2 * 2.0;

/// One bin of the empirical semivariogram of the controlled recordings' corrections.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariogramBin {
    /// Mean separation of the bin's pairs along the trajectory, m.
    pub lag_m: f64,
    /// Semivariance per horizontal axis, m² (after making the variogram non-decreasing).
    pub gamma_xy_m2: f64,
    /// Semivariance of the vertical axis, m² (non-decreasing).
    pub gamma_z_m2: f64,
    pub pairs: usize,
}

/// What [`widen_off_control_sigma`] did, for metrics.json.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OffControlSigma {
    /// The variogram used (empty when there were too few controlled recordings for one).
    pub variogram: Vec<VariogramBin>,
    /// Recordings whose σ was widened by the variogram.
    pub widened: usize,
    /// Recordings whose σ was raised to their recorded prior σ (no variogram).
    pub raised_to_prior: usize,
    /// Bridged recordings whose σ the local evidence of their two anchors widened beyond the variogram's.
    pub widened_by_anchors: usize,
}

/// The local variances per axis (x, y, z; m²) of bridged recording `i` from its anchors `a` < `i` < `b`
/// (module documentation): the Brownian bridge of the anchors' correction difference, and the squared
/// distance of its correction from their interpolation. `corr(j)` is recording `j`'s correction, `s_m` the
/// along-track positions.
fn anchor_variance(
    i: usize,
    (a, b): (usize, usize),
    s_m: &[f64],
    corr: impl Fn(usize) -> [f64; 3],
) -> Option<AnchorVariance> {
    let length = s_m[b] - s_m[a];
    let (d_a, d_b) = (s_m[i] - s_m[a], s_m[b] - s_m[i]);
    if !(length > 0.0 && d_a >= 0.0 && d_b >= 0.0) {
        return None;
    }
    let (ca, cb, ci) = (corr(a), corr(b), corr(i));
    let delta: [f64; 3] = std::array::from_fn(|k| cb[k] - ca[k]);
    let rate_xy = (delta[0] * delta[0] + delta[1] * delta[1]) / (2.0 * length);
    let rate = [rate_xy, rate_xy, delta[2] * delta[2] / length];
    let pinned = d_a * d_b / length;
    let out = AnchorVariance {
        bridge_m2: std::array::from_fn(|k| rate[k] * pinned),
        off_interpolation_m2: std::array::from_fn(|k| {
            (ci[k] - (ca[k] + delta[k] * d_a / length)).powi(2)
        }),
    };
    let finite = |v: &[f64; 3]| v.iter().all(|x| x.is_finite());
    (finite(&out.bridge_m2) && finite(&out.off_interpolation_m2)).then_some(out)
}

/// What a bridged recording's two anchors say of its correction's variance, per axis (x, y, z), m².
#[derive(Clone, Copy, Debug, PartialEq)]
struct AnchorVariance {
    /// The random walk pinned at both anchors, around the interpolation of their corrections.
    bridge_m2: [f64; 3],
    /// The squared distance of the adjusted correction from that interpolation.
    off_interpolation_m2: [f64; 3],
}

/// Distance along the recorded trajectory (horizontal, m) of every recording from the first.
pub(crate) fn along_track_m(run: &AdjustmentRun) -> Vec<f64> {
    let mut s = Vec::with_capacity(run.recordings.len());
    let mut total = 0.0;
    for (i, r) in run.recordings.iter().enumerate() {
        if i > 0 {
            let p = run.recordings[i - 1].recorded_world;
            total += (r.recorded_world[0] - p[0]).hypot(r.recorded_world[1] - p[1]);
        }
        s.push(total);
    }
    s
}

/// The empirical semivariogram of `corrections` (m) at along-track positions `s_m`; empty when fewer than
/// [`MIN_PAIRS_PER_BIN`] pairs fall in the first bin.
pub fn correction_variogram(s_m: &[f64], corrections: &[[f64; 3]]) -> Vec<VariogramBin> {
    let n = s_m.len();
    if n < 2 {
        return Vec::new();
    }
    let mut steps: Vec<f64> = s_m.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    let width_m = (2.0 * median_in_place(&mut steps).unwrap_or(0.0)).max(1.0);
    // (lag, Δx² + Δy², Δz²) per bin.
    let mut bins: Vec<Vec<(f64, f64, f64)>> = vec![Vec::new(); MAX_BINS];
    for i in 0..n {
        for j in i + 1..n {
            let h = (s_m[j] - s_m[i]).abs();
            let b = (h / width_m) as usize;
            if b >= MAX_BINS {
                continue;
            }
            let d = |k: usize| corrections[j][k] - corrections[i][k];
            bins[b].push((h, d(0) * d(0) + d(1) * d(1), d(2) * d(2)));
        }
    }
    let mut out: Vec<VariogramBin> = Vec::new();
    let mut pending: Vec<(f64, f64, f64)> = Vec::new();
    for bin in bins {
        pending.extend(bin);
        if pending.len() < MIN_PAIRS_PER_BIN {
            continue;
        }
        let lag_m = pending.iter().map(|p| p.0).sum::<f64>() / pending.len() as f64;
        let mut xy: Vec<f64> = pending.iter().map(|p| p.1).collect();
        let mut z: Vec<f64> = pending.iter().map(|p| p.2).collect();
        // Δx² + Δy² ~ 2γ·χ²₂ and Δz² ~ 2γ_z·χ²₁ for Gaussian differences.
        let gamma_xy = median_in_place(&mut xy).unwrap_or(0.0) / (2.0 * CHI2_2_MEDIAN);
        let gamma_z = median_in_place(&mut z).unwrap_or(0.0) / (2.0 * CHI2_1_MEDIAN);
        let (prev_xy, prev_z) = out
            .last()
            .map_or((0.0, 0.0), |b| (b.gamma_xy_m2, b.gamma_z_m2));
        out.push(VariogramBin {
            lag_m,
            gamma_xy_m2: gamma_xy.max(prev_xy),
            gamma_z_m2: gamma_z.max(prev_z),
            pairs: pending.len(),
        });
        pending.clear();
    }
    out
}

/// Semivariance (per horizontal axis, vertical) at separation `h_m`: the first bin below its lag, linear
/// between bins, growing linearly in `h_m` beyond the last. `None` for an empty variogram.
pub fn semivariance_at(variogram: &[VariogramBin], h_m: f64) -> Option<(f64, f64)> {
    let first = variogram.first()?;
    let last = variogram.last()?;
    if h_m <= first.lag_m {
        return Some((first.gamma_xy_m2, first.gamma_z_m2));
    }
    if h_m >= last.lag_m {
        let f = h_m / last.lag_m.max(f64::MIN_POSITIVE);
        return Some((last.gamma_xy_m2 * f, last.gamma_z_m2 * f));
    }
    let j = variogram.partition_point(|b| b.lag_m <= h_m);
    let (a, b) = (&variogram[j - 1], &variogram[j]);
    let w = (h_m - a.lag_m) / (b.lag_m - a.lag_m);
    Some((
        a.gamma_xy_m2 + w * (b.gamma_xy_m2 - a.gamma_xy_m2),
        a.gamma_z_m2 + w * (b.gamma_z_m2 - a.gamma_z_m2),
    ))
}

/// Widens the σ of every bridged or extrapolated recording of `run` by the variogram of the controlled
/// recordings' corrections at its distance from the nearest controlled recording of its linked group; without a
/// variogram raises it to at least `prior_sigma_m` (per recording: σ of recorded x/y, z; `None` = no prior).
pub fn widen_off_control_sigma(
    run: &mut AdjustmentRun,
    prior_sigma_m: &[(Option<f64>, Option<f64>)],
) -> OffControlSigma {
    let support = recording_support(run);
    let s_m = along_track_m(run);
    let controlled: Vec<usize> = (0..support.len())
        .filter(|&i| support[i].support == Support::Controlled)
        .collect();
    let corrections: Vec<[f64; 3]> = controlled
        .iter()
        .map(|&i| {
            let r = &run.recordings[i];
            std::array::from_fn(|k| r.adjusted_world[k] - r.recorded_world[k])
        })
        .collect();
    let s_controlled: Vec<f64> = controlled.iter().map(|&i| s_m[i]).collect();
    let variogram = correction_variogram(&s_controlled, &corrections);
    let mut report = OffControlSigma::default();
    for (i, sup) in support.iter().enumerate() {
        if !matches!(sup.support, Support::Bridged | Support::Extrapolated) {
            continue;
        }
        // The nearest controlled recordings of its group before and after it (`controlled` is in recording
        // order, and the along-track position grows with it).
        let same_group = |c: &usize| support[*c].group == sup.group;
        let split = controlled.partition_point(|&c| c < i);
        let before = controlled[..split].iter().rev().copied().find(same_group);
        let after = controlled[split..].iter().copied().find(same_group);
        let nearest_m = [before, after]
            .into_iter()
            .flatten()
            .map(|c| (s_m[c] - s_m[i]).abs())
            .min_by(f64::total_cmp);
        let anchors = match (sup.support, before, after) {
            (Support::Bridged, Some(a), Some(b)) => anchor_variance(i, (a, b), &s_m, |j| {
                let r = &run.recordings[j];
                std::array::from_fn(|k| r.adjusted_world[k] - r.recorded_world[k])
            }),
            _ => None,
        };
        let sigma = &mut run.recordings[i].sigma_m;
        match nearest_m.and_then(|d| semivariance_at(&variogram, d)) {
            Some((g_xy, g_z)) => {
                let mut by_anchors = false;
                for (k, g) in [g_xy, g_xy, g_z].into_iter().enumerate() {
                    let (bridge, off) =
                        anchors.map_or((0.0, 0.0), |v| (v.bridge_m2[k], v.off_interpolation_m2[k]));
                    let added = bridge.max(2.0 * g) + off;
                    // (More than a millimetre's variance beyond the variogram's counts.)
                    by_anchors |= added - 2.0 * g > 1e-6;
                    sigma[k] = (sigma[k] * sigma[k] + added).sqrt();
                }
                report.widened += 1;
                report.widened_by_anchors += usize::from(by_anchors);
            }
            None => {
                let (xy, z) = prior_sigma_m.get(i).copied().unwrap_or((None, None));
                let before = *sigma;
                for (k, p) in [xy, xy, z].into_iter().enumerate() {
                    if let Some(p) = p {
                        sigma[k] = sigma[k].max(p);
                    }
                }
                report.raised_to_prior += usize::from(before != *sigma);
            }
        }
    }
    report.variogram = variogram;
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjustment::{AdjustConfig, PointKind};
    use crate::correction::fixture::{point, recording, run};

    /// Corrections with white noise of known σ per axis (a deterministic ±σ pattern) have semivariance σ²
    /// at every lag.
    #[test]
    fn white_noise_corrections_give_a_flat_variogram_of_their_variance() {
        let sigma = 0.1;
        let s: Vec<f64> = (0..60).map(|i| 5.0 * i as f64).collect();
        // Alternating signs with a period that decorrelates: differences are 0 or ±2σ.
        let c: Vec<[f64; 3]> = (0..60)
            .map(|i| {
                let sign = |k: usize| if (i * 7 + k * 3) % 4 < 2 { 1.0 } else { -1.0 };
                [sigma * sign(0), sigma * sign(1), sigma * sign(2)]
            })
            .collect();
        let v = correction_variogram(&s, &c);
        assert!(!v.is_empty());
        for b in &v {
            assert!(b.pairs >= MIN_PAIRS_PER_BIN);
            // Non-decreasing by construction; and of the order of σ² (E[Δ²] = 2σ²).
            assert!(
                b.gamma_xy_m2 > 0.3 * sigma * sigma && b.gamma_xy_m2 < 3.0 * sigma * sigma,
                "{b:?}"
            );
        }
        assert!(v.windows(2).all(|w| w[1].gamma_xy_m2 >= w[0].gamma_xy_m2));
    }

    /// A correction that grows linearly along the street (a drift of 1 cm per metre) gives γ(h) = ½·(0.01·h)²
    /// per axis in x, and the interpolation between bins follows it.
    #[test]
    fn a_linear_drift_gives_a_quadratic_variogram() {
        let s: Vec<f64> = (0..40).map(|i| 5.0 * i as f64).collect();
        let c: Vec<[f64; 3]> = s.iter().map(|&x| [0.01 * x, 0.0, 0.0]).collect();
        let v = correction_variogram(&s, &c);
        // Δx² + Δy² = (0.01 h)² exactly; γ_xy = median / (2·χ²₂ median) per axis, the median taken over the
        // bin's pairs, whose lags lie within half a bin (two 5 m spacings) of the bin's mean lag.
        let gamma = |h: f64| (0.01 * h).powi(2) / (2.0 * CHI2_2_MEDIAN);
        for b in &v[..5] {
            assert!(
                b.gamma_xy_m2 >= gamma(b.lag_m - 5.0) && b.gamma_xy_m2 <= gamma(b.lag_m + 5.0),
                "{b:?}"
            );
            assert_eq!(b.gamma_z_m2, 0.0);
        }
        let (g, _) = semivariance_at(&v, 0.5 * (v[1].lag_m + v[2].lag_m)).unwrap();
        assert!(g > v[1].gamma_xy_m2 && g < v[2].gamma_xy_m2);
        let last = v.last().unwrap();
        let (far, _) = semivariance_at(&v, 2.0 * last.lag_m).unwrap();
        assert!((far - 2.0 * last.gamma_xy_m2).abs() < 1e-12);
    }

    /// Controlled recordings every other one with corrections alternating by ±0.1 m: the recordings between
    /// them get σ widened to ≈ the noise between neighbours, the controlled ones keep theirs; with one
    /// controlled recording only, the others fall back to their prior σ.
    #[test]
    fn off_control_recordings_are_widened_and_controlled_ones_kept() {
        let n = 41;
        let recs = (0..n)
            .map(|i| {
                let dx = if (i / 2) % 2 == 0 { 0.8 } else { 0.6 };
                recording(i, 5.0 * i as f64, [dx, 0.0, 0.0])
            })
            .collect();
        let points = (0..n)
            .step_by(2)
            .map(|i| point(PointKind::Control, &[i]))
            .collect();
        let config = AdjustConfig {
            relative_constraints: true,
            ..AdjustConfig::default()
        };
        let mut r = run(config.clone(), recs, points);
        let priors = vec![(Some(1.0), Some(0.3)); n];
        let report = widen_off_control_sigma(&mut r, &priors);
        assert!(!report.variogram.is_empty());
        assert_eq!(report.widened, n / 2);
        assert_eq!(report.raised_to_prior, 0);
        for (i, rec) in r.recordings.iter().enumerate() {
            if i % 2 == 0 {
                assert_eq!(rec.sigma_m, [0.1; 3]);
            } else {
                assert!(
                    rec.sigma_m[0] > 0.12 && rec.sigma_m[0] < 0.5,
                    "{:?}",
                    rec.sigma_m
                );
                assert_eq!(rec.sigma_m[2], 0.1, "no vertical difference, no widening");
            }
        }

        let recs = (0..5)
            .map(|i| recording(i, 5.0 * i as f64, [0.8, 0.0, 0.0]))
            .collect();
        let mut r = run(config, recs, vec![point(PointKind::Control, &[2])]);
        let report = widen_off_control_sigma(&mut r, &[(Some(1.0), None); 5]);
        assert!(report.variogram.is_empty());
        assert_eq!(report.raised_to_prior, 4);
        assert_eq!(r.recordings[0].sigma_m, [1.0, 1.0, 0.1]);
        assert_eq!(r.recordings[2].sigma_m, [0.1; 3]);
    }

    /// A bridged recording midway between anchors whose corrections differ by 2 m in x over 40 m: the random
    /// walk pinned at both has variance (2²/(2·40))·20·20/40 = 0.5 m² per horizontal axis at the middle, none
    /// at the anchors; a correction 0.3 m off the interpolation adds 0.09 m² on that axis.
    #[test]
    fn a_bridged_recordings_anchors_widen_it_by_their_difference() {
        let s: Vec<f64> = (0..9).map(|i| 5.0 * i as f64).collect();
        let corr = |j: usize| match j {
            0 => [1.0, 0.0, 0.0],
            8 => [3.0, 0.0, 0.0],
            4 => [2.3, 0.0, 0.0],
            _ => [1.0 + 0.25 * j as f64, 0.0, 0.0],
        };
        let mid = anchor_variance(4, (0, 8), &s, corr).unwrap();
        assert!((mid.bridge_m2[0] - 0.5).abs() < 1e-12 && (mid.bridge_m2[1] - 0.5).abs() < 1e-12);
        assert_eq!(mid.bridge_m2[2], 0.0);
        assert!((mid.off_interpolation_m2[0] - 0.09).abs() < 1e-12);
        assert_eq!(mid.off_interpolation_m2[1], 0.0);
        let near = anchor_variance(1, (0, 8), &s, corr).unwrap();
        assert!((near.bridge_m2[0] - 0.05 * 5.0 * 35.0 / 40.0).abs() < 1e-12);
        assert!(near.off_interpolation_m2[0] < 1e-24);
        assert!(anchor_variance(4, (8, 0), &s, corr).is_none());
    }

    /// The stretch of a drift between two controlled recordings that the adjustment left on its recorded shape
    /// (corrections equal to the first anchor's) gets a σ that covers how far it is from the interpolation; a
    /// recording beyond the last controlled one (extrapolated) is left to the variogram.
    #[test]
    fn a_bridge_left_on_its_recorded_shape_is_widened_by_its_anchors() {
        let n = 30;
        // Controlled every other recording on 0–10 and 20–29 with the same correction 0.8 m; 11–19 bridged
        // with the correction of the first anchor although the second anchor's is 2.8 m.
        let recs = (0..n)
            .map(|i| {
                let dx = if i >= 19 { 2.8 } else { 0.8 };
                recording(i, 5.0 * i as f64, [dx, 0.0, 0.0])
            })
            .collect();
        let points = (0..=10)
            .step_by(2)
            .chain((20..n).step_by(2))
            .map(|i| point(PointKind::Control, &[i]))
            .collect();
        let config = AdjustConfig {
            relative_constraints: true,
            ..AdjustConfig::default()
        };
        let mut r = run(config, recs, points);
        let report = widen_off_control_sigma(&mut r, &vec![(Some(1.0), Some(0.3)); n]);
        assert!(report.widened_by_anchors > 0);
        // Recording 15, midway: 1.0 m from the interpolation in x, plus the pinned random walk.
        let sx = r.recordings[15].sigma_m[0];
        assert!(sx > 1.0 && sx < 1.5, "{sx}");
        // Recording 19 carries the second anchor's correction: close to it, small σ from the anchors.
        assert!(r.recordings[19].sigma_m[0] < sx);
    }
}

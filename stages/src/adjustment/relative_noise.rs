//! The relative accuracy of the recorded trajectory, estimated from the trajectory itself: the σ of the
//! relative constraints between consecutive recordings (thesis 3.4.2) when the user does not give it.
//!
//! Recordings are taken at nearly constant spacing along a smooth path, so the second difference
//! `d = p[i+1] − 2·p[i] + p[i−1]` of the recorded positions is almost all noise. Only its cross-track component
//! is used (perpendicular to `p[i+1] − p[i−1]`): the along-track component also holds irregular spacing
//! (stop-and-go, time-triggered recording), the cross-track one only the path's curvature, which is large in
//! a few bends and tiny elsewhere — the median absolute deviation ignores the bends. For independent position
//! errors of σ per axis, each component of `d` has variance 6σ², and the difference of two consecutive
//! positions — what a relative constraint keeps — has σ_rel = √2·σ = σ_d / √3 per axis. A random-walk error
//! (drift) with steps of σ_w gives σ_d = √2·σ_w and so σ_rel = 0.82·σ_w: slightly tight, never wildly off.
//!
//! The estimate is floored at [`MIN_RELATIVE_SIGMA_M`] (a trajectory smooth to the millimetre still has that
//! much error between recordings) and needs [`MIN_TRIPLES`] consecutive triples, else the stage default
//! [`DEFAULT_RELATIVE_SIGMA_M`] of a healthy GNSS/INS trajectory is used and the result says so.

use crate::campaign::Recording;
use crate::estimators::median_consensus::median_in_place;
use serde::{Deserialize, Serialize};

/// Relative σ assumed when the trajectory is too short to estimate it, m (a healthy GNSS/INS trajectory).
pub const DEFAULT_RELATIVE_SIGMA_M: f64 = 0.02;
/// Smallest estimated relative σ, m.
pub const MIN_RELATIVE_SIGMA_M: f64 = 0.01;
/// Fewest consecutive triples for an estimate.
pub const MIN_TRIPLES: usize = 8;
/// σ of a normal distribution per unit of median absolute deviation.
const MAD_TO_SIGMA: f64 = 1.4826;

/// Where the relative constraints' σ came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RelativeSigmaSource {
    /// `[adjust] relative_sigma_m` in the workflow.
    Given,
    /// Estimated from the recorded trajectory.
    Estimated,
    /// Too few consecutive recordings to estimate: [`DEFAULT_RELATIVE_SIGMA_M`].
    Default,
}

/// The relative constraints' σ and how it was found.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RelativeSigma {
    /// σ per axis of the difference of two consecutive recorded positions, m.
    pub sigma_m: f64,
    pub source: RelativeSigmaSource,
    /// Consecutive triples the estimate used (0 when given).
    pub triples: usize,
    /// Relative constraints whose σ the adjustment widened because the evidence contradicts their step
    /// (`[adjust] relative_release_threshold`, `super::relative_release`).
    #[serde(default)]
    pub released: usize,
}

/// The stage default of a healthy GNSS/INS trajectory, used as such ([`RelativeSigmaSource::Default`]).
impl Default for RelativeSigma {
    fn default() -> Self {
        RelativeSigma {
            sigma_m: DEFAULT_RELATIVE_SIGMA_M,
            source: RelativeSigmaSource::Default,
            triples: 0,
            released: 0,
        }
    }
}

impl RelativeSigma {
    /// `given` if set, else the estimate from `recordings` (in trajectory order; consecutive recordings farther
    /// apart than `max_gap_m` are not neighbours).
    pub fn resolve(given: Option<f64>, recordings: &[Recording], max_gap_m: f64) -> Self {
        match given {
            Some(sigma_m) => RelativeSigma {
                sigma_m,
                source: RelativeSigmaSource::Given,
                triples: 0,
                released: 0,
            },
            None => estimate(recordings, max_gap_m),
        }
    }
}

/// The estimate described in the module documentation.
pub fn estimate(recordings: &[Recording], max_gap_m: f64) -> RelativeSigma {
    let cross_track = cross_track_second_differences(recordings, max_gap_m);
    let triples = cross_track.len();
    if triples < MIN_TRIPLES {
        return RelativeSigma {
            sigma_m: DEFAULT_RELATIVE_SIGMA_M,
            source: RelativeSigmaSource::Default,
            triples,
            released: 0,
        };
    }
    let sigma_d = MAD_TO_SIGMA * median_absolute_deviation(cross_track);
    RelativeSigma {
        sigma_m: (sigma_d / 3f64.sqrt()).max(MIN_RELATIVE_SIGMA_M),
        source: RelativeSigmaSource::Estimated,
        triples,
        released: 0,
    }
}

/// The cross-track component of the second difference at every recording whose two neighbours are within
/// `max_gap_m` (horizontal), m.
fn cross_track_second_differences(recordings: &[Recording], max_gap_m: f64) -> Vec<f64> {
    let near = |a: &Recording, b: &Recording| (a.x - b.x).hypot(a.y - b.y) <= max_gap_m;
    recordings
        .windows(3)
        .filter(|w| near(&w[0], &w[1]) && near(&w[1], &w[2]))
        .filter_map(|w| {
            let (tx, ty) = (w[2].x - w[0].x, w[2].y - w[0].y);
            let chord = tx.hypot(ty);
            let (dx, dy) = (
                w[2].x - 2.0 * w[1].x + w[0].x,
                w[2].y - 2.0 * w[1].y + w[0].y,
            );
            let cross = (dx * -ty + dy * tx) / chord;
            (chord > 0.0 && cross.is_finite()).then_some(cross)
        })
        .collect()
}

/// Median of |v − median(v)| (`values` not empty).
fn median_absolute_deviation(mut values: Vec<f64>) -> f64 {
    let centre = median_in_place(&mut values).unwrap_or(0.0);
    let mut deviations: Vec<f64> = values.iter().map(|v| (v - centre).abs()).collect();
    median_in_place(&mut deviations).unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A street of `n` recordings 5 m apart with a 90° bend of radius 20 m in the middle, plus `error(i)`.
    fn street(n: usize, error: impl Fn(usize) -> (f64, f64)) -> Vec<Recording> {
        let mut path = Vec::with_capacity(n);
        let (mut x, mut y, mut heading) = (155_000.0_f64, 463_000.0_f64, 0.0_f64);
        let bend = (n / 2)..(n / 2 + 6);
        for i in 0..n {
            let (ex, ey) = error(i);
            path.push(Recording {
                image_id: format!("r{i}"),
                x: x + ex,
                y: y + ey,
                ..Recording::default()
            });
            if bend.contains(&i) {
                heading += std::f64::consts::FRAC_PI_2 / 6.0;
            }
            x += 5.0 * heading.cos();
            y += 5.0 * heading.sin();
        }
        path
    }

    /// Deterministic N(0, 1) draws.
    fn normals(n: usize) -> Vec<f64> {
        let mut rng = crate::rng::SplitMix64::new(0x2545_f491_4f6c_dd1d);
        (0..n).map(|_| rng.next_gaussian()).collect()
    }

    #[test]
    fn white_noise_of_ten_centimetres_gives_the_consecutive_difference_sigma() {
        let z = normals(800);
        let recs = street(400, |i| (0.10 * z[2 * i], 0.10 * z[2 * i + 1]));
        let r = estimate(&recs, 15.0);
        assert_eq!(r.source, RelativeSigmaSource::Estimated);
        // σ_rel = √2 · 0.10 = 0.141 m; 400 recordings give a MAD estimate good to about ±10 %.
        assert!((r.sigma_m - 0.1414).abs() < 0.015, "{r:?}");
    }

    #[test]
    fn a_constant_offset_is_not_relative_error_and_a_smooth_path_hits_the_floor() {
        let recs = street(100, |_| (0.8, -0.3));
        let r = estimate(&recs, 15.0);
        assert_eq!(r.source, RelativeSigmaSource::Estimated);
        assert_eq!(r.sigma_m, MIN_RELATIVE_SIGMA_M);
    }

    #[test]
    fn short_or_broken_trajectories_fall_back_and_given_values_win() {
        let r = estimate(&street(6, |_| (0.0, 0.0)), 15.0);
        assert_eq!(r.source, RelativeSigmaSource::Default);
        assert_eq!(r.sigma_m, DEFAULT_RELATIVE_SIGMA_M);
        // Recordings 5 m apart but a 4 m gap limit: no neighbours at all.
        let r = estimate(&street(50, |_| (0.0, 0.0)), 4.0);
        assert_eq!((r.source, r.triples), (RelativeSigmaSource::Default, 0));
        let given = RelativeSigma::resolve(Some(0.15), &street(50, |_| (0.0, 0.0)), 15.0);
        assert_eq!(given.source, RelativeSigmaSource::Given);
        assert_eq!(given.sigma_m, 0.15);
    }
}

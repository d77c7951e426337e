//! The trajectory correction as a function of time, for sensors recorded by the same vehicle (a LiDAR
//! scanner georeferenced from the same GNSS/INS trajectory): at each recording time the correction the
//! adjustment found (adjusted − recorded position, ΔE ΔN ΔU in the campaign's world frame, and the yaw
//! correction) with its σ; between two recordings the linear interpolation of the two, whose σ grows towards
//! the middle of the interval; outside the recorded time span the nearest correction, whose σ grows with the
//! time distance. Every value says how it was obtained ([`SampleKind`]) and what supports it ([`Support`]).
//!
//! Error model of the interpolation: the trajectory error between two recordings is a random walk tied down
//! at both ends (a Brownian bridge) with rate `q = relative_sigma_m² / Δt_median` m²/s per axis, i.e. the
//! adjustment's relative accuracy between consecutive recordings (`[adjust] relative_sigma_m`, or its estimate
//! from the recorded trajectory when not given) spread over
//! the median time between recordings. At time t between recordings i and j (w = (t − tᵢ)/(tⱼ − tᵢ)):
//! `Δ(t) = (1 − w)·Δᵢ + w·Δⱼ`, `σ(t)² = ((1 − w)·σᵢ + w·σⱼ)² + q·(t − tᵢ)·(tⱼ − t)/(tⱼ − tᵢ)` (the σ term
//! assumes the two ends fully correlated, the conservative case). Outside the span: `σ(t)² = σ_end² +
//! q·|t − t_end|`. Two recordings the adjustment did not link (a gap, or separate groups) are still
//! interpolated, but flagged [`SampleKind::Gap`]. Yaw uses the same model with `yaw_relative_sigma_deg` (or,
//! without it, `yaw_prior_sigma_deg`) when yaw is estimated, and is exactly 0 otherwise.

use crate::adjustment::AdjustmentRun;
use crate::campaign::Recording;
use crate::correction::support::{recording_support, Support};
use serde::{Deserialize, Serialize};
use std::io;

/// How a correction value was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SampleKind {
    /// At a recording's time: the adjustment's own value.
    Recording,
    /// Between two linked recordings: interpolated.
    Interpolated,
    /// Between two recordings the adjustment did not link (trajectory gap or separate groups).
    Gap,
    /// Before the first or after the last recording: the nearest recording's value.
    Extrapolated,
}

impl SampleKind {
    /// The word used in the CSV files.
    pub fn label(&self) -> &'static str {
        match self {
            SampleKind::Recording => "recording",
            SampleKind::Interpolated => "interpolated",
            SampleKind::Gap => "gap",
            SampleKind::Extrapolated => "extrapolated",
        }
    }
}

/// The correction at one time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Correction {
    /// Seconds since the Unix epoch (UTC, as `time` in recordings.csv).
    pub time_s: f64,
    /// Adjusted − recorded position: east, north, up (world frame X, Y, Z), metres.
    pub delta_enu_m: [f64; 3],
    /// Adjusted − recorded yaw, degrees (clockwise seen from above, as recordings.csv `yaw`).
    pub delta_yaw_deg: f64,
    /// Standard deviations of the three position components, metres.
    pub sigma_enu_m: [f64; 3],
    pub sigma_yaw_deg: f64,
    pub kind: SampleKind,
    /// What supports the value (the weaker of the two recordings for an interpolated one).
    pub support: Support,
}

/// One recording's entry of the series.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SeriesRecording {
    pub image_id: String,
    pub correction: Correction,
    /// Linked-group index ([`crate::correction::support::linked_groups`]).
    pub group: usize,
    /// Linked to the next recording by the adjustment (same group).
    pub linked_to_next: bool,
}

/// The correction series of one adjustment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CorrectionSeries {
    /// In time order.
    pub recordings: Vec<SeriesRecording>,
    /// Random-walk rate of the position error, m²/s per axis.
    pub q_position_m2_per_s: f64,
    /// Random-walk rate of the yaw error, deg²/s (0 when yaw is not estimated).
    pub q_yaw_deg2_per_s: f64,
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// Median of the positive time steps between consecutive recordings (1 s when there is none).
fn median_step_s(times: &[f64]) -> f64 {
    let mut steps: Vec<f64> = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    if steps.is_empty() {
        return 1.0;
    }
    steps.sort_by(f64::total_cmp);
    steps[steps.len() / 2]
}

impl CorrectionSeries {
    /// The series of `run` for the campaign recordings it was run on (same order, same ids).
    pub fn from_run(recordings: &[Recording], run: &AdjustmentRun) -> io::Result<Self> {
        if recordings.len() != run.recordings.len() {
            return Err(invalid(format!(
                "the adjustment has {} recordings, the campaign {}; pass the recordings it was run on",
                run.recordings.len(),
                recordings.len()
            )));
        }
        let support = recording_support(run);
        let mut out = Vec::with_capacity(recordings.len());
        for (i, (r, a)) in recordings.iter().zip(&run.recordings).enumerate() {
            if a.image_id != r.image_id {
                return Err(invalid(format!(
                    "adjusted recording '{}' does not match campaign recording '{}'",
                    a.image_id, r.image_id
                )));
            }
            let d = |k: usize| a.adjusted_world[k] - a.recorded_world[k];
            out.push(SeriesRecording {
                image_id: r.image_id.clone(),
                correction: Correction {
                    time_s: r.time_s,
                    delta_enu_m: [d(0), d(1), d(2)],
                    delta_yaw_deg: a.yaw_correction_deg,
                    sigma_enu_m: a.sigma_m,
                    sigma_yaw_deg: a.sigma_yaw_deg,
                    kind: SampleKind::Recording,
                    support: support[i].support,
                },
                group: support[i].group,
                linked_to_next: false,
            });
        }
        for i in 1..out.len() {
            out[i - 1].linked_to_next = out[i - 1].group == out[i].group;
        }
        let times: Vec<f64> = recordings.iter().map(|r| r.time_s).collect();
        let step = median_step_s(&times);
        let c = &run.config;
        Ok(Self {
            recordings: out,
            q_position_m2_per_s: run.relative_sigma.sigma_m * run.relative_sigma.sigma_m / step,
            q_yaw_deg2_per_s: if c.estimate_yaw {
                let per_step = c.yaw_relative_sigma_deg.unwrap_or(c.yaw_prior_sigma_deg);
                per_step * per_step / step
            } else {
                0.0
            },
        })
    }

    /// The correction at `time_s` (seconds since the Unix epoch). `None` for an empty series or a
    /// non-finite time.
    pub fn at(&self, time_s: f64) -> Option<Correction> {
        if !time_s.is_finite() {
            return None;
        }
        let recs = &self.recordings;
        let first = recs.first()?;
        let last = recs.last()?;
        if time_s <= first.correction.time_s || time_s >= last.correction.time_s {
            let end = if time_s <= first.correction.time_s {
                first
            } else {
                last
            };
            let dt = (time_s - end.correction.time_s).abs();
            if dt == 0.0 {
                return Some(Correction {
                    time_s,
                    ..end.correction
                });
            }
            return Some(self.extrapolate(&end.correction, time_s, dt));
        }
        // First recording strictly after time_s; the one before it is at or before time_s.
        let j = recs.partition_point(|r| r.correction.time_s <= time_s);
        let (a, b) = (&recs[j - 1], &recs[j]);
        if a.correction.time_s == time_s {
            return Some(a.correction);
        }
        Some(self.interpolate(a, b, time_s))
    }

    fn extrapolate(&self, end: &Correction, time_s: f64, dt: f64) -> Correction {
        let grow = |s: f64, q: f64| (s * s + q * dt).sqrt();
        Correction {
            time_s,
            sigma_enu_m: end.sigma_enu_m.map(|s| grow(s, self.q_position_m2_per_s)),
            sigma_yaw_deg: grow(end.sigma_yaw_deg, self.q_yaw_deg2_per_s),
            kind: SampleKind::Extrapolated,
            ..*end
        }
    }

    fn interpolate(&self, a: &SeriesRecording, b: &SeriesRecording, time_s: f64) -> Correction {
        let (ca, cb) = (&a.correction, &b.correction);
        let span = cb.time_s - ca.time_s;
        let w = (time_s - ca.time_s) / span;
        let bridge = (time_s - ca.time_s) * (cb.time_s - time_s) / span;
        let lerp = |x: f64, y: f64| (1.0 - w) * x + w * y;
        let sigma = |x: f64, y: f64, q: f64| (lerp(x, y).powi(2) + q * bridge).sqrt();
        Correction {
            time_s,
            delta_enu_m: std::array::from_fn(|k| lerp(ca.delta_enu_m[k], cb.delta_enu_m[k])),
            delta_yaw_deg: lerp(ca.delta_yaw_deg, cb.delta_yaw_deg),
            sigma_enu_m: std::array::from_fn(|k| {
                sigma(
                    ca.sigma_enu_m[k],
                    cb.sigma_enu_m[k],
                    self.q_position_m2_per_s,
                )
            }),
            sigma_yaw_deg: sigma(ca.sigma_yaw_deg, cb.sigma_yaw_deg, self.q_yaw_deg2_per_s),
            kind: if a.linked_to_next {
                SampleKind::Interpolated
            } else {
                SampleKind::Gap
            },
            support: ca.support.weaker(cb.support),
        }
    }

    /// The rows of `corrections.csv`: every recording, and between two linked recordings the interpolated
    /// values at the multiples of `step_s` strictly between them (none across a gap: its two ends suffice).
    /// Each row with the recording's id (empty between recordings). Made one at a time as they are read, so
    /// a long campaign's 10 Hz series is never held whole.
    pub fn rows(&self, step_s: f64) -> impl Iterator<Item = (Option<&str>, Correction)> + '_ {
        self.recordings.iter().enumerate().flat_map(move |(i, r)| {
            let between = self
                .recordings
                .get(i + 1)
                .filter(|_| r.linked_to_next && step_s > 0.0)
                .map(|next| {
                    let (t0, t1) = (r.correction.time_s, next.correction.time_s);
                    let first = (t0 / step_s).floor() + 1.0;
                    (0u64..)
                        .map(move |j| (first + j as f64) * step_s)
                        .take_while(move |&t| t < t1)
                        .filter(move |&t| t > t0)
                        .map(move |t| (None, self.interpolate(r, next, t)))
                });
            std::iter::once((Some(r.image_id.as_str()), r.correction))
                .chain(between.into_iter().flatten())
        })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::adjustment::relative_noise::RelativeSigma;
    use crate::adjustment::{AdjustConfig, PointKind};
    use crate::correction::fixture::{point, recording, run};

    /// The campaign row of fixture recording `i` (same position and id).
    pub(crate) fn campaign_recording(a: &crate::adjustment::RunRecording, t: f64) -> Recording {
        Recording::new(
            &a.image_id,
            t,
            [
                a.recorded_world[0],
                a.recorded_world[1],
                a.recorded_world[2],
            ],
            90.0,
            2.5,
        )
    }

    /// Four recordings 5 m and 0.5 s apart, each moved by a known vector; control at every recording.
    pub(crate) fn fixture() -> (Vec<Recording>, AdjustmentRun) {
        let run_recs: Vec<_> = (0..4)
            .map(|i| {
                let mut r = recording(i, 5.0 * i as f64, [0.8 + 0.01 * i as f64, -0.3, 0.05]);
                r.yaw_correction_deg = 0.1 * i as f64;
                r.sigma_m = [0.02 + 0.01 * i as f64, 0.03, 0.05];
                r.sigma_yaw_deg = 0.01;
                r
            })
            .collect();
        let recs: Vec<Recording> = run_recs
            .iter()
            .enumerate()
            .map(|(i, a)| campaign_recording(a, 100.0 + 0.5 * i as f64))
            .collect();
        let config = AdjustConfig {
            relative_constraints: true,
            relative_sigma_m: Some(0.15),
            estimate_yaw: true,
            ..AdjustConfig::default()
        };
        let points = (0..4).map(|i| point(PointKind::Control, &[i])).collect();
        let mut run = run(config, run_recs, points);
        run.relative_sigma = RelativeSigma::resolve(Some(0.15), &recs, 15.0);
        (recs, run)
    }

    #[test]
    fn reproduces_the_adjusted_poses_at_recording_times() {
        let (recs, run) = fixture();
        let s = CorrectionSeries::from_run(&recs, &run).unwrap();
        for (r, a) in recs.iter().zip(&run.recordings) {
            let c = s.at(r.time_s).unwrap();
            assert_eq!(c.kind, SampleKind::Recording);
            let corrected = [r.x, r.y, r.z]
                .iter()
                .zip(c.delta_enu_m)
                .map(|(p, d)| p + d)
                .collect::<Vec<_>>();
            for k in 0..3 {
                assert!((corrected[k] - a.adjusted_world[k]).abs() < 1e-3);
            }
            assert_eq!(c.delta_yaw_deg, a.yaw_correction_deg);
            assert_eq!(c.sigma_enu_m, a.sigma_m);
        }
    }

    #[test]
    fn interpolates_linearly_with_a_growing_sigma() {
        let (recs, run) = fixture();
        let s = CorrectionSeries::from_run(&recs, &run).unwrap();
        // q = 0.15² / 0.5 s = 0.045 m²/s; halfway between r0 and r1 the bridge term is q·0.25·0.25/0.5.
        assert!((s.q_position_m2_per_s - 0.045).abs() < 1e-12);
        let c = s.at(100.25).unwrap();
        assert_eq!(c.kind, SampleKind::Interpolated);
        assert_eq!(c.support, Support::Controlled);
        assert!((c.delta_enu_m[0] - 0.805).abs() < 1e-12);
        assert!((c.delta_yaw_deg - 0.05).abs() < 1e-12);
        let expect = (0.025f64.powi(2) + 0.045 * 0.125).sqrt();
        assert!((c.sigma_enu_m[0] - expect).abs() < 1e-12);
        assert!(c.sigma_enu_m[0] > 0.03, "σ grows between recordings");
    }

    #[test]
    fn extrapolation_and_gaps_are_flagged() {
        let (recs, mut run) = fixture();
        // Recording 3 is 100 m away: no relative constraint, no shared point.
        run.recordings[3].recorded_world[0] += 100.0;
        run.points.pop();
        let s = CorrectionSeries::from_run(&recs, &run).unwrap();
        assert_eq!(s.at(101.25).unwrap().kind, SampleKind::Gap);
        assert_eq!(s.at(101.25).unwrap().support, Support::Uncorrected);
        let e = s.at(99.0).unwrap();
        assert_eq!(e.kind, SampleKind::Extrapolated);
        assert_eq!(e.delta_enu_m, s.recordings[0].correction.delta_enu_m);
        assert!((e.sigma_enu_m[0] - (0.02f64.powi(2) + 0.045).sqrt()).abs() < 1e-12);
        assert!(s.at(f64::NAN).is_none());
        // Rows: every recording plus 0.1 s steps inside linked intervals, none across the gap.
        let rows: Vec<_> = s.rows(0.1).collect();
        let between = rows.iter().filter(|(id, _)| id.is_none()).count();
        assert_eq!(rows.len() - between, 4);
        assert_eq!(
            between,
            2 * 4,
            "4 steps inside each of the two linked intervals"
        );
        assert!(rows.windows(2).all(|w| w[0].1.time_s < w[1].1.time_s));
    }

    #[test]
    fn mismatched_recordings_are_an_error() {
        let (mut recs, run) = fixture();
        recs[1].image_id = "other".into();
        let e = CorrectionSeries::from_run(&recs, &run).unwrap_err();
        assert!(e.to_string().contains("other"), "{e}");
        recs.pop();
        assert!(CorrectionSeries::from_run(&recs, &run).is_err());
    }
}

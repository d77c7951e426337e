//! Corrections applied only where the evidence shows them: the recorded trajectory is kept, stretch by stretch
//! and component by component, unless the adjustment's corrections around it are significant.
//!
//! An adjustment always moves every recording a little: its estimate scatters about the truth by its σ, and
//! where the aerial evidence is thin (few markings, façades behind trees) that σ is decimetres. A surveyor's
//! trajectory that is already good — a stretch under open sky, an RTK solution — would come back worse by that
//! scatter, and a street the aerial images barely see would be "corrected" on weak evidence. So the recorded
//! trajectory is the null hypothesis. Under it a recording's correction `Δ` (adjusted − recorded) is the
//! adjustment's own error, distributed with the recording's σ (after [`super::off_control_sigma`]).
//!
//! **Test.** Each component — horizontal position, height, yaw (when the adjustment estimated it per recording;
//! a chain of recordings whose yaw corrections are tied already passed its own test as a whole,
//! `adjustment::yaw_support`, and keeps its one common correction) — is tested
//! per recording, in a window of `window_m` along the recorded track centred on it (its linked group's
//! recordings only, [`super::support::linked_groups`]): horizontally `|Δxy| / σ_h` with
//! `σ_h² = (σx² + σy²) / 2` against `√χ²₂(1 − α/n)`, the height `|Δz| / σz` and the yaw `|Δψ| / σψ` against
//! `Φ⁻¹(1 − α/(2n))`, for `n` recordings in the window at significance level `α` (Bonferroni: a window whose
//! recorded values are right exceeds the threshold anywhere with probability at most `α`). A significant
//! correction is **corroborated** when a neighbouring recording's is significant too (or the recording is
//! the only one of its group): one wrong control point moves nothing.
//!
//! **Applied.** A recording's component is applied when a corroborated significant correction lies within
//! `window_m / 2` of it along the track: a drift moves its whole surroundings, including the recordings at
//! its onset whose own evidence is too weak to show it (a bridged recording with a wide σ). Otherwise the
//! recording keeps its recorded value of that component and says so ([`HeldComponents`]); its σ becomes
//! `√(σ² + Δ²)`: the recorded value lies `Δ` from the adjustment's estimate, which is itself `σ` from the truth.
//! The report lists the held stretches (consecutive held recordings) per component.

use super::off_control_sigma::along_track_m;
use super::support::linked_groups;
use crate::adjustment::{AdjustmentRun, HeldComponents, RunRecording};
use crate::estimators::normal_quantile::{chi2_2_quantile, normal_quantile};
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// The tested components, in the order of the arrays below.
pub const COMPONENTS: [&str; 3] = ["horizontal", "height", "yaw"];

/// A run of consecutive recordings of one linked group whose component was held.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeldStretch {
    /// `horizontal`, `height` or `yaw`.
    pub component: String,
    pub first_image_id: String,
    pub last_image_id: String,
    pub recordings: usize,
    /// The stretch's largest normalised correction |Δ| / σ (before it was held).
    pub largest: f64,
}

/// What [`hold_insignificant`] did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Significance {
    /// The significance level α of each window's test.
    pub level: f64,
    /// Length of the window along the track, m.
    pub window_m: f64,
    /// Yaw was estimated, so tested.
    pub yaw_tested: bool,
    /// Recordings whose horizontal / height / yaw correction was significant (corroborated or not).
    pub significant: [usize; 3],
    pub held: Vec<HeldStretch>,
}

impl Significance {
    /// Recordings whose horizontal / height / yaw correction was held.
    pub fn held_recordings(&self) -> [usize; 3] {
        let mut out = [0; 3];
        for h in &self.held {
            if let Some(k) = COMPONENTS.iter().position(|c| *c == h.component) {
                out[k] += h.recordings;
            }
        }
        out
    }
}

/// For every recording, its window: the recordings within `half_m` along the track (inclusive) of the run of
/// consecutive recordings of its linked group that holds it.
fn windows(s_m: &[f64], groups: &[usize], half_m: f64) -> Vec<Range<usize>> {
    let n = s_m.len();
    let (mut lo, mut hi, mut run_start) = (0, 0, 0);
    (0..n)
        .map(|i| {
            if i > 0 && groups[i] != groups[i - 1] {
                run_start = i;
            }
            // Both ends only move forward as i does (s grows with i).
            lo = lo.max(run_start);
            while lo < i && s_m[i] - s_m[lo] > half_m {
                lo += 1;
            }
            hi = hi.max(i + 1);
            while hi < n && groups[hi] == groups[i] && s_m[hi] - s_m[i] <= half_m {
                hi += 1;
            }
            lo..hi
        })
        .collect()
}

/// The normalised corrections (|Δ| / σ) of a recording: horizontal, height, yaw.
fn normalised_corrections(r: &RunRecording) -> [f64; 3] {
    let d = |k: usize| r.adjusted_world[k] - r.recorded_world[k];
    let s_h = ((r.sigma_m[0].powi(2) + r.sigma_m[1].powi(2)) / 2.0).sqrt();
    [
        normalised(d(0).hypot(d(1)), s_h),
        normalised(d(2), r.sigma_m[2]),
        normalised(r.yaw_correction_deg, r.sigma_yaw_deg),
    ]
}

/// |Δ| / σ, or 0 for a correction without σ (the test then sees nothing significant in it).
fn normalised(delta: f64, sigma: f64) -> f64 {
    if sigma > 0.0 && sigma.is_finite() && delta.is_finite() {
        delta.abs() / sigma
    } else {
        0.0
    }
}

/// The thresholds for `n` recordings at level `level`, Bonferroni over them: horizontal (χ²₂), height and
/// yaw (normal).
pub fn thresholds(level: f64, n: usize) -> [f64; 3] {
    let per = level / n.max(1) as f64;
    let k_1 = normal_quantile(1.0 - per / 2.0).unwrap_or(f64::INFINITY);
    [
        chi2_2_quantile(1.0 - per).map_or(f64::INFINITY, f64::sqrt),
        k_1,
        k_1,
    ]
}

/// Tests every recording's corrections at level `level` in windows of `window_m` (module documentation) and
/// holds the components without a corroborated significant correction nearby at the recorded values, widening
/// their σ.
pub fn hold_insignificant(run: &mut AdjustmentRun, level: f64, window_m: f64) -> Significance {
    let n = run.recordings.len();
    let groups = linked_groups(run);
    let s_m = along_track_m(run);
    let win = windows(&s_m, &groups, window_m / 2.0);
    let z: Vec<[f64; 3]> = run.recordings.iter().map(normalised_corrections).collect();
    let components = if run.config.estimate_yaw { 3 } else { 2 };
    // A chain of recordings whose yaw corrections are tied passed its own significance test as a whole
    // (`adjustment::yaw_support`); its yaw is one common correction, not tested again piece by piece.
    let mut yaw_decided = vec![false; n];
    for chain in run.yaw_chains.iter().filter(|c| c.tied) {
        for &i in chain.recordings.iter().filter(|&&i| i < n) {
            yaw_decided[i] = true;
        }
    }
    let significant: Vec<[bool; 3]> = (0..n)
        .map(|i| {
            let k = thresholds(level, win[i].len());
            std::array::from_fn(|c| c < components && z[i][c] > k[c])
        })
        .collect();
    let alone = |i: usize| {
        (i == 0 || groups[i - 1] != groups[i]) && (i + 1 == n || groups[i + 1] != groups[i])
    };
    let corroborated: Vec<[bool; 3]> = (0..n)
        .map(|i| {
            let linked = |j: usize, c: usize| groups[j] == groups[i] && significant[j][c];
            std::array::from_fn(|c| {
                significant[i][c]
                    && (alone(i) || (i > 0 && linked(i - 1, c)) || (i + 1 < n && linked(i + 1, c)))
            })
        })
        .collect();
    let mut report = Significance {
        level,
        window_m,
        yaw_tested: components == 3,
        significant: std::array::from_fn(|c| significant.iter().filter(|s| s[c]).count()),
        held: Vec::new(),
    };
    let held: Vec<HeldComponents> = (0..n)
        .map(|i| {
            let applied = |c: usize| win[i].clone().any(|j| corroborated[j][c]);
            HeldComponents {
                horizontal: !applied(0),
                height: !applied(1),
                yaw: components == 3 && !yaw_decided[i] && !applied(2),
            }
        })
        .collect();
    report.held = held_stretches(run, &groups, &z, &held, components);
    for (r, h) in run.recordings.iter_mut().zip(held) {
        hold(r, h);
    }
    report
}

/// The runs of consecutive recordings of one linked group whose component `c` is held, per component, with
/// their largest normalised correction `z`.
fn held_stretches(
    run: &AdjustmentRun,
    groups: &[usize],
    z: &[[f64; 3]],
    held: &[HeldComponents],
    components: usize,
) -> Vec<HeldStretch> {
    let n = held.len();
    let mut out = Vec::new();
    for c in 0..components {
        let is_held = |i: usize| held[i].as_array()[c];
        let mut i = 0;
        while i < n {
            if !is_held(i) {
                i += 1;
                continue;
            }
            let start = i;
            while i + 1 < n && is_held(i + 1) && groups[i + 1] == groups[start] {
                i += 1;
            }
            out.push(HeldStretch {
                component: COMPONENTS[c].to_string(),
                first_image_id: run.recordings[start].image_id.clone(),
                last_image_id: run.recordings[i].image_id.clone(),
                recordings: i + 1 - start,
                largest: (start..=i).map(|k| z[k][c]).fold(0.0, f64::max),
            });
            i += 1;
        }
    }
    out
}

/// Puts the `held` components of `r` back to the recorded values and widens their σ by the correction.
fn hold(r: &mut RunRecording, held: HeldComponents) {
    let axes: &[usize] = match (held.horizontal, held.height) {
        (true, true) => &[0, 1, 2],
        (true, false) => &[0, 1],
        (false, true) => &[2],
        (false, false) => &[],
    };
    for &k in axes {
        let d = r.adjusted_world[k] - r.recorded_world[k];
        r.sigma_m[k] = r.sigma_m[k].hypot(d);
        r.adjusted_world[k] = r.recorded_world[k];
    }
    if held.yaw {
        r.sigma_yaw_deg = r.sigma_yaw_deg.hypot(r.yaw_correction_deg);
        r.yaw_correction_deg = 0.0;
    }
    r.held = held;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjustment::{AdjustConfig, PointKind};
    use crate::correction::fixture;

    /// `n` recordings 5 m apart, each moved by `delta(i)` with σ 0.02 m, linked in one chain.
    fn chain(n: usize, delta: impl Fn(usize) -> [f64; 3]) -> AdjustmentRun {
        let recordings = (0..n)
            .map(|i| {
                let mut r = fixture::recording(i, 5.0 * i as f64, delta(i));
                r.sigma_m = [0.02; 3];
                r
            })
            .collect();
        let points = (1..n)
            .map(|i| fixture::point(PointKind::Tie, &[i - 1, i]))
            .collect();
        fixture::run(AdjustConfig::default(), recordings, points)
    }

    /// The held stretches of `component` as (first, last) recording indices of `chain`'s ids (`r{i}`).
    fn stretches(report: &Significance, component: &str) -> Vec<(usize, usize)> {
        let index = |id: &str| id[1..].parse::<usize>().unwrap();
        report
            .held
            .iter()
            .filter(|h| h.component == component)
            .map(|h| (index(&h.first_image_id), index(&h.last_image_id)))
            .collect()
    }

    #[test]
    fn thresholds_follow_from_the_level_and_the_number_of_recordings() {
        // 21 recordings at α = 0.05: √χ²₂(1 − 0.05/21) = 3.475, Φ⁻¹(1 − 0.025/21) = 3.038.
        let [h, z, yaw] = thresholds(0.05, 21);
        assert!((h - 3.4752).abs() < 1e-3, "{h}");
        assert!((z - 3.0381).abs() < 1e-3, "{z}");
        assert_eq!(z, yaw);
    }

    #[test]
    fn windows_hold_the_recordings_within_half_their_length_of_the_same_group() {
        let s = [0.0, 5.0, 10.0, 15.0, 20.0, 0.0, 5.0];
        let g = [0, 0, 0, 0, 0, 5, 5];
        let w = windows(&s, &g, 5.0);
        assert_eq!(w, vec![0..2, 0..3, 1..4, 2..5, 3..5, 5..7, 5..7]);
        // Groups that interleave (a later drive linked to an earlier one): a window never crosses another group.
        let s = [0.0, 5.0, 10.0, 15.0];
        let g = [0, 1, 0, 0];
        assert_eq!(windows(&s, &g, 20.0), vec![0..1, 1..2, 2..4, 2..4]);
    }

    #[test]
    fn corrections_within_their_noise_are_held_and_say_so() {
        // Horizontal corrections of 1.5 σ and height corrections of 1 σ: nothing significant.
        let mut run = chain(20, |i| {
            let s = if i % 2 == 0 { 1.0 } else { -1.0 };
            [0.03 * s, 0.0, 0.02 * s]
        });
        let report = hold_insignificant(&mut run, 0.05, 100.0);
        assert_eq!(report.held_recordings(), [20, 20, 0]);
        assert_eq!(stretches(&report, "horizontal"), vec![(0, 19)]);
        assert!(!report.yaw_tested);
        for r in &run.recordings {
            assert_eq!(r.adjusted_world, r.recorded_world);
            assert_eq!(r.held.label(), "xy+z");
            // σ widened by the correction not applied: √(0.02² + 0.03²) in x, √(0.02² + 0.02²) in z.
            assert!((r.sigma_m[0] - 0.036_06).abs() < 1e-4, "{:?}", r.sigma_m);
            assert!((r.sigma_m[1] - 0.02).abs() < 1e-12);
            assert!((r.sigma_m[2] - 0.028_28).abs() < 1e-4);
        }
    }

    #[test]
    fn a_significant_offset_is_applied_and_a_weak_component_beside_it_held() {
        // 0.5 m east (25 σ) everywhere, heights within the noise.
        let mut run = chain(20, |_| [0.5, 0.0, 0.01]);
        let before: Vec<[f64; 3]> = run.recordings.iter().map(|r| r.adjusted_world).collect();
        let report = hold_insignificant(&mut run, 0.05, 100.0);
        assert_eq!(report.held_recordings(), [0, 20, 0]);
        assert_eq!(report.significant[0], 20);
        for (r, b) in run.recordings.iter().zip(&before) {
            assert_eq!(r.adjusted_world[..2], b[..2]);
            assert_eq!(r.adjusted_world[2], r.recorded_world[2]);
            assert_eq!(r.held.label(), "z");
        }
    }

    #[test]
    fn one_outlier_moves_nothing() {
        let mut run = chain(20, |i| if i == 7 { [0.4, 0.0, 0.0] } else { [0.0; 3] });
        let report = hold_insignificant(&mut run, 0.05, 100.0);
        assert_eq!(report.significant[0], 1);
        assert_eq!(report.held_recordings()[0], 20);
        assert_eq!(
            run.recordings[7].adjusted_world,
            run.recordings[7].recorded_world
        );
    }

    #[test]
    fn a_drift_moves_its_surroundings_and_nothing_farther() {
        // 60 recordings over 295 m; a drift over recordings 30–33 (up to 0.4 m, 20 σ), nothing elsewhere. With a
        // 100 m window the recordings within 50 m of the drift (20–43) are corrected, the rest kept.
        let mut run = chain(60, |i| match i {
            30..=33 => [0.1 * (i - 29) as f64, 0.0, 0.0],
            _ => [0.005, 0.0, 0.0],
        });
        let report = hold_insignificant(&mut run, 0.05, 100.0);
        assert_eq!(stretches(&report, "horizontal"), vec![(0, 19), (44, 59)]);
        let r = &run.recordings[32];
        assert!((r.adjusted_world[0] - r.recorded_world[0] - 0.3).abs() < 1e-9);
        // Recording 25 moved by its 5 mm; recording 10 kept.
        assert!(
            (run.recordings[25].adjusted_world[0] - run.recordings[25].recorded_world[0] - 0.005)
                .abs()
                < 1e-9
        );
        assert_eq!(
            run.recordings[10].adjusted_world,
            run.recordings[10].recorded_world
        );
    }

    #[test]
    fn a_weakly_observed_onset_of_a_drift_is_moved_with_it() {
        // Recording 19 drifts by 0.15 m but is bridged (σ 0.12 m: 1.2 σ); 20.. drift by 0.3 m and more (15 σ).
        let mut run = chain(30, |i| match i {
            19 => [0.15, 0.0, 0.0],
            20.. => [0.3 + 0.05 * (i - 20) as f64, 0.0, 0.0],
            _ => [0.01, 0.0, 0.0],
        });
        run.recordings[19].sigma_m = [0.12; 3];
        hold_insignificant(&mut run, 0.05, 100.0);
        let r = &run.recordings[19];
        assert!(!r.held.horizontal);
        assert!((r.adjusted_world[0] - r.recorded_world[0] - 0.15).abs() < 1e-9);
    }

    #[test]
    fn separate_groups_do_not_move_each_other() {
        // Recordings 0–9 and 10–19 are not linked; only the second group is off.
        let mut run = chain(20, |i| {
            if i >= 10 {
                [0.5, 0.0, 0.0]
            } else {
                [0.01, 0.0, 0.0]
            }
        });
        run.points.remove(9);
        let report = hold_insignificant(&mut run, 0.05, 100.0);
        assert_eq!(stretches(&report, "horizontal"), vec![(0, 9)]);
    }

    #[test]
    fn yaw_is_tested_when_estimated() {
        let mut run = chain(10, |_| [0.0; 3]);
        run.config.estimate_yaw = true;
        for (i, r) in run.recordings.iter_mut().enumerate() {
            r.sigma_yaw_deg = 0.02;
            r.yaw_correction_deg = if i < 5 { 0.3 } else { 0.01 };
        }
        let report = hold_insignificant(&mut run, 0.05, 100.0);
        assert!(report.yaw_tested);
        assert_eq!(report.significant[2], 5);
        assert_eq!(report.held_recordings()[2], 0);
        assert_eq!(run.recordings[0].yaw_correction_deg, 0.3);

        let mut weak = chain(10, |_| [0.0; 3]);
        weak.config.estimate_yaw = true;
        for r in &mut weak.recordings {
            r.sigma_yaw_deg = 0.1;
            r.yaw_correction_deg = 0.05;
        }
        let mut tied = weak.clone();
        let report = hold_insignificant(&mut weak, 0.05, 100.0);
        assert_eq!(report.held_recordings(), [10, 10, 10]);
        assert_eq!(weak.recordings[3].yaw_correction_deg, 0.0);
        assert!((weak.recordings[3].sigma_yaw_deg - 0.1118).abs() < 1e-3);

        // The same corrections as one tied chain: its common correction stands.
        tied.yaw_chains = vec![crate::adjustment::yaw_support::ChainYaw {
            recordings: (0..10).collect(),
            correction_rad: 0.05_f64.to_radians(),
            sigma_rad: 0.02_f64.to_radians(),
            tied: true,
        }];
        let report = hold_insignificant(&mut tied, 0.05, 100.0);
        assert_eq!(report.held_recordings(), [10, 10, 0]);
        assert_eq!(tied.recordings[3].yaw_correction_deg, 0.05);
    }
}

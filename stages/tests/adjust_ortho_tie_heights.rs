//! Known-answer test of tie-point heights from a terrain model (`[adjust] dtm_tie_heights`): on a synthetic
//! block whose tie points are each seen by two consecutive recordings only — as most of the nadir matching's
//! are — the pairs fix their baselines' directions but not their lengths, so a stretch without control keeps
//! the recordings' own along-track error; with the heights of the tie points seen from recordings without
//! control observed, the stretch is carried by the tie points to centimetres.

mod common_adjust;

use common_adjust::{relative_config_with, runs_without_and_with, weak_prior_campaign};
use nalgebra::Vector3;
use skytie_stages::adjustment::problem::HeightObservation;
use skytie_stages::adjustment::synthetic_campaign::SyntheticCampaign;
use skytie_stages::adjustment::{run, AdjustInputs};

/// Recordings without control of their own.
const STRETCH: std::ops::RangeInclusive<usize> = 10..=29;

fn campaign() -> SyntheticCampaign {
    // Each recording off by up to 0.3 m on its own, besides the common 0.8 m.
    let mut c = weak_prior_campaign(40, 0.3, 0.0, 5);
    // Two views per tie point: the first two recordings that see it.
    for tp in &mut c.tie_points {
        tp.observations.truncate(2);
    }
    // No control seen from the stretch.
    let observed_in_stretch: Vec<bool> = (0..c.control.len())
        .map(|k| {
            c.control_observed_from(k)
                .iter()
                .any(|r| STRETCH.contains(r))
        })
        .collect();
    let mut k = 0;
    c.control.retain(|_| {
        k += 1;
        !observed_in_stretch[k - 1]
    });
    c
}

/// Along-track error (m) of each adjusted recording of `run` against the truth.
fn along_track_errors_m(
    c: &SyntheticCampaign,
    run: &skytie_stages::adjustment::AdjustmentRun,
) -> Vec<f64> {
    let t = &c.truth.true_centers_world;
    (0..t.len())
        .map(|i| {
            let d = t[(i + 1).min(t.len() - 1)] - t[i.saturating_sub(1)];
            let dir = Vector3::new(d.x, d.y, 0.0).normalize();
            let a = run.recordings[i].adjusted_world;
            (a[0] - t[i].x) * dir.x + (a[1] - t[i].y) * dir.y
        })
        .collect()
}

#[test]
fn observed_tie_point_heights_hold_a_stretch_without_control_along_the_trajectory() {
    let c = campaign();
    assert!(c.control.len() >= 10, "{}", c.control.len());
    // The terrain model's height of every tie point: its true height, σ 0.05 m.
    let heights: Vec<Option<HeightObservation>> = c
        .truth
        .true_points_world
        .iter()
        .map(|p| {
            Some(HeightObservation {
                z_world: p.z,
                sigma_m: 0.05,
            })
        })
        .collect();
    let inputs = AdjustInputs {
        tie_point_heights: Some(&heights),
        ..c.adjust_inputs()
    };
    let (plain, observed) = runs_without_and_with(&inputs, |config| config.dtm_tie_heights = true);
    assert_eq!(plain.build.tie_point_heights, 0);
    // Every tie point seen from a recording without control gets one (a recording whose only control the
    // block does not use counts as without control there, so a few more may), and not those where every
    // recording has control.
    let n = observed.build.tie_point_heights;
    assert!(
        n >= expected_heights(&c, |_| true) && n < c.tie_points.len(),
        "{n}"
    );
    let rms = |e: &[f64]| (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt();
    let (before, after) = (
        along_track_errors_m(&c, &plain),
        along_track_errors_m(&c, &observed),
    );
    let (b, a) = (rms(&before[STRETCH]), rms(&after[STRETCH]));
    println!(
        "recordings 10–29 along-track RMS error: {b:.3} m without, {a:.3} m with tie-point heights"
    );
    // Without heights the stretch keeps much of its own along-track error (uniform in a 0.3 m disc: 0.15 m RMS
    // per axis).
    assert!(b > 0.05, "{before:?}");
    // With them the tie points carry it to a few centimetres (the heights' 0.05 m σ against the relative
    // constraints' 0.15 m leaves 0.027 m here), under a quarter of it.
    assert!(a < 0.035 && a < 0.25 * b, "{after:?}");
}

/// The tie points (`with_height` by index) that get a height: not a control point, and seen from a recording
/// that observes no control point.
fn expected_heights(c: &SyntheticCampaign, with_height: impl Fn(usize) -> bool) -> usize {
    let mut controlled = vec![false; c.recordings.len()];
    for k in 0..c.control.len() {
        for r in c.control_observed_from(k) {
            controlled[r] = true;
        }
    }
    let control_ids: std::collections::HashSet<&str> = c
        .control
        .iter()
        .map(|cp| cp.tie_point_id.as_str())
        .collect();
    c.tie_points
        .iter()
        .enumerate()
        .filter(|(k, tp)| {
            with_height(*k)
                && !control_ids.contains(tp.id.as_str())
                && tp.observations.iter().any(|o| {
                    let r = c.recordings.iter().position(|r| r.image_id == o.image_id);
                    r.is_some_and(|r| !controlled[r])
                })
        })
        .count()
}

#[test]
fn tie_point_heights_need_the_key_and_skip_control_points_and_controlled_recordings() {
    let c = campaign();
    let heights: Vec<Option<HeightObservation>> = c
        .tie_points
        .iter()
        .enumerate()
        .map(|(k, tp)| {
            (k % 2 == 0).then_some(HeightObservation {
                z_world: tp.point_world[2],
                sigma_m: 0.05,
            })
        })
        .collect();
    let inputs = AdjustInputs {
        tie_point_heights: Some(&heights),
        ..c.adjust_inputs()
    };
    let r = run(
        &inputs,
        &relative_config_with(|config| config.dtm_tie_heights = true),
    )
    .unwrap();
    let expected = expected_heights(&c, |k| k % 2 == 0);
    let n = r.build.tie_point_heights;
    assert!(
        n >= expected && n <= expected + expected / 20,
        "{n} {expected}"
    );
    // Those of the stretch without control, not those where every recording has control.
    let stretch_points = c
        .tie_points
        .iter()
        .filter(|tp| {
            tp.observations.iter().all(|o| {
                let r = c.recordings.iter().position(|r| r.image_id == o.image_id);
                r.is_some_and(|r| STRETCH.contains(&r))
            })
        })
        .count();
    assert!(
        expected >= stretch_points / 3 && expected < c.tie_points.len() / 2,
        "{expected} {stretch_points}"
    );
}

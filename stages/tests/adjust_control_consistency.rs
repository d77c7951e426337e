//! Known-answer tests of the orthophoto route's two safeguards on synthetic blocks: control that is wrong
//! together on neighbouring recordings — strong, and agreeing with itself — is caught against the control of
//! the other recordings nearby (`[adjust] control_consistency_window`), and a stretch beyond the last
//! recording with control keeps that recording's correction instead of drifting with a noisy tie-point chain
//! (`[adjust] extrapolation_anchor`), while staying flagged as extrapolated. The first check works the same
//! when the control points' aerial pixels go into the bundle (`aerial_observations`).

mod common_adjust;

use common_adjust::{
    relative_config_with, runs_without_and_with, weak_prior_campaign, RELATIVE_SIGMA_M,
};
use nalgebra::Vector3;
use skytie_stages::adjustment::control_consistency::tolerance_m;
use skytie_stages::adjustment::run;
use skytie_stages::adjustment::synthetic_campaign::SyntheticCampaign;
use skytie_stages::export::{recording_support, Support};
use skytie_stages::geometry::FrameCamera;

/// The weak-prior campaign with every control point seen only from recordings 19–22 moved 0.5 m east (its
/// `point_world`): strong, and consistent with the others of its stretch — a template matched at a wrong place
/// by several recordings. Returns the campaign and the moved points.
fn wrong_together_at_19_to_22() -> (SyntheticCampaign, Vec<usize>) {
    let mut c = weak_prior_campaign(30, 0.05, 0.0, 5);
    let wrong: Vec<usize> = (0..c.control.len())
        .filter(|&k| {
            c.control_observed_from(k)
                .iter()
                .all(|r| (19..=22).contains(r))
        })
        .collect();
    assert!(wrong.len() >= 2, "{wrong:?}");
    for &k in &wrong {
        let p = c.control[k].point_world.as_mut().expect("triangulated");
        p[0] += 0.5;
    }
    (c, wrong)
}

#[test]
fn control_wrong_together_on_neighbouring_recordings_is_not_used() {
    let (c, wrong) = wrong_together_at_19_to_22();
    let (plain, checked) = runs_without_and_with(&c.adjust_inputs(), |config| {
        config.control_consistency_window = Some(20)
    });
    let (before, after) = (
        c.horizontal_errors_m(&plain),
        c.horizontal_errors_m(&checked),
    );
    let worst = |e: &[f64]| e[19..=22].iter().copied().fold(0.0, f64::max);
    println!(
        "recordings 19–22: worst error {:.3} m unchecked, {:.3} m checked (tolerance {:.3} m)",
        worst(&before),
        worst(&after),
        tolerance_m(RELATIVE_SIGMA_M)
    );
    // Unchecked, the wrong points take recordings 19–22 0.14 m off (the tie points and the relative
    // constraints spread it); checked, every recording is back within 0.01 m of the truth.
    assert!(worst(&before) > 0.1, "{before:?}");
    assert!(after.iter().all(|&e| e < 0.01), "{after:?}");
    // Exactly the wrong points were dropped; they stay tie points.
    assert_eq!(checked.build.inconsistent_control_dropped, wrong.len());
    assert_eq!(
        checked.build.control_as_gcp,
        plain.build.control_as_gcp - wrong.len()
    );
    assert_eq!(plain.build.inconsistent_control_dropped, 0);
}

#[test]
fn wrong_aerial_pixels_in_the_bundle_are_caught_like_wrong_ground_control() {
    // The same wrong content as above, but as aerial pixels: every aerial pixel of a moved point is where the
    // point 0.5 m east of its true place would be.
    let (mut c, wrong) = wrong_together_at_19_to_22();
    for &k in &wrong {
        let moved = Vector3::from(c.control[k].point_world.expect("triangulated"));
        for o in &mut c.control[k].aerial {
            let image = c
                .nadir
                .iter()
                .find(|n| n.image_id == o.image_id)
                .expect("nadir");
            let (u, v) = FrameCamera::from_aerial(image)
                .project_world(&moved)
                .expect("in view");
            (o.u_px, o.v_px) = (u, v);
        }
    }
    let (unchecked, checked) = {
        let in_bundle = relative_config_with(|config| config.aerial_observations = true);
        let mut with_check = in_bundle.clone();
        with_check.control_consistency_window = Some(20);
        let inputs = c.adjust_inputs();
        (
            run(&inputs, &in_bundle).unwrap(),
            run(&inputs, &with_check).unwrap(),
        )
    };
    assert!(unchecked.build.aerial_observations > 0);
    let (before, after) = (
        c.horizontal_errors_m(&unchecked),
        c.horizontal_errors_m(&checked),
    );
    let worst = |e: &[f64]| e[19..=22].iter().copied().fold(0.0, f64::max);
    println!(
        "aerial pixels, recordings 19–22: worst error {:.3} m unchecked, {:.3} m checked",
        worst(&before),
        worst(&after),
    );
    assert!(worst(&before) > 0.1, "{before:?}");
    assert!(after.iter().all(|&e| e < 0.01), "{after:?}");
    // Exactly the wrong points' aerial observations left the bundle.
    assert_eq!(checked.build.inconsistent_control_dropped, wrong.len());
    let wrong_pixels: usize = wrong.iter().map(|&k| c.control[k].aerial.len()).sum();
    assert_eq!(
        checked.build.aerial_observations,
        unchecked.build.aerial_observations - wrong_pixels
    );
    assert_eq!(
        checked.build.control_as_aerial_observations,
        unchecked.build.control_as_aerial_observations - wrong.len()
    );
    assert_eq!(unchecked.build.inconsistent_control_dropped, 0);
}

#[test]
fn a_stretch_beyond_the_last_control_keeps_its_correction_and_stays_flagged() {
    // The recorded error is one offset common to the whole trajectory, so the stretch's true correction is
    // the last controlled recording's; the panorama pixels are noisy, so the tie-point chain drifts.
    let mut c = weak_prior_campaign(30, 0.0, 1.5, 7);
    c.control
        .retain(|cp| cp.mm.iter().all(|o| o.image_id.as_str() < "pano_0028"));
    let ids: Vec<&str> = c.recordings.iter().map(|r| r.image_id.as_str()).collect();
    assert!(ids.windows(2).all(|w| w[0] < w[1]), "{ids:?}");
    let (plain, anchored) = runs_without_and_with(&c.adjust_inputs(), |config| {
        config.extrapolation_anchor = true
    });
    let support = recording_support(&anchored);
    let last = support
        .iter()
        .rposition(|s| s.support == Support::Controlled)
        .expect("control");
    let tail = last + 1..c.recordings.len();
    assert!(tail.len() >= 10, "{tail:?}");
    assert!(support[tail.clone()]
        .iter()
        .all(|s| s.support == Support::Extrapolated));
    assert_eq!(anchored.build.extrapolation_anchors, tail.len());
    let (before, after) = (
        c.horizontal_errors_m(&plain),
        c.horizontal_errors_m(&anchored),
    );
    let rms = |e: &[f64]| (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt();
    println!(
        "stretch after recording {last}: RMS error {:.3} m by the tie-point chain, {:.3} m anchored; controlled \
         part {:.3} / {:.3} m",
        rms(&before[tail.clone()]),
        rms(&after[tail.clone()]),
        rms(&before[..=last]),
        rms(&after[..=last])
    );
    // 0.090 m by the chain, 0.076 m anchored (the anchor's own error, 0.03 m, stays).
    assert!(rms(&after[tail.clone()]) < 0.9 * rms(&before[tail.clone()]));
    // The controlled part does not change beyond a few millimetres.
    assert!((rms(&after[..=last]) - rms(&before[..=last])).abs() < 0.005);
}

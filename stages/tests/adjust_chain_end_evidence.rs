//! Known-answer test of the chain-end check (`[adjust] chain_end_min_aerial_observations`): a wrong point seen
//! in a single aerial image that alone anchors the start of the street moves the first recordings by its error;
//! left out, they follow the correction of the rest of the chain and are flagged `extrapolated`.

mod common_adjust;

use common_adjust::{relative_config_with, weak_prior_campaign};
use nalgebra::Vector3;
use skytie_stages::adjustment::run;
use skytie_stages::export::{recording_support, Support};
use skytie_stages::geometry::FrameCamera;

/// Aerial error of the lone point, metres east.
const WRONG_EAST_M: f64 = 1.0;

#[test]
fn a_wrong_single_aerial_observation_alone_at_the_street_start_is_left_out() {
    // Every recording shares one recorded offset, so the true correction of the first recordings is the
    // one the rest of the chain shows.
    let mut c = weak_prior_campaign(30, 0.0, 0.0, 11);
    // The start's evidence: one point seen only from recordings 0-3; every other control point is seen
    // only from recording 8 on.
    let start = (0..c.control.len())
        .filter(|&k| c.control_observed_from(k).iter().all(|&r| r <= 3))
        .min_by_key(|&k| c.control_observed_from(k).into_iter().max())
        .expect("a control point at the start");
    let lone_id = c.control[start].tie_point_id.clone();
    let lone_observers = c.control_observed_from(start);
    c.control.retain(|cp| {
        cp.tie_point_id == lone_id
            || cp
                .mm
                .iter()
                .all(|o| c.recordings.iter().position(|r| r.image_id == o.image_id) >= Some(8))
    });
    assert!(c.control.len() >= 5, "{}", c.control.len());
    // One aerial pixel, where the point 1 m east of its true place would be.
    let lone = c
        .control
        .iter_mut()
        .find(|cp| cp.tie_point_id == lone_id)
        .expect("kept");
    lone.aerial.truncate(1);
    let mut moved = Vector3::from(lone.point_world.expect("triangulated"));
    moved.x += WRONG_EAST_M;
    lone.point_world = None;
    let image = c
        .nadir
        .iter()
        .find(|n| n.image_id == lone.aerial[0].image_id)
        .expect("nadir");
    (lone.aerial[0].u_px, lone.aerial[0].v_px) = FrameCamera::from_aerial(image)
        .project_world(&moved)
        .expect("in view");

    let in_bundle = relative_config_with(|config| config.aerial_observations = true);
    let mut checked_config = in_bundle.clone();
    checked_config.chain_end_min_aerial_observations = 2;
    let inputs = c.adjust_inputs();
    let unchecked = run(&inputs, &in_bundle).unwrap();
    let checked = run(&inputs, &checked_config).unwrap();
    let (before, after) = (
        c.horizontal_errors_m(&unchecked),
        c.horizontal_errors_m(&checked),
    );
    let last_observer = *lone_observers.iter().max().expect("observed");
    let worst = |e: &[f64]| e[..=last_observer].iter().copied().fold(0.0, f64::max);
    println!(
        "recordings 0-{last_observer}: worst error {:.3} m with the lone point, {:.3} m without",
        worst(&before),
        worst(&after)
    );
    // With it, the start follows the wrong point by most of its error.
    assert!(worst(&before) > 0.5 * WRONG_EAST_M, "{before:?}");
    // Without it, the start keeps the chain's correction, as does every other recording (with it, the
    // pull reaches recordings well past the start through the relative constraints).
    assert!(after.iter().all(|&e| e < 0.01), "{after:?}");
    assert!(before[8] > 0.05, "{before:?}");
    assert_eq!(checked.build.chain_end_evidence_dropped, 1);
    assert_eq!(unchecked.build.chain_end_evidence_dropped, 0);
    assert_eq!(
        checked.build.aerial_observations,
        unchecked.build.aerial_observations - 1
    );
    // The recordings it would have moved say that they are extrapolated.
    let support = recording_support(&checked);
    for s in &support[..=last_observer] {
        assert_eq!(s.support, Support::Extrapolated);
    }
    assert_eq!(
        recording_support(&unchecked)[lone_observers[0]].support,
        Support::Controlled
    );
}

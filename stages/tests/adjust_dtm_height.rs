//! Known-answer tests of the recordings' height observations from a terrain model (`[adjust] dtm_height`): a
//! synthetic block whose recorded heights are biased gets its true heights back from a synthetic DTM of its
//! ground, a campaign without a DTM observes nothing and says so, and a recording off the DTM is counted.

use nalgebra::Vector3;
use skytie_stages::adjustment::height_observation::{
    dtm_height_sigma_m, terrain_heights, HeightSource,
};
use skytie_stages::adjustment::synthetic_campaign::SyntheticCampaignSpec;
use skytie_stages::adjustment::{run, AdjustConfig, AdjustmentRun, SyntheticBlockSpec};

/// Stated σ of the synthetic DTM, metres.
const DTM_SIGMA_M: f64 = 0.02;

/// A block without aerial control (nothing but the recorded heights and the terrain model fixes Z) whose
/// recorded heights are all 0.40 m too high, with a stated σ_z of 0.30 m.
fn biased_block() -> SyntheticCampaignSpec {
    SyntheticCampaignSpec {
        block: SyntheticBlockSpec {
            control_points: 0,
            z_offset_m: 0.40,
            prior_sigma_xy_m: 1.0,
            prior_sigma_z_m: 0.30,
            seed: 3,
            ..SyntheticBlockSpec::default()
        },
        ..SyntheticCampaignSpec::default()
    }
}

/// The synthetic DTM: the ground under the true trajectory (camera centres minus the 2.5 m camera height),
/// continued along the local direction of travel with the trajectory's slope; `None` beyond `max_x_m`.
fn ground_z_m(true_centres: &[Vector3<f64>], x: f64, y: f64, max_x_m: f64) -> Option<f64> {
    if x > max_x_m {
        return None;
    }
    let p = Vector3::new(x, y, 0.0);
    let i = (0..true_centres.len())
        .min_by(|&a, &b| {
            let da = (true_centres[a] - p).xy().norm();
            let db = (true_centres[b] - p).xy().norm();
            da.total_cmp(&db)
        })
        .expect("recordings");
    let (a, b) = match i + 1 < true_centres.len() {
        true => (true_centres[i], true_centres[i + 1]),
        false => (true_centres[i - 1], true_centres[i]),
    };
    let step = b - a;
    let along_m = (p - true_centres[i]).xy().dot(&step.xy()) / step.xy().norm();
    Some(true_centres[i].z - 2.5 + along_m * step.z / step.xy().norm())
}

fn z_errors_m(run: &AdjustmentRun, true_centres: &[Vector3<f64>]) -> Vec<f64> {
    run.recordings
        .iter()
        .zip(true_centres)
        .map(|(r, t)| r.adjusted_world[2] - t.z)
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

#[test]
fn biased_recorded_heights_come_back_from_a_synthetic_dtm() {
    let campaign = biased_block().generate();
    let truth = &campaign.truth.true_centers_world;
    let sigma_m = dtm_height_sigma_m(DTM_SIGMA_M, 0.02);
    let heights = terrain_heights(
        &campaign.recordings,
        |x, y| ground_z_m(truth, x, y, f64::INFINITY),
        sigma_m,
    );
    assert!(heights.iter().all(Option::is_some));
    let off = AdjustConfig::default();
    let on = AdjustConfig {
        dtm_height: true,
        ..AdjustConfig::default()
    };
    let mut inputs = campaign.adjust_inputs();
    inputs.heights = Some(&heights);
    let without = run(&inputs, &off).unwrap();
    let with = run(&inputs, &on).unwrap();
    let (e_without, e_with) = (z_errors_m(&without, truth), z_errors_m(&with, truth));
    println!(
        "mean Z error without the DTM {:.3} m, with it {:.4} m (max |error| {:.4} m)",
        mean(&e_without),
        mean(&e_with),
        e_with.iter().map(|e| e.abs()).fold(0.0, f64::max)
    );
    // Without the DTM the heights keep their bias; with it they come back to the truth (σ 0.028 m per
    // recording against the recorded heights' 0.30 m: 0.4 m · 0.028² / 0.30² = 0.004 m of the bias stays),
    // within what the DTM sampled at the recorded position, 0.8 m off on a 2 % slope, adds (≤ 0.016 m).
    assert!((mean(&e_without) - 0.40).abs() < 0.02, "{e_without:?}");
    assert!(mean(&e_with).abs() < 0.022, "{e_with:?}");
    assert!(e_with.iter().all(|e| e.abs() < 0.025), "{e_with:?}");
    assert_eq!(with.build.heights.source, HeightSource::Dtm);
    assert_eq!(with.build.heights.observed, campaign.recordings.len());
    assert_eq!(with.build.heights.without_terrain, 0);
    assert!((with.build.heights.sigma_m - sigma_m).abs() < 1e-12);
    assert_eq!(without.build.heights.source, HeightSource::Off);
    // One height observation per recording joins the priors.
    assert_eq!(
        with.observations.priors,
        without.observations.priors + campaign.recordings.len()
    );
}

#[test]
fn without_a_dtm_nothing_is_observed_and_the_run_says_so() {
    let campaign = biased_block().generate();
    let on = AdjustConfig {
        dtm_height: true,
        ..AdjustConfig::default()
    };
    let inputs = campaign.adjust_inputs();
    assert!(inputs.heights.is_none());
    let asked = run(&inputs, &on).unwrap();
    let plain = run(&inputs, &AdjustConfig::default()).unwrap();
    assert_eq!(asked.build.heights.source, HeightSource::NoDtm);
    assert_eq!(asked.build.heights.observed, 0);
    assert_eq!(asked.recordings, plain.recordings);
    assert!(asked.build.heights.describe().contains("no DTM"));
}

#[test]
fn recordings_off_the_dtm_get_no_height_and_are_counted() {
    let campaign = biased_block().generate();
    let truth = &campaign.truth.true_centers_world;
    // The DTM ends a little past the middle of the block.
    let mut xs: Vec<f64> = campaign.recordings.iter().map(|r| r.x).collect();
    xs.sort_by(f64::total_cmp);
    let max_x_m = xs[xs.len() / 2];
    let sigma_m = dtm_height_sigma_m(DTM_SIGMA_M, 0.02);
    let heights = terrain_heights(
        &campaign.recordings,
        |x, y| ground_z_m(truth, x, y, max_x_m),
        sigma_m,
    );
    let inside = heights.iter().flatten().count();
    assert!(inside > 10 && inside < campaign.recordings.len());
    let mut inputs = campaign.adjust_inputs();
    inputs.heights = Some(&heights);
    let on = AdjustConfig {
        dtm_height: true,
        ..AdjustConfig::default()
    };
    let with = run(&inputs, &on).unwrap();
    assert_eq!(with.build.heights.observed, inside);
    assert_eq!(
        with.build.heights.without_terrain,
        campaign.recordings.len() - inside
    );
    // The observed recordings are back at the truth; the tie points carry the correction some way beyond.
    let e = z_errors_m(&with, truth);
    for (h, e) in heights.iter().zip(&e) {
        if h.is_some() {
            assert!(e.abs() < 0.04, "{e}");
        }
    }
    // A height list of the wrong length is refused with what to do.
    inputs.heights = Some(&heights[1..]);
    let err = run(&inputs, &on).unwrap_err().to_string();
    assert!(
        err.contains("recording heights") && err.contains("per recording"),
        "{err}"
    );
}

//! Fixtures shared by the adjustment's integration tests (`adjust_*`): the largest position error of an
//! adjustment against its synthetic block's truth, synthetic blocks with relative constraints and a GNSS
//! outage drifting part of the recorded trajectory, and the synthetic campaign with weak recorded-position
//! priors that the control tests (consistency, orthophoto control) adjust with relative constraints, with
//! and without the option under test.
//! Each test file uses what it needs.

#![allow(dead_code)]

use skytie_stages::adjustment::synthetic_campaign::{SyntheticCampaign, SyntheticCampaignSpec};
use skytie_stages::adjustment::{
    consecutive_constraints, run, AdjustConfig, AdjustInputs, Adjustment, AdjustmentRun,
    SyntheticBlock, SyntheticBlockSpec,
};
use std::ops::Range;

/// Largest 3-D distance of an adjusted recording from its true position, metres.
pub fn max_position_error_m(block: &SyntheticBlock, adj: &Adjustment) -> f64 {
    adj.recordings
        .iter()
        .zip(&block.true_centers_world)
        .map(|(r, t)| (r.position_world - t).norm())
        .fold(0.0, f64::max)
}

/// The recordings a simulated GNSS outage drifts: 12–27.
pub const OUTAGE: Range<usize> = 12..28;

/// The block of `spec` with relative constraints of σ `sigma_rel_m` between consecutive recordings.
pub fn constrained_block(spec: SyntheticBlockSpec, sigma_rel_m: f64) -> SyntheticBlock {
    let mut synth = spec.generate();
    let n = synth.block.recordings.len();
    synth.block.relative_constraints = consecutive_constraints(n, sigma_rel_m);
    synth
}

/// Size of a smooth outage drift at `t` (0 at the first drifted recording, 1 one recording after the last):
/// a sin² bump up to 1.5 m and back, metres.
pub fn outage_bump_m(t: f64) -> f64 {
    1.5 * (std::f64::consts::PI * t).sin().powi(2)
}

/// [`constrained_block`] whose recorded positions in [`OUTAGE`] are moved horizontally by `drift(t)` (x, y),
/// metres, with `t` as in [`outage_bump_m`].
pub fn drifted_block(
    spec: SyntheticBlockSpec,
    sigma_rel_m: f64,
    drift: impl Fn(f64) -> [f64; 2],
) -> SyntheticBlock {
    let mut synth = constrained_block(spec, sigma_rel_m);
    for (i, r) in synth.block.recordings.iter_mut().enumerate() {
        if OUTAGE.contains(&i) {
            let [dx, dy] = drift((i - OUTAGE.start) as f64 / OUTAGE.len() as f64);
            r.camera.center_world.x += dx;
            r.camera.center_world.y += dy;
        }
    }
    synth
}

/// σ of the relative constraints between consecutive recordings in [`relative_config`], metres.
pub const RELATIVE_SIGMA_M: f64 = 0.15;

/// A synthetic campaign whose recorded positions are weak priors (σ 3 m horizontal, 0.3 m vertical) with
/// `control_points` aerial control points, each seen in at least two aerial images (no single-image
/// points); the recorded positions share the default systematic offset plus a random one of up to
/// `random_offset_m`, and the panorama observations carry Gaussian noise of σ `pixel_noise_px`.
pub fn weak_prior_campaign(
    control_points: usize,
    random_offset_m: f64,
    pixel_noise_px: f64,
    seed: u64,
) -> SyntheticCampaign {
    SyntheticCampaignSpec {
        block: SyntheticBlockSpec {
            control_points,
            random_offset_m,
            pixel_noise_px,
            prior_sigma_xy_m: 3.0,
            prior_sigma_z_m: 0.3,
            seed,
            ..SyntheticBlockSpec::default()
        },
        single_aerial_every: 0,
        ..SyntheticCampaignSpec::default()
    }
    .generate()
}

/// The default adjustment with relative constraints of σ [`RELATIVE_SIGMA_M`] between consecutive
/// recordings.
pub fn relative_config() -> AdjustConfig {
    AdjustConfig {
        relative_constraints: true,
        relative_sigma_m: Some(RELATIVE_SIGMA_M),
        ..AdjustConfig::default()
    }
}

/// [`relative_config`] with `option` applied (the option under test turned on).
pub fn relative_config_with(option: impl FnOnce(&mut AdjustConfig)) -> AdjustConfig {
    let mut config = relative_config();
    option(&mut config);
    config
}

/// `inputs` adjusted with [`relative_config`] and with [`relative_config_with`] `option`: (without the
/// option, with it).
pub fn runs_without_and_with(
    inputs: &AdjustInputs,
    option: impl FnOnce(&mut AdjustConfig),
) -> (AdjustmentRun, AdjustmentRun) {
    let without = run(inputs, &relative_config()).unwrap();
    let with = run(inputs, &relative_config_with(option)).unwrap();
    (without, with)
}

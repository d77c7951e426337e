//! Known-answer test of the Gauss–Markov trajectory error model (`adjustment::gauss_markov`): a street whose
//! recorded positions share a common offset plus white noise (the thesis' error), with aerial evidence only on
//! its second half. The correction found there must carry to the start of the street instead of fading back
//! to the recorded positions.

mod common_adjust;

use common_adjust::constrained_block;
use skytie_stages::adjustment::gauss_markov::carry;
use skytie_stages::adjustment::{adjust, AdjustOptions, SyntheticBlock, SyntheticBlockSpec};
use skytie_stages::rng::SplitMix64;

/// Prior σ of the recorded positions, m (horizontal and vertical).
const PRIOR_SIGMA_M: f64 = 1.0;
/// White noise on each recorded horizontal coordinate, m.
const NOISE_M: f64 = 0.10;
/// σ of a consecutive difference of white noise of [`NOISE_M`]: √2 × 0.10 m, what the relative σ estimate
/// gives for this error.
const SIGMA_REL_M: f64 = 0.141;
/// Recordings without any panorama observation: the start of the street, carried only by the trajectory.
const WITHOUT_EVIDENCE: std::ops::Range<usize> = 0..17;

/// Deterministic N(0, 1) draws.
fn normals(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix64::new(seed);
    (0..n).map(|_| rng.next_gaussian()).collect()
}

/// 40 recordings 0.8 m off in a common direction plus white noise of 0.10 m per axis, 1 m priors, relative
/// constraints of σ 0.141 m, and no panorama observation in recordings 0–16; with `gauss_markov` the
/// constraints carry φ = √(1 − σ_rel² / σ_abs²).
fn street(seed: u64, gauss_markov: bool) -> SyntheticBlock {
    let spec = SyntheticBlockSpec {
        systematic_offset_m: 0.8,
        random_offset_m: 0.0,
        prior_sigma_xy_m: PRIOR_SIGMA_M,
        prior_sigma_z_m: PRIOR_SIGMA_M,
        seed,
        ..SyntheticBlockSpec::default()
    };
    let mut synth = constrained_block(spec, SIGMA_REL_M);
    let z = normals(
        2 * synth.block.recordings.len(),
        seed ^ 0x9e37_79b9_7f4a_7c15,
    );
    for (i, r) in synth.block.recordings.iter_mut().enumerate() {
        r.camera.center_world.x += NOISE_M * z[2 * i];
        r.camera.center_world.y += NOISE_M * z[2 * i + 1];
    }
    synth
        .block
        .pano_observations
        .retain(|o| !WITHOUT_EVIDENCE.contains(&o.recording));
    if gauss_markov {
        let phi = carry(SIGMA_REL_M, PRIOR_SIGMA_M, PRIOR_SIGMA_M);
        for rc in &mut synth.block.relative_constraints {
            rc.carry_xy = phi;
            rc.carry_z = phi;
        }
    }
    synth
}

/// Horizontal error of each adjusted recording, m.
fn errors_m(synth: &SyntheticBlock) -> Vec<f64> {
    let adj = adjust(&synth.block, &AdjustOptions::default()).unwrap();
    adj.recordings
        .iter()
        .zip(&synth.true_centers_world)
        .map(|(r, t)| (r.position_world - t).xy().norm())
        .collect()
}

/// Horizontal error of each recording of the start if it took recording 17's correction exactly (what a
/// perfect carry of the evidence gives when nothing observes the white noise), m.
fn carried_exactly_m(synth: &SyntheticBlock) -> Vec<f64> {
    let error =
        |i: usize| synth.block.recordings[i].camera.center_world - synth.true_centers_world[i];
    let anchor = error(WITHOUT_EVIDENCE.end);
    WITHOUT_EVIDENCE
        .map(|i| (error(i) - anchor).xy().norm())
        .collect()
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|e| e * e).sum::<f64>() / v.len() as f64).sqrt()
}

/// Under the random-walk model the start's 17 independent 1 m priors pull it back to the recorded positions:
/// the 0.8 m correction fades within about 7 recordings. Under the Gauss–Markov model it carries: what is
/// left is the white noise, which nothing observes there (√2 × 0.10 m per axis about the carried correction).
/// Measured on seeds 3, 4, 5: start RMS (2-D) 0.495 / 0.563 / 0.531 m under the random walk, 0.208 / 0.209 /
/// 0.215 m under Gauss–Markov, 0.256 / 0.170 / 0.214 m for recording 17's correction carried exactly; the
/// recordings with evidence 0.026–0.028 m (random walk) and 0.003–0.007 m (Gauss–Markov).
#[test]
fn a_correction_carries_to_the_start_of_the_street() {
    for seed in [3, 4, 5] {
        let random_walk = errors_m(&street(seed, false));
        let synth = street(seed, true);
        let gauss_markov = errors_m(&synth);
        let ideal = rms(&carried_exactly_m(&synth));
        let start = |e: &[f64]| rms(&e[WITHOUT_EVIDENCE]);
        let rest = |e: &[f64]| rms(&e[WITHOUT_EVIDENCE.end..]);
        println!(
            "seed {seed}: start RMS {:.3} m random walk, {:.3} m Gauss–Markov, {ideal:.3} m carried exactly; \
             rest {:.3} / {:.3} m",
            start(&random_walk),
            start(&gauss_markov),
            rest(&random_walk),
            rest(&gauss_markov)
        );
        // Recording 17's own adjusted correction is not exact, and φ < 1 lets the correction fade slightly.
        assert!(start(&gauss_markov) < 1.3 * ideal, "{gauss_markov:?}");
        assert!(
            start(&random_walk) > 2.0 * start(&gauss_markov),
            "{random_walk:?}"
        );
        assert!(
            rest(&gauss_markov) < 0.01,
            "recordings with evidence: {gauss_markov:?}"
        );
    }
}

/// Without a relative constraint leading into it a recording keeps its own prior: a block without
/// constraints adjusts the same under both models.
#[test]
fn the_first_recording_of_each_chain_keeps_its_prior() {
    let mut synth = street(3, true);
    // Break the chain after recording 20: recording 21 starts a new one and has its prior again.
    synth.block.relative_constraints.retain(|rc| rc.to != 21);
    let adj = adjust(&synth.block, &AdjustOptions::default()).unwrap();
    // Priors of recordings 0 and 21, x and y and z each.
    assert_eq!(adj.observations.priors, 6);
}

//! Posterior precision, weighting methods and input errors of the bundle adjustment core: analytic σ of
//! tiny blocks, a Monte Carlo check of the a-priori σ on noisy synthetic blocks, the thesis 5.7 weighting
//! methods on an exact block, and located errors for bad input.

mod common_adjust;

use common_adjust::max_position_error_m;
use nalgebra::Vector3;
use skytie_stages::adjustment::{
    adjust, AdjustError, AdjustOptions, Block, BlockRecording, PanoObservation, RelativeConstraint,
    ResidualWeighting, SyntheticBlockSpec, WeightingMethod,
};
use skytie_stages::geometry::PanoramaCamera;

fn recording(x: f64, sigma_xy: Option<f64>, sigma_z: Option<f64>) -> BlockRecording {
    BlockRecording {
        camera: PanoramaCamera::new(
            4800,
            2400,
            Vector3::new(250_000.0 + x, 5_600_000.0, 102.5),
            0.0,
            0.0,
            0.0,
        ),
        prior_sigma_xy_m: sigma_xy,
        prior_sigma_z_m: sigma_z,
        height_observation: None,
    }
}

#[test]
fn a_recording_constrained_by_one_prior_has_the_prior_sigma() {
    let block = Block {
        recordings: vec![recording(0.0, Some(0.5), Some(0.2))],
        ..Block::default()
    };
    let adj = adjust(&block, &AdjustOptions::default()).unwrap();
    let s = adj.recordings[0].sigma_a_priori_m;
    assert!(
        (s.x - 0.5).abs() < 1e-14 && (s.y - 0.5).abs() < 1e-14 && (s.z - 0.2).abs() < 1e-14,
        "{s:?}"
    );
    assert_eq!(adj.redundancy, 0);
    assert_eq!(adj.variance_factor, None);
    assert_eq!(
        adj.recordings[0].position_world,
        block.recordings[0].camera.center_world
    );
}

#[test]
fn two_priors_and_a_relative_constraint_give_the_analytic_sigma() {
    let (sigma, sigma_rel) = (0.3, 0.05);
    let block = Block {
        recordings: vec![
            recording(0.0, Some(sigma), Some(sigma)),
            recording(5.0, Some(sigma), Some(sigma)),
        ],
        relative_constraints: vec![RelativeConstraint::new(0, 1, sigma_rel)],
        ..Block::default()
    };
    let adj = adjust(&block, &AdjustOptions::default()).unwrap();
    // N = [[a, −b], [−b, a]] per axis with a = 1/σ² + 1/σr², b = 1/σr²; (N⁻¹)₁₁ = a / (a² − b²).
    let a = 1.0 / (sigma * sigma) + 1.0 / (sigma_rel * sigma_rel);
    let b = 1.0 / (sigma_rel * sigma_rel);
    let expected = (a / (a * a - b * b)).sqrt();
    for r in &adj.recordings {
        for axis in 0..3 {
            assert!(
                (r.sigma_a_priori_m[axis] - expected).abs() < 1e-12 * expected,
                "{r:?}"
            );
        }
    }
    // Redundancy: 6 prior + 3 relative components − 6 unknowns.
    assert_eq!(adj.redundancy, 3);
    assert_eq!(adj.variance_factor, Some(0.0));
}

#[test]
fn monte_carlo_spread_matches_the_a_priori_sigma() {
    let mut sum_sq = Vector3::zeros();
    let mut count = 0usize;
    let mut sum_residual_sq = 0.0;
    let mut expected_sum = 0.0;
    let runs = 30;
    for seed in 0..runs {
        let synth = SyntheticBlockSpec {
            recordings: 12,
            control_points: 6,
            pixel_noise_px: 1.0,
            sigma_px: 1.0,
            control_noise_m: 0.10,
            seed: 100 + seed,
            ..SyntheticBlockSpec::default()
        }
        .generate();
        let adj = adjust(&synth.block, &AdjustOptions::default()).unwrap();
        for (r, t) in adj.recordings.iter().zip(&synth.true_centers_world) {
            let z = (r.position_world - t).component_div(&r.sigma_a_priori_m);
            sum_sq += z.component_mul(&z);
            count += 1;
        }
        // The weak priors (σ 100 m) each carry a redundancy number ≈ 1 but a residual ≈ 0.008σ (the recorded
        // positions are a deterministic 0.8 m off, not N(0, σ²) draws), so Σr² ≈ redundancy − prior components.
        sum_residual_sq += adj.variance_factor.unwrap() * adj.redundancy as f64;
        expected_sum += (adj.redundancy - adj.observations.priors as i64) as f64;
    }
    let rms = (sum_sq / count as f64).map(f64::sqrt);
    let mean_vf = sum_residual_sq / expected_sum;
    println!("normalised RMS error per axis {rms:?}, Σr² / (redundancy − priors) {mean_vf:.3}");
    // Errors of recordings in one block are correlated, so the effective sample is smaller than 360.
    for axis in 0..3 {
        assert!(
            rms[axis] > 0.75 && rms[axis] < 1.25,
            "axis {axis}: {}",
            rms[axis]
        );
    }
    assert!((mean_vf - 1.0).abs() < 0.05, "{mean_vf}");
}

#[test]
fn every_weighting_method_converges_on_exact_data() {
    let synth = SyntheticBlockSpec::default().generate();
    for method in [
        WeightingMethod::Unweighted,
        WeightingMethod::NearWeighted,
        WeightingMethod::FarWeighted,
        WeightingMethod::GsdWeighted,
    ] {
        let options = AdjustOptions {
            weighting: ResidualWeighting::new(method),
            ..AdjustOptions::default()
        };
        let adj = adjust(&synth.block, &options).unwrap();
        let err = max_position_error_m(&synth, &adj);
        // Method 2 drops rays at ≥ 15 m (evaluated at the initial estimate).
        let far = synth
            .block
            .pano_observations
            .iter()
            .filter(|o| {
                (synth.block.points_initial_world[o.point]
                    - synth.block.recordings[o.recording].camera.center_world)
                    .norm()
                    >= 15.0
            })
            .count();
        println!(
            "{method:?}: max error {err:.2e} m, unused {} (far rays {far})",
            adj.unused_pano
        );
        assert!(err < 1e-3, "{method:?}: {err}");
        if method == WeightingMethod::NearWeighted {
            assert!(
                far > 0 && adj.unused_pano >= far,
                "{} < {far}",
                adj.unused_pano
            );
        } else {
            assert_eq!(adj.unused_pano, 0);
        }
    }
}

#[test]
fn bad_input_is_located() {
    let mut block = Block {
        recordings: vec![recording(0.0, Some(1.0), Some(1.0))],
        points_initial_world: vec![Vector3::new(250_005.0, 5_600_003.0, 100.0)],
        pano_observations: vec![PanoObservation {
            recording: 3,
            point: 0,
            u_px: 10.0,
            v_px: 1200.0,
            sigma_px: 1.0,
        }],
        ..Block::default()
    };
    match adjust(&block, &AdjustOptions::default()) {
        Err(AdjustError::InvalidPanoObservation { index: 0, problem }) => {
            assert!(problem.contains("recording"))
        }
        other => panic!("{other:?}"),
    }
    block.pano_observations[0].recording = 0;
    block.pano_observations[0].sigma_px = 0.0;
    assert!(matches!(
        adjust(&block, &AdjustOptions::default()),
        Err(AdjustError::InvalidPanoObservation { index: 0, .. })
    ));
    block.recordings[0].prior_sigma_xy_m = Some(f64::NAN);
    assert!(matches!(
        adjust(&block, &AdjustOptions::default()),
        Err(AdjustError::InvalidRecording {
            index: 0,
            field: "sigma_xy_m",
            ..
        })
    ));
    // Without priors or control the block has no datum.
    let mut synth = SyntheticBlockSpec {
        recordings: 6,
        control_points: 0,
        ..SyntheticBlockSpec::default()
    }
    .generate();
    for r in &mut synth.block.recordings {
        r.prior_sigma_xy_m = None;
        r.prior_sigma_z_m = None;
    }
    assert!(matches!(
        adjust(&synth.block, &AdjustOptions::default()),
        Err(AdjustError::Singular { .. })
    ));
}

//! Known-answer comparison of the control schemes on a synthetic block with nadir aerial images,
//! compared against the thesis' scheme: (a) the thesis scheme (control points triangulated from ≥ 2
//! aerial images, σ = 0.10 m, 5.4.3), (b) aerial pixel observations in the bundle with the aerial orientation
//! fixed, (c) robust loss + rejection with injected gross outliers. Built through
//! `build_block`/`run` from the correspondence types, so the plumbing is tested too.

use skytie_stages::adjustment::synthetic_campaign::{SyntheticCampaign, SyntheticCampaignSpec};
use skytie_stages::adjustment::trajectory_errors::trajectory_errors;
use skytie_stages::adjustment::{
    run, AdjustConfig, AdjustmentRun, ControlWeighting, Dimensions, LossKind, SyntheticBlockSpec,
};

/// (max 2-D, max 3-D, RMSE 2-D) error of the adjusted positions against the truth, metres.
fn errors(c: &SyntheticCampaign, r: &AdjustmentRun) -> (f64, f64, f64) {
    let (mut max2, mut max3, mut sum2) = (0.0f64, 0.0f64, 0.0);
    for (rec, t) in r.recordings.iter().zip(&c.truth.true_centers_world) {
        let d = nalgebra::Vector3::from(rec.adjusted_world) - t;
        let d2 = d.xy().norm();
        max2 = max2.max(d2);
        max3 = max3.max(d.norm());
        sum2 += d2 * d2;
    }
    (max2, max3, (sum2 / r.recordings.len() as f64).sqrt())
}

fn thesis() -> AdjustConfig {
    AdjustConfig::default()
}

fn aerial_in_bundle() -> AdjustConfig {
    AdjustConfig {
        aerial_observations: true,
        ..AdjustConfig::default()
    }
}

fn robust() -> AdjustConfig {
    AdjustConfig {
        loss: LossKind::Huber,
        loss_scale: 2.0,
        rejection_threshold: Some(3.0),
        ..AdjustConfig::default()
    }
}

fn exact_spec() -> SyntheticCampaignSpec {
    SyntheticCampaignSpec {
        block: SyntheticBlockSpec {
            recordings: 30,
            control_points: 12,
            seed: 7,
            ..SyntheticBlockSpec::default()
        },
        ..SyntheticCampaignSpec::default()
    }
}

#[test]
fn all_three_schemes_recover_the_true_poses_from_exact_observations() {
    let c = exact_spec().generate();
    let initial = c
        .recordings
        .iter()
        .zip(&c.truth.true_centers_world)
        .map(|(r, t)| (r.x - t.x).hypot(r.y - t.y))
        .fold(0.0, f64::max);
    assert!(initial > 0.7, "deteriorated by {initial} m");
    let singles = c.control.iter().filter(|cp| cp.aerial.len() == 1).count();
    assert!(singles >= 2, "{singles} single-aerial control points");

    let a = run(&c.adjust_inputs(), &thesis()).unwrap();
    assert_eq!(a.build.control_as_gcp, c.control.len() - singles);
    assert_eq!(a.build.control_unused, singles);
    assert_eq!(a.observations.aerial, 0);
    let (ea, _, _) = errors(&c, &a);

    let b = run(&c.adjust_inputs(), &aerial_in_bundle()).unwrap();
    assert_eq!(b.build.control_as_aerial_observations, c.control.len());
    assert_eq!(b.observations.control, 0);
    assert_eq!(
        b.observations.aerial,
        c.control.iter().map(|cp| cp.aerial.len()).sum::<usize>()
    );
    let (eb, _, _) = errors(&c, &b);

    // (c) on the same data with 3 % gross outliers (20–50 px) in the panorama observations.
    let mut spec = exact_spec();
    spec.block.outlier_fraction = 0.03;
    let co = spec.generate();
    let injected = &co.truth.outlier_observations;
    assert!(injected.len() >= 5, "{} outliers", injected.len());
    let rc = run(&co.adjust_inputs(), &robust()).unwrap();
    let (ec, _, _) = errors(&co, &rc);
    let plain = run(&co.adjust_inputs(), &thesis()).unwrap();
    let (e_plain, _, _) = errors(&co, &plain);
    eprintln!(
        "exact block, max 3-D error: (a) thesis {ea:.2e} m, (b) aerial in bundle {eb:.2e} m, \
         (c) robust {ec:.2e} m with {} of {} outliers rejected (plain LS on the same data: {e_plain:.3} m)",
        rc.rejected.pano,
        injected.len()
    );
    assert!(ea < 1e-3, "thesis scheme error {ea}");
    assert!(eb < 1e-3, "aerial-in-bundle error {eb}");
    assert!(ec < 1e-3, "robust error {ec}");
    assert_eq!(rc.rejected.pano, injected.len());
    assert!(
        e_plain > 10.0 * ec.max(1e-4),
        "outliers should hurt plain LS: {e_plain}"
    );
}

#[test]
fn single_aerial_points_alone_fix_the_block_only_with_aerial_observations() {
    // Every control point is seen in exactly one aerial image: the thesis scheme has no control at all.
    let spec = SyntheticCampaignSpec {
        single_aerial_every: 1,
        ..exact_spec()
    };
    let c = spec.generate();
    assert!(c.control.iter().all(|cp| cp.aerial.len() == 1));
    let a = run(&c.adjust_inputs(), &thesis()).unwrap();
    assert_eq!(a.build.control_as_gcp, 0);
    let (ea, _, _) = errors(&c, &a);
    let b = run(&c.adjust_inputs(), &aerial_in_bundle()).unwrap();
    let (eb, _, _) = errors(&c, &b);
    eprintln!("single-aerial control only: thesis scheme {ea:.3} m, aerial in bundle {eb:.2e} m");
    assert!(ea > 0.5, "without control the block keeps its offset: {ea}");
    assert!(eb < 1e-3, "single aerial rays fix the block: {eb}");
}

#[test]
fn noisy_block_all_schemes_within_their_precision() {
    let spec = SyntheticCampaignSpec {
        block: SyntheticBlockSpec {
            recordings: 40,
            control_points: 15,
            pixel_noise_px: 0.5,
            sigma_px: 0.5,
            seed: 11,
            ..SyntheticBlockSpec::default()
        },
        aerial_noise_px: 0.5,
        aerial_sigma_px: 0.5,
        ..SyntheticCampaignSpec::default()
    };
    let c = spec.generate();
    let configs = [
        (
            "thesis",
            AdjustConfig {
                pano_sigma_px: 0.5,
                ..thesis()
            },
        ),
        (
            "thesis-covariance",
            AdjustConfig {
                pano_sigma_px: 0.5,
                control_weighting: ControlWeighting::Covariance,
                ..thesis()
            },
        ),
        (
            "aerial",
            AdjustConfig {
                pano_sigma_px: 0.5,
                ..aerial_in_bundle()
            },
        ),
        (
            "robust",
            AdjustConfig {
                pano_sigma_px: 0.5,
                ..robust()
            },
        ),
        (
            "horizontal",
            AdjustConfig {
                pano_sigma_px: 0.5,
                dimensions: Dimensions::Horizontal,
                ..thesis()
            },
        ),
    ];
    for (name, config) in configs {
        let r = run(&c.adjust_inputs(), &config).unwrap();
        let (max2, max3, rmse2) = errors(&c, &r);
        eprintln!(
            "noisy block (0.5 px pano and aerial noise), {name}: RMSE 2-D {rmse2:.4} m, max 2-D {max2:.4} m, \
             max 3-D {max3:.4} m, {} iterations, cost {:.3}, σ̂0² {:?}, rejected {}",
            r.iterations, r.final_cost, r.variance_factor, r.rejected_total
        );
        // 0.80 m + 0.10 m deterioration; 0.5 px aerial noise is 5 cm on the ground per observation.
        assert!(rmse2 < 0.03, "{name}: RMSE 2-D {rmse2}");
        assert!(max2 < 0.06, "{name}: max 2-D {max2}");
        // Each recording within 4 posterior σ (horizontal components) plus 5 mm.
        for (rec, t) in r.recordings.iter().zip(&c.truth.true_centers_world) {
            for k in 0..2 {
                let e = (rec.adjusted_world[k] - t[k]).abs();
                assert!(
                    e < 4.0 * rec.sigma_m[k] + 0.005,
                    "{name} {}: axis {k} error {e} vs σ {}",
                    rec.image_id,
                    rec.sigma_m[k]
                );
            }
        }
    }
}

#[test]
fn trajectory_errors_against_truth_and_determinism_across_thread_counts() {
    // Purely systematic deterioration: the recorded differences between consecutive recordings are then
    // exact, so relative constraints are consistent with the truth (with a random part they would not be).
    let mut spec = exact_spec();
    spec.block.random_offset_m = 0.0;
    let c = spec.generate();
    let truth: Vec<_> = c
        .recordings
        .iter()
        .zip(&c.truth.true_centers_world)
        .map(|(r, t)| {
            let mut r = r.clone();
            [r.x, r.y, r.z] = [t.x, t.y, t.z];
            r
        })
        .collect();
    let config = AdjustConfig {
        relative_constraints: true,
        ..aerial_in_bundle()
    };
    let in_pool = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run(&c.adjust_inputs(), &config).unwrap())
    };
    let one = in_pool(1);
    let two = in_pool(2);
    assert_eq!(
        serde_json::to_string(&one).unwrap(),
        serde_json::to_string(&two).unwrap()
    );
    assert_eq!(one.build.relative_constraints, c.recordings.len() - 1);
    let e = trajectory_errors(&one, &truth);
    eprintln!("exact block with relative constraints: {e:?}");
    assert_eq!(e.missing_truth, 0);
    assert_eq!(e.before.count, c.recordings.len());
    // 0.8 m systematic before; exact after.
    assert!(
        (e.before.rmse_2d - 0.8).abs() < 1e-9 && (e.before.max_2d - 0.8).abs() < 1e-9,
        "{e:?}"
    );
    assert!(e.after.max_2d < 1e-3 && e.after.rmse_3d < 1e-3, "{e:?}");
}

#[test]
fn aerial_observations_behind_the_camera_are_skipped_not_fatal() {
    let mut c = exact_spec().generate();
    // Move one nadir camera below the ground: its observations can no longer be of the points.
    let victim = c.control[0].aerial[0].image_id.clone();
    let row = c.nadir.iter_mut().find(|r| r.image_id == victim).unwrap();
    row.z -= 1000.0;
    let seen_by_victim = c
        .control
        .iter()
        .flat_map(|cp| &cp.aerial)
        .filter(|a| a.image_id == victim)
        .count();
    let r = run(&c.adjust_inputs(), &aerial_in_bundle()).unwrap();
    assert_eq!(r.build.aerial_observations_skipped, seen_by_victim);
    assert_eq!(
        r.build.aerial_observations + seen_by_victim,
        c.control.iter().map(|cp| cp.aerial.len()).sum::<usize>()
    );
}

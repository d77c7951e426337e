//! Known-answer tests of MLESAC plane fitting (Torr & Zisserman 2000; 50 % outliers to < 1° / 1 cm).

use nalgebra::Vector3;
use skytie_stages::estimators::mlesac::{
    axis_angle_deg, fit_plane_mlesac, plane_from_three, PlaneFitParams,
};
use skytie_stages::estimators::{required_iterations, SplitMix64};
use skytie_stages::params::Params;

/// `n_in` points on the plane x = `x0` over 10 × 8 m (y, z) with Gaussian noise `noise_m` along x, then
/// `n_out` uniform outliers in the 20 m cube centred at the origin. Returns the points and the inlier count.
fn plane_x_with_outliers(
    x0: f64,
    n_in: usize,
    noise_m: f64,
    n_out: usize,
    seed: u64,
) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed);
    let mut pts = Vec::with_capacity(n_in + n_out);
    for _ in 0..n_in {
        pts.push([
            x0 + noise_m * rng.next_gaussian(),
            -5.0 + 10.0 * rng.next_f64(),
            -4.0 + 8.0 * rng.next_f64(),
        ]);
    }
    for _ in 0..n_out {
        pts.push([
            -10.0 + 20.0 * rng.next_f64(),
            -10.0 + 20.0 * rng.next_f64(),
            -10.0 + 20.0 * rng.next_f64(),
        ]);
    }
    pts
}

fn normal_error_deg(n: [f64; 3], truth: [f64; 3]) -> f64 {
    axis_angle_deg(&Vector3::from(n), &Vector3::from(truth))
}

/// d of the fitted plane for the true normal's sign (n·p + d = 0 with n ≈ +x ⇒ d ≈ −x0).
fn signed_d(n: [f64; 3], d: f64, truth: [f64; 3]) -> f64 {
    if Vector3::from(n).dot(&Vector3::from(truth)) < 0.0 {
        -d
    } else {
        d
    }
}

#[test]
fn plane_with_30_percent_outliers_is_recovered() {
    // 200 inliers, σ = 5 cm; outliers are 30 % of all points: 86 of 286.
    let pts = plane_x_with_outliers(3.0, 200, 0.05, 86, 11);
    let fit = fit_plane_mlesac(
        &pts,
        &PlaneFitParams {
            seed: 5,
            ..Default::default()
        },
    )
    .unwrap();
    let err = normal_error_deg(fit.normal, [1.0, 0.0, 0.0]);
    assert!(err < 1.0, "normal error {err}°");
    let d = signed_d(fit.normal, fit.d, [1.0, 0.0, 0.0]);
    assert!((d + 3.0).abs() < 0.02, "d {d} (expected −3)");
    let recall = fit.inliers.iter().filter(|&&i| i < 200).count() as f64 / 200.0;
    assert!(recall > 0.95, "inlier recall {recall}");
    // The mixture sees 70 % inliers (plus the few outliers that fall near the plane).
    assert!((fit.gamma - 0.7).abs() < 0.05, "gamma {}", fit.gamma);
    assert!(fit.neg_log_likelihood.is_finite());
    assert!(fit.trials >= 1 && fit.trials <= 10_000);
}

#[test]
fn plane_with_50_percent_outliers_to_one_degree_and_one_centimetre() {
    // 400 inliers with 5 mm noise + 400 outliers in the 20 m cube.
    for seed in 0..5u64 {
        let pts = plane_x_with_outliers(3.0, 400, 0.005, 400, 100 + seed);
        let fit = fit_plane_mlesac(
            &pts,
            &PlaneFitParams {
                seed,
                ..Default::default()
            },
        )
        .unwrap();
        let err = normal_error_deg(fit.normal, [1.0, 0.0, 0.0]);
        let d = signed_d(fit.normal, fit.d, [1.0, 0.0, 0.0]);
        assert!(err < 1.0, "seed {seed}: normal error {err}°");
        assert!((d + 3.0).abs() < 0.01, "seed {seed}: d {d} (expected −3)");
        assert!(
            (0..400).all(|i| fit.inliers.contains(&i)),
            "seed {seed}: an inlier was missed"
        );
    }
}

#[test]
fn trial_count_formula() {
    // w = 0.7, p = 0.99, s = 3 ⇒ ⌈ln 0.01 / ln(1 − 0.343)⌉ = 11.
    assert_eq!(required_iterations(0.99, 0.7, 3), 11);
    // All inliers: one sample is enough.
    assert_eq!(required_iterations(0.99, 1.0, 3), 0);
}

#[test]
fn adaptive_stop_uses_few_trials_on_clean_data() {
    let pts = plane_x_with_outliers(1.0, 300, 0.01, 0, 3);
    let fit = fit_plane_mlesac(&pts, &PlaneFitParams::default()).unwrap();
    assert_eq!(fit.inliers.len(), 300);
    assert!(
        fit.trials < 20,
        "{} trials for outlier-free data",
        fit.trials
    );
}

#[test]
fn collinear_samples_are_rejected() {
    assert!(plane_from_three(&[0.0, 0.0, 0.0], &[1.0, 1.0, 1.0], &[2.0, 2.0, 2.0]).is_none());
    assert!(plane_from_three(&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0], &[0.0, 0.0, 1.0]).is_none());
    let (n, d) = plane_from_three(&[0.0, 0.0, 2.0], &[1.0, 0.0, 2.0], &[0.0, 1.0, 2.0]).unwrap();
    assert!((n.z.abs() - 1.0).abs() < 1e-12 && (d + 2.0 * n.z).abs() < 1e-12);
    // Points all on one line: no plane at all.
    let line: Vec<[f64; 3]> = (0..50).map(|i| [i as f64, 2.0 * i as f64, 0.5]).collect();
    assert!(fit_plane_mlesac(&line, &PlaneFitParams::default()).is_none());
}

#[test]
fn horizontal_ground_plane_fails_the_facade_constraint() {
    // A ground plane z = 0 (normal up) with a façade reference normal along +x.
    let mut rng = SplitMix64::new(9);
    let ground: Vec<[f64; 3]> = (0..200)
        .map(|_| {
            [
                20.0 * rng.next_f64(),
                20.0 * rng.next_f64(),
                0.02 * rng.next_gaussian(),
            ]
        })
        .collect();
    let facade = PlaneFitParams {
        reference_normal: Some([1.0, 0.0, 0.0]),
        ..Default::default()
    };
    assert!(fit_plane_mlesac(&ground, &facade).is_none());
    // Unconstrained, the same points give the ground plane.
    let fit = fit_plane_mlesac(&ground, &PlaneFitParams::default()).unwrap();
    assert!(normal_error_deg(fit.normal, [0.0, 0.0, 1.0]) < 1.0);
}

#[test]
fn angular_constraint_picks_the_facade_among_ground_and_facade() {
    // Ground (z = 0, 300 points, the larger set) and a façade x = 6 (150 points): the constrained fit must
    // return the façade, oriented towards the reference.
    let mut rng = SplitMix64::new(21);
    let mut pts: Vec<[f64; 3]> = (0..300)
        .map(|_| {
            [
                6.0 * rng.next_f64(),
                20.0 * rng.next_f64(),
                0.02 * rng.next_gaussian(),
            ]
        })
        .collect();
    pts.extend((0..150).map(|_| {
        [
            6.0 + 0.02 * rng.next_gaussian(),
            20.0 * rng.next_f64(),
            1.0 + 9.0 * rng.next_f64(),
        ]
    }));
    let p = PlaneFitParams {
        reference_normal: Some([-2.0, 0.0, 0.0]),
        seed: 4,
        ..Default::default()
    };
    let fit = fit_plane_mlesac(&pts, &p).unwrap();
    let err = normal_error_deg(fit.normal, [1.0, 0.0, 0.0]);
    assert!(err < 0.5, "normal off by {err}°");
    assert!(
        fit.normal[0] < 0.0,
        "oriented along the reference: {:?}",
        fit.normal
    );
    assert!((fit.d - 6.0).abs() < 0.02, "d {}", fit.d);
    // A plane 10° off the reference is rejected at 5° and accepted at 15°.
    let tilt = 10f64.to_radians();
    let tilted: Vec<[f64; 3]> = (0..200)
        .map(|_| {
            let (a, b) = (20.0 * rng.next_f64(), 10.0 * rng.next_f64());
            // In-plane axes (−sin t, cos t, 0) and z: normal (cos t, sin t, 0).
            [-a * tilt.sin(), a * tilt.cos(), b]
        })
        .collect();
    let strict = PlaneFitParams {
        reference_normal: Some([1.0, 0.0, 0.0]),
        ..Default::default()
    };
    assert!(fit_plane_mlesac(&tilted, &strict).is_none());
    let loose = PlaneFitParams {
        max_angle_deg: 15.0,
        ..strict
    };
    let fit = fit_plane_mlesac(&tilted, &loose).unwrap();
    assert!(normal_error_deg(fit.normal, [tilt.cos(), tilt.sin(), 0.0]) < 0.01);
}

#[test]
fn deterministic_for_a_seed_and_invalid_params_give_none() {
    let pts = plane_x_with_outliers(2.0, 100, 0.05, 60, 77);
    let p = PlaneFitParams {
        seed: 42,
        ..Default::default()
    };
    assert_eq!(fit_plane_mlesac(&pts, &p), fit_plane_mlesac(&pts, &p));
    let bad = PlaneFitParams {
        sigma_m: -1.0,
        confidence: 1.5,
        ..Default::default()
    };
    let errs = bad.validate().unwrap_err();
    assert!(errs.iter().any(|v| v.field == "sigma_m"));
    assert!(errs.iter().any(|v| v.field == "confidence"));
    assert!(fit_plane_mlesac(&pts, &bad).is_none());
    assert!(fit_plane_mlesac(&pts[..2], &p).is_none());
    let mut nan = pts.clone();
    nan[3][1] = f64::NAN;
    assert!(fit_plane_mlesac(&nan, &p).is_none());
}

//! RANSAC homography (Hartley & Zisserman 2004, ch. 4 KAT): 40 % outliers, noisy inliers, degenerate samples, determinism.

use crate::estimators::{ransac, RansacParams, SplitMix64};
use crate::geometry::{Homography, PointPair};
use nalgebra::{Matrix3, Vector2};

fn truth() -> Homography {
    Homography(Matrix3::new(
        0.98, 0.04, 12.0, -0.03, 1.02, -7.0, 1e-4, -5e-5, 1.0,
    ))
    .normalized()
}

fn contaminated(n_in: usize, n_out: usize, noise: f64, seed: u64) -> Vec<PointPair> {
    let mut rng = SplitMix64::new(seed);
    let h = truth();
    let mut pairs: Vec<PointPair> = (0..n_in)
        .map(|_| {
            let src = Vector2::new(800.0 * rng.next_f64(), 800.0 * rng.next_f64());
            let dst = h.apply(&src).unwrap()
                + Vector2::new(rng.next_gaussian(), rng.next_gaussian()) * noise;
            PointPair { src, dst }
        })
        .collect();
    pairs.extend((0..n_out).map(|_| {
        PointPair::new(
            800.0 * rng.next_f64(),
            800.0 * rng.next_f64(),
            800.0 * rng.next_f64(),
            800.0 * rng.next_f64(),
        )
    }));
    pairs
}

fn max_corner_difference(a: &Homography, b: &Homography) -> f64 {
    [
        (0.0, 0.0),
        (800.0, 0.0),
        (0.0, 800.0),
        (800.0, 800.0),
        (400.0, 400.0),
    ]
    .iter()
    .map(|&(x, y)| {
        let p = Vector2::new(x, y);
        (a.apply(&p).unwrap() - b.apply(&p).unwrap()).norm()
    })
    .fold(0.0, f64::max)
}

#[test]
fn exact_inliers_with_40_percent_outliers() {
    let pairs = contaminated(90, 60, 0.0, 31);
    let params = RansacParams {
        threshold: 1.0,
        confidence: 0.99,
        max_iterations: 2000,
        seed: 5,
    };
    let r = ransac::<Homography>(&pairs, &params).unwrap();
    let (got, want) = (r.model.normalized(), truth().normalized());
    assert!((got.0 - want.0).norm() < 1e-10, "{:?}", got.0);
    assert!((0..90).all(|i| r.inliers.contains(&i)));
    assert!(r
        .inliers
        .iter()
        .all(|&i| truth().transfer_error(&pairs[i]) <= 1.0));
}

#[test]
fn noisy_inliers_match_least_squares_on_true_inliers() {
    let noise = 0.5;
    let pairs = contaminated(150, 100, noise, 32);
    let params = RansacParams {
        threshold: 3.0 * noise * 2f64.sqrt(),
        confidence: 0.995,
        max_iterations: 2000,
        seed: 6,
    };
    let r = ransac::<Homography>(&pairs, &params).unwrap();
    let recall = (0..150).filter(|i| r.inliers.contains(i)).count() as f64 / 150.0;
    assert!(recall > 0.98, "recall {recall}");
    let reference = Homography::from_pairs(&pairs[..150]).unwrap();
    let d = max_corner_difference(&r.model, &reference);
    assert!(
        d < 0.5 * noise,
        "differs from the LS fit on the true inliers by {d} px"
    );
}

#[test]
fn all_collinear_data_give_none() {
    // A road marking: every correspondence on one line; no sample is non-degenerate.
    let h = truth();
    let pairs: Vec<PointPair> = (0..30)
        .map(|i| {
            let s = Vector2::new(10.0 * f64::from(i), 20.0 + 4.0 * f64::from(i));
            PointPair {
                src: s,
                dst: h.apply(&s).unwrap(),
            }
        })
        .collect();
    let params = RansacParams {
        threshold: 1.0,
        confidence: 0.99,
        max_iterations: 200,
        seed: 1,
    };
    assert!(ransac::<Homography>(&pairs, &params).is_none());
}

#[test]
fn deterministic_for_a_seed() {
    let pairs = contaminated(60, 40, 0.3, 33);
    let params = RansacParams {
        threshold: 1.5,
        confidence: 0.99,
        max_iterations: 2000,
        seed: 12345,
    };
    let a = ransac::<Homography>(&pairs, &params).unwrap();
    let b = ransac::<Homography>(&pairs, &params).unwrap();
    assert_eq!(a, b);
}

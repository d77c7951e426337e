//! RANSAC homography (Hartley & Zisserman 2004, ch. 4 KAT): 40 % outliers, noisy inliers, degenerate samples, determinism.

use super::fixtures::{self, ransac_params};
use crate::estimators::ransac;
use crate::geometry::{Homography, PointPair};
use nalgebra::{Matrix3, Vector2};

fn truth() -> Homography {
    Homography(Matrix3::new(
        0.98, 0.04, 12.0, -0.03, 1.02, -7.0, 1e-4, -5e-5, 1.0,
    ))
    .normalized()
}

/// `n_in` correspondences of `truth()` with N(0, noise) in dst, then `n_out` random ones over the image.
fn contaminated(n_in: usize, n_out: usize, noise: f64, seed: u64) -> Vec<PointPair> {
    let h = truth();
    fixtures::contaminated(|p| h.apply(p).unwrap(), 800.0, (n_in, n_out), noise, seed)
}

#[test]
fn exact_inliers_with_40_percent_outliers() {
    let pairs = contaminated(90, 60, 0.0, 31);
    let params = ransac_params(1.0, 0.99, 2000, 5);
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
    let params = ransac_params(3.0 * noise * 2f64.sqrt(), 0.995, 2000, 6);
    let r = ransac::<Homography>(&pairs, &params).unwrap();
    let recall = (0..150).filter(|i| r.inliers.contains(i)).count() as f64 / 150.0;
    assert!(recall > 0.98, "recall {recall}");
    let reference = Homography::from_pairs(&pairs[..150]).unwrap();
    let d = fixtures::max_corner_difference(
        |p| r.model.apply(p).unwrap(),
        |p| reference.apply(p).unwrap(),
        800.0,
    );
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
    let params = ransac_params(1.0, 0.99, 200, 1);
    assert!(ransac::<Homography>(&pairs, &params).is_none());
}

#[test]
fn deterministic_for_a_seed() {
    let pairs = contaminated(60, 40, 0.3, 33);
    let params = ransac_params(1.5, 0.99, 2000, 12345);
    let a = ransac::<Homography>(&pairs, &params).unwrap();
    let b = ransac::<Homography>(&pairs, &params).unwrap();
    assert_eq!(a, b);
}

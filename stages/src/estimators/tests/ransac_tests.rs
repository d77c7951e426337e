//! Generic RANSAC behaviour: trial counts, parameter validation, a 1-D model with a known answer.

use super::fixtures::ransac_params;
use crate::estimators::{ransac, required_iterations, Model, RansacParams};
use crate::params::Params;

#[test]
fn trial_counts_match_the_formula() {
    // Hartley & Zisserman 2004, ch. 4: p = 0.99, w = 0.5 → 17 (s = 2) and 72 (s = 4).
    assert_eq!(required_iterations(0.99, 0.5, 2), 17);
    assert_eq!(required_iterations(0.99, 0.5, 4), 72);
    assert_eq!(required_iterations(0.99, 1.0, 4), 0);
    assert_eq!(required_iterations(0.99, 0.0, 2), usize::MAX);
}

/// A constant (1-D location) model: fitted as the mean, residual |x − c|.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Constant(f64);

impl Model for Constant {
    const MIN_SAMPLES: usize = 1;
    type Datum = f64;
    fn fit(data: &[&f64]) -> Option<Self> {
        (!data.is_empty()).then(|| Constant(data.iter().copied().sum::<f64>() / data.len() as f64))
    }
    fn residual(&self, d: &f64) -> f64 {
        (d - self.0).abs()
    }
}

#[test]
fn finds_the_majority_cluster_and_refits() {
    // 60 inliers at 10 ± 0.1 and 40 outliers spread over [100, 500).
    let mut data: Vec<f64> = (0..60)
        .map(|i| 10.0 + 0.1 * ((f64::from(i) * 0.37).fract() * 2.0 - 1.0))
        .collect();
    data.extend((0..40).map(|i| 100.0 + 10.0 * f64::from(i)));
    let params = ransac_params(0.25, 0.999, 500, 3);
    let result = ransac::<Constant>(&data, &params).unwrap();
    assert_eq!(result.inliers, (0..60).collect::<Vec<_>>());
    let mean = data[..60].iter().sum::<f64>() / 60.0;
    assert!(
        (result.model.0 - mean).abs() < 1e-12,
        "refit must be the LS fit on the inliers"
    );
    assert!(result.iterations >= 1 && result.iterations <= 500);
}

#[test]
fn invalid_parameters_or_too_few_data_give_none() {
    let data = [1.0, 2.0, 3.0];
    let good = RansacParams::new(0.5, 1);
    assert!(ransac::<Constant>(&data, &good).is_some());
    assert!(ransac::<Constant>(&[], &good).is_none());
    for bad in [
        RansacParams {
            threshold: 0.0,
            ..good
        },
        RansacParams {
            threshold: f64::NAN,
            ..good
        },
        RansacParams {
            confidence: 1.0,
            ..good
        },
        RansacParams {
            max_iterations: 0,
            ..good
        },
    ] {
        assert!(bad.validate().is_err());
        assert!(ransac::<Constant>(&data, &bad).is_none());
    }
}

#[test]
fn max_iterations_caps_the_trials() {
    // Only outliers (every pair is far apart): no consensus above 1, so the trial count stays at the cap.
    let data: Vec<f64> = (0..50).map(|i| f64::from(i) * 100.0).collect();
    let params = ransac_params(1.0, 0.99, 37, 1);
    let result = ransac::<Constant>(&data, &params).unwrap();
    assert_eq!(result.iterations, 37);
    assert_eq!(result.inliers.len(), 1);
}

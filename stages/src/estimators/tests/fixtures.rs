//! Data of the RANSAC known-answer tests: correspondences of a known 2-D transformation contaminated by
//! outliers, parameters, and the largest disagreement of two transformations over an image.

use crate::estimators::{RansacParams, SplitMix64};
use crate::geometry::PointPair;
use nalgebra::Vector2;

/// `n_in` correspondences of `map` (sources uniform over a `side_px` square, N(0, noise) added to the
/// destinations), then `n_out` random pairs over the same square.
pub fn contaminated(
    map: impl Fn(&Vector2<f64>) -> Vector2<f64>,
    side_px: f64,
    (n_in, n_out): (usize, usize),
    noise: f64,
    seed: u64,
) -> Vec<PointPair> {
    let mut rng = SplitMix64::new(seed);
    let mut pairs: Vec<PointPair> = (0..n_in)
        .map(|_| {
            let src = Vector2::new(side_px * rng.next_f64(), side_px * rng.next_f64());
            let dst = map(&src) + Vector2::new(rng.next_gaussian(), rng.next_gaussian()) * noise;
            PointPair { src, dst }
        })
        .collect();
    pairs.extend((0..n_out).map(|_| {
        let mut draw = || side_px * rng.next_f64();
        PointPair::new(draw(), draw(), draw(), draw())
    }));
    pairs
}

/// RANSAC parameters.
pub fn ransac_params(
    threshold: f64,
    confidence: f64,
    max_iterations: usize,
    seed: u64,
) -> RansacParams {
    RansacParams {
        threshold,
        confidence,
        max_iterations,
        seed,
    }
}

/// The largest distance between where `a` and `b` put the corners and the centre of a `side_px` square.
pub fn max_corner_difference(
    a: impl Fn(&Vector2<f64>) -> Vector2<f64>,
    b: impl Fn(&Vector2<f64>) -> Vector2<f64>,
    side_px: f64,
) -> f64 {
    let (s, h) = (side_px, side_px / 2.0);
    [(0.0, 0.0), (s, 0.0), (0.0, s), (s, s), (h, h)]
        .iter()
        .map(|&(x, y)| {
            let p = Vector2::new(x, y);
            (a(&p) - b(&p)).norm()
        })
        .fold(0.0, f64::max)
}

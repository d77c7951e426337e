//! Known-answer tests of the geometry core (campaign-format.md conventions, Hartley & Zisserman 2004).

mod closest_approach_tests;
mod frame_tests;
mod homography_tests;
mod local_frame_tests;
mod panorama_tests;
mod ray_tests;
mod rotation_tests;
mod similarity_tests;
mod triangulation_tests;

use crate::geometry::PointPair;
use crate::rng::SplitMix64;
use nalgebra::Vector2;

/// `n` pairs of `map` drawn with `seed`: sources uniform over `offset` + [0, `size.0`] × [0, `size.1`],
/// destinations `map(src)`, plus N(0, σ) per coordinate when `noise` is `Some(σ)` (drawn after each source).
fn pairs_of(
    map: impl Fn(&Vector2<f64>) -> Vector2<f64>,
    n: usize,
    seed: u64,
    (offset, size): (f64, (f64, f64)),
    noise: Option<f64>,
) -> Vec<PointPair> {
    let mut rng = SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            let src = Vector2::new(
                offset + size.0 * rng.next_f64(),
                offset + size.1 * rng.next_f64(),
            );
            let mut dst = map(&src);
            if let Some(sigma) = noise {
                dst += Vector2::new(rng.next_gaussian(), rng.next_gaussian()) * sigma;
            }
            PointPair { src, dst }
        })
        .collect()
}

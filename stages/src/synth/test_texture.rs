//! Band-limited noise images: the test texture of the peer benchmarks (`stages/benches/`) and the tool tests
//! (`tests/support/tool_cli.rs`) — known content with texture at every scale above the blur, for detectors,
//! matchers and samplers. Not part of the synthetic campaign's scene.

use crate::imaging::{gaussian_blur, GrayImage};
use crate::rng::SplitMix64;

/// `width × height` uniform noise (24-bit values from the SplitMix64 stream of `seed`) blurred with a Gaussian of
/// σ = `sigma_px` and stretched to [0, 1] (min → 0, max → 1). Deterministic for a given seed.
pub fn band_limited_noise(width: usize, height: usize, sigma_px: f32, seed: u64) -> GrayImage {
    let mut rng = SplitMix64::new(seed);
    let noise = (0..width * height)
        .map(|_| (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32)
        .collect();
    let mut img = gaussian_blur(
        &GrayImage::from_vec(width, height, noise).expect("width × height values"),
        sigma_px,
    );
    let (lo, hi) = img
        .data
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    let range = if hi > lo { hi - lo } else { 1.0 };
    img.data.iter_mut().for_each(|v| *v = (*v - lo) / range);
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_zero_to_one_is_smooth_and_repeats_per_seed() {
        let a = band_limited_noise(64, 48, 2.0, 7);
        assert_eq!((a.width, a.height), (64, 48));
        let (lo, hi) = a
            .data
            .iter()
            .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
        assert_eq!((lo, hi), (0.0, 1.0));
        // Blurred: neighbours differ far less than the full range.
        let steps: f32 =
            a.data.windows(2).map(|p| (p[1] - p[0]).abs()).sum::<f32>() / a.data.len() as f32;
        assert!(steps < 0.1, "mean step {steps}");
        assert_eq!(a, band_limited_noise(64, 48, 2.0, 7));
        assert_ne!(a, band_limited_noise(64, 48, 2.0, 8));
    }
}

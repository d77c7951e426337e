//! Separable Gaussian blur (kernel radius ⌈3σ⌉, sampled and normalised to unit sum, reflective border).

use super::convolve::convolve_separable;
use super::image::GrayImage;

/// Kernel radius used for `sigma_px`: ⌈3σ⌉ (at least 1 for σ > 0).
pub fn gaussian_radius(sigma_px: f32) -> usize {
    if !(sigma_px.is_finite() && sigma_px > 0.0) {
        return 0;
    }
    ((3.0 * sigma_px).ceil() as usize).max(1)
}

/// Sampled 1-D Gaussian, length `2·radius + 1`, sums to 1. A non-positive or non-finite σ gives `[1.0]`.
pub fn gaussian_kernel(sigma_px: f32) -> Vec<f32> {
    let r = gaussian_radius(sigma_px);
    if r == 0 {
        return vec![1.0];
    }
    let s2 = 2.0 * (sigma_px as f64) * (sigma_px as f64);
    let raw: Vec<f64> = (0..=2 * r)
        .map(|i| (-((i as f64 - r as f64).powi(2)) / s2).exp())
        .collect();
    let sum: f64 = raw.iter().sum();
    raw.iter().map(|&v| (v / sum) as f32).collect()
}

/// Gaussian blur with standard deviation `sigma_px` (pixels); σ ≤ 0 returns a copy.
pub fn gaussian_blur(img: &GrayImage, sigma_px: f32) -> GrayImage {
    let k = gaussian_kernel(sigma_px);
    convolve_separable(img, &k, &k)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_is_normalised_symmetric_with_3_sigma_radius() {
        let k = gaussian_kernel(2.0);
        assert_eq!(k.len(), 13);
        assert!((k.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        for i in 0..6 {
            assert_eq!(k[i], k[12 - i]);
        }
        // Second moment ≈ σ² (truncation at 3σ loses ~1 %).
        let var: f32 = k
            .iter()
            .enumerate()
            .map(|(i, &v)| v * (i as f32 - 6.0).powi(2))
            .sum();
        assert!((var - 4.0).abs() < 0.12, "{var}");
        assert_eq!(gaussian_kernel(0.0), vec![1.0]);
        assert_eq!(gaussian_kernel(f32::NAN), vec![1.0]);
    }

    #[test]
    fn constant_stays_constant_and_impulse_spreads_with_sigma() {
        let c = gaussian_blur(&GrayImage::filled(20, 15, 0.7), 1.5);
        assert!(c.data.iter().all(|&v| (v - 0.7).abs() < 1e-6));
        let n = 41;
        let mut img = GrayImage::filled(n, n, 0.0);
        img.set(20, 20, 1.0);
        let b = gaussian_blur(&img, 2.5);
        let total: f32 = b.data.iter().sum();
        assert!((total - 1.0).abs() < 1e-5);
        let var_x: f32 = (0..n * n)
            .map(|k| b.data[k] * ((k % n) as f32 - 20.0).powi(2))
            .sum();
        assert!((var_x - 6.25).abs() < 0.15, "{var_x}");
    }
}

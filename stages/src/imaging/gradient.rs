//! Image derivatives: central differences, Scharr (optionally with a wider tap spacing, as KAZE uses),
//! and derivative-of-Gaussian. All are normalised to unit gain: on the ramp `I = a·u + b·v` they return
//! `dx = a`, `dy = b` (intensity per pixel; +x along u to the right, +y along v downwards).
//! Borders are reflective, so the derivative across the image edge is attenuated (mirror symmetry).

use super::convolve::convolve_separable;
use super::gaussian::{gaussian_kernel, gaussian_radius};
use super::image::GrayImage;

/// The two first derivatives of an image, `dx = ∂I/∂u`, `dy = ∂I/∂v` (per pixel).
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    pub dx: GrayImage,
    pub dy: GrayImage,
}

impl Gradient {
    fn from_kernels(img: &GrayImage, deriv: &[f32], smooth: &[f32]) -> Self {
        Self {
            dx: convolve_separable(img, deriv, smooth),
            dy: convolve_separable(img, smooth, deriv),
        }
    }
}

/// Central differences `(I[x+1] − I[x−1]) / 2` along each axis, no cross smoothing.
pub fn central_gradient(img: &GrayImage) -> Gradient {
    Gradient::from_kernels(img, &[-0.5, 0.0, 0.5], &[1.0])
}

/// 3×3 Scharr derivative, normalised: derivative `[−1, 0, 1]/2` × smoothing `[3, 10, 3]/16`.
pub fn scharr_gradient(img: &GrayImage) -> Gradient {
    scharr_gradient_step(img, 1)
}

/// Scharr derivative with taps spaced `step_px` apart (KAZE's scale-dependent derivative, Alcantarilla, Bartoli & Davison 2012):
/// derivative `[−1, 0…0, +1] / (2·step)` × smoothing `[3, 0…0, 10, 0…0, 3] / 16`. Unit gain per pixel; OpenCV's
/// `compute_derivative_kernels` for scale s equals `s` times this. `step_px = 0` is treated as 1.
pub fn scharr_gradient_step(img: &GrayImage, step_px: usize) -> Gradient {
    let s = step_px.max(1);
    let (deriv, smooth) = scharr_kernels(s);
    Gradient::from_kernels(img, &deriv, &smooth)
}

/// (derivative, smoothing) kernels of [`scharr_gradient_step`], each of length `2·step + 1`.
pub fn scharr_kernels(step_px: usize) -> (Vec<f32>, Vec<f32>) {
    let s = step_px.max(1);
    let n = 2 * s + 1;
    let mut deriv = vec![0.0f32; n];
    let mut smooth = vec![0.0f32; n];
    deriv[0] = -1.0 / (2 * s) as f32;
    deriv[n - 1] = 1.0 / (2 * s) as f32;
    smooth[0] = 3.0 / 16.0;
    smooth[s] = 10.0 / 16.0;
    smooth[n - 1] = 3.0 / 16.0;
    (deriv, smooth)
}

/// First-derivative-of-Gaussian kernel (correlation form, radius ⌈3σ⌉): `k[j] ∝ j·exp(−j²/2σ²)`, scaled so that
/// `Σ j·k[j] = 1` (unit gain on a ramp). σ ≤ 0 or non-finite falls back to central differences.
pub fn gaussian_derivative_kernel(sigma_px: f32) -> Vec<f32> {
    let r = gaussian_radius(sigma_px);
    if r == 0 {
        return vec![-0.5, 0.0, 0.5];
    }
    let s2 = 2.0 * (sigma_px as f64).powi(2);
    let raw: Vec<f64> = (0..=2 * r)
        .map(|i| {
            let j = i as f64 - r as f64;
            j * (-(j * j) / s2).exp()
        })
        .collect();
    let moment: f64 = raw
        .iter()
        .enumerate()
        .map(|(i, &v)| v * (i as f64 - r as f64))
        .sum();
    raw.iter().map(|&v| (v / moment) as f32).collect()
}

/// Derivative-of-Gaussian gradient at scale `sigma_px` (the Gaussian-smoothed image's gradient).
pub fn gaussian_gradient(img: &GrayImage, sigma_px: f32) -> Gradient {
    let deriv = gaussian_derivative_kernel(sigma_px);
    let smooth = if gaussian_radius(sigma_px) == 0 {
        vec![1.0]
    } else {
        gaussian_kernel(sigma_px)
    };
    Gradient::from_kernels(img, &deriv, &smooth)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(w: usize, h: usize, a: f32, b: f32) -> GrayImage {
        let data = (0..w * h)
            .map(|k| a * (k % w) as f32 + b * (k / w) as f32)
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }

    fn check_interior(g: &Gradient, a: f32, b: f32, margin: usize) {
        let (w, h) = (g.dx.width, g.dx.height);
        for row in margin..h - margin {
            for col in margin..w - margin {
                assert!((g.dx.get(col, row) - a).abs() < 1e-4, "dx at {col},{row}");
                assert!((g.dy.get(col, row) - b).abs() < 1e-4, "dy at {col},{row}");
            }
        }
    }

    #[test]
    fn unit_gain_on_ramps() {
        let img = ramp(30, 25, 0.3, -0.7);
        check_interior(&central_gradient(&img), 0.3, -0.7, 1);
        check_interior(&scharr_gradient(&img), 0.3, -0.7, 1);
        check_interior(&scharr_gradient_step(&img, 3), 0.3, -0.7, 3);
        check_interior(&gaussian_gradient(&img, 1.2), 0.3, -0.7, 4);
    }

    #[test]
    fn derivative_of_gaussian_matches_analytic_on_a_sinusoid() {
        // I = sin(ω x); DoG(σ) gives ω·cos(ω x)·exp(−ω²σ²/2) (truncation/sampling error small).
        let (w, omega, sigma) = (64usize, 0.3f64, 1.0f32);
        let data = (0..w * 8)
            .map(|k| ((k % w) as f64 * omega).sin() as f32)
            .collect();
        let img = GrayImage::from_vec(w, 8, data).unwrap();
        let g = gaussian_gradient(&img, sigma);
        let atten = (-(omega * sigma as f64).powi(2) / 2.0).exp();
        for col in 10..50 {
            let truth = omega * (col as f64 * omega).cos() * atten;
            assert!((g.dx.get(col, 4) as f64 - truth).abs() < 2e-3, "{col}");
            assert!(g.dy.get(col, 4).abs() < 1e-5);
        }
    }
}

//! The KAZE nonlinear scale space (ALGORITHMS.md §1, thesis 3.4.4.2 / 3.4.5.2): N = O·S full-resolution
//! levels at σ_i = σ0·2^(o + s/S), evolution time t_i = σ_i²/2, each level diffused from the previous one
//! with the conductance of the previous one (FED or AOS), plus the scale-normalised derivatives and the
//! det(Hessian) response the detector, orientation and descriptor need.
//!
//! As in OpenCV, the derivatives of level i are taken on Lσ = G(derivative σ) * L^(i−1) (level 0: on
//! G * L^0), with the Scharr-type kernel of tap spacing s_i = round(σ_i), unit gain, then scale-normalised:
//! Lx·s, Ly·s, Lxx·s², Lyy·s², Lxy·s². Gaussian blurs use `imaging::gaussian` (radius ⌈3σ⌉, reflective
//! border), not OpenCV's kernel-size rule, so values differ slightly from OpenCV near the kernel tails.

use super::contrast::contrast_factor;
use super::diffusion::{aos_step, conductance, fed_diffuse};
use super::params::{KazeParams, Scheme};
use crate::imaging::convolve::convolve_separable;
use crate::imaging::gaussian::gaussian_blur;
use crate::imaging::gradient::scharr_kernels;
use crate::imaging::GrayImage;

/// One evolution level with what later stages need.
#[derive(Clone, Debug)]
pub struct Level {
    /// Octave o and sub-level s (i = o·S + s).
    pub octave: usize,
    pub sublevel: usize,
    /// σ_i in pixels.
    pub sigma_px: f32,
    /// Integer derivative / sampling step round(σ_i) (≥ 1).
    pub step_px: usize,
    /// Scale-normalised first derivatives Lx·s, Ly·s (per pixel, +x right, +y down).
    pub lx: GrayImage,
    pub ly: GrayImage,
    /// Scale-normalised det(Hessian): (Lxx·Lyy − Lxy²)·s⁴.
    pub det: GrayImage,
}

/// The whole scale space and the contrast factor used to build it.
#[derive(Clone, Debug)]
pub struct ScaleSpace {
    pub levels: Vec<Level>,
    pub contrast_k: f32,
}

/// Build the scale space of `img` (grey, 0..1). An empty image or zero levels gives no levels.
pub fn build_scale_space(img: &GrayImage, p: &KazeParams) -> ScaleSpace {
    let n = p.levels();
    let base = gaussian_blur(img, p.sigma0);
    let contrast_k = contrast_factor(&base, p.derivative_sigma, p.k_percentile);
    let mut levels = Vec::with_capacity(n);
    if img.width == 0 || img.height == 0 {
        return ScaleSpace { levels, contrast_k };
    }
    let mut current = base;
    let mut prev_time = 0.5 * p.sigma0 * p.sigma0;
    for i in 0..n {
        let (octave, sublevel) = (i / p.sublevels, i % p.sublevels);
        let sigma_px = p.sigma_of(octave, sublevel as f32);
        let time = 0.5 * sigma_px * sigma_px;
        // Lσ of the previous level (level 0: of L0): feeds the conductance and the derivatives.
        let smoothed = gaussian_blur(&current, p.derivative_sigma);
        if i > 0 {
            let g = conductance(&smoothed, contrast_k, p.diffusivity);
            let dt = time - prev_time;
            current = match p.scheme {
                Scheme::Fed => fed_diffuse(&current, &g, dt),
                Scheme::Aos => aos_step(&current, &g, dt),
            };
        }
        prev_time = time;
        let step_px = (sigma_px.round() as usize).max(1);
        levels.push(derivatives(&smoothed, octave, sublevel, sigma_px, step_px));
    }
    ScaleSpace { levels, contrast_k }
}

fn derivatives(
    smoothed: &GrayImage,
    octave: usize,
    sublevel: usize,
    sigma_px: f32,
    step_px: usize,
) -> Level {
    let (deriv, smooth) = scharr_kernels(step_px);
    let lx = convolve_separable(smoothed, &deriv, &smooth);
    let ly = convolve_separable(smoothed, &smooth, &deriv);
    let lxx = convolve_separable(&lx, &deriv, &smooth);
    let lxy = convolve_separable(&lx, &smooth, &deriv);
    let lyy = convolve_separable(&ly, &smooth, &deriv);
    let s = step_px as f32;
    let s4 = s * s * s * s;
    let det_data = lxx
        .data
        .iter()
        .zip(&lyy.data)
        .zip(&lxy.data)
        .map(|((&xx, &yy), &xy)| (xx * yy - xy * xy) * s4)
        .collect();
    let scale = |mut img: GrayImage| {
        img.data.iter_mut().for_each(|v| *v *= s);
        img
    };
    Level {
        octave,
        sublevel,
        sigma_px,
        step_px,
        det: GrayImage {
            width: smoothed.width,
            height: smoothed.height,
            data: det_data,
        },
        lx: scale(lx),
        ly: scale(ly),
    }
}

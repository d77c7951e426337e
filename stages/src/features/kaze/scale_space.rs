//! The KAZE nonlinear scale space (Alcantarilla, Bartoli & Davison 2012, thesis 3.4.4.2 / 3.4.5.2): N = O·S full-resolution
//! levels at σ_i = σ0·2^(o + s/S), evolution time t_i = σ_i²/2, each level diffused from the previous one
//! with the conductance of the previous one (FED or AOS), plus the scale-normalised derivatives and the
//! det(Hessian) response the detector, orientation and descriptor need.
//!
//! As in OpenCV, the derivatives of level i are taken on Lσ = G(derivative σ) * L^(i−1) (level 0: on
//! G * L^0), with the Scharr-type kernel of tap spacing s_i = round(σ_i), unit gain, then scale-normalised:
//! Lx·s, Ly·s, Lxx·s², Lyy·s², Lxy·s². Gaussian blurs use `imaging::gaussian` (radius ⌈3σ⌉, reflective
//! border), not OpenCV's kernel-size rule, so values differ slightly from OpenCV near the kernel tails.

use super::contrast::contrast_factor_from_gradient;
use super::diffusion::{aos_step, conductance_from_gradient, fed_diffuse};
use super::filters::{level_derivatives, scharr_gradient, Scratch};
use super::params::{KazeParams, Scheme};
use crate::imaging::gaussian::gaussian_blur;
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
///
/// Lσ = G(derivative σ) * L of each diffused level is computed once: for L0 it serves the contrast factor,
/// level 0's and level 1's derivatives and level 1's conductance (with the same Scharr gradient); level 1
/// reuses level 0's derivative images when both have the same tap spacing (identical inputs).
pub fn build_scale_space(img: &GrayImage, p: &KazeParams) -> ScaleSpace {
    let n = p.levels();
    let base = gaussian_blur(img, p.sigma0);
    let mut scratch = Scratch::default();
    // Lσ of the current level and its Scharr gradient (for the contrast factor and the next conductance).
    let mut smoothed = gaussian_blur(&base, p.derivative_sigma);
    let mut gradient = scharr_gradient(&smoothed, &mut scratch);
    let contrast_k = contrast_factor_from_gradient(&gradient, p.k_percentile);
    let mut levels: Vec<Level> = Vec::with_capacity(n);
    if img.width == 0 || img.height == 0 {
        return ScaleSpace { levels, contrast_k };
    }
    let mut current = base;
    let mut prev_time = 0.5 * p.sigma0 * p.sigma0;
    // Whether `smoothed` is the one the previous level's derivatives were computed from.
    let mut smoothed_reused = false;
    for i in 0..n {
        let (octave, sublevel) = (i / p.sublevels, i % p.sublevels);
        let sigma_px = p.sigma_of(octave, sublevel as f32);
        let time = 0.5 * sigma_px * sigma_px;
        // `smoothed` = Lσ of the previous level (level 0: of L0): feeds the conductance and the derivatives.
        if i > 0 {
            let g = conductance_from_gradient(&gradient, contrast_k, p.diffusivity);
            let dt = time - prev_time;
            current = match p.scheme {
                Scheme::Fed => fed_diffuse(&current, &g, dt),
                Scheme::Aos => aos_step(&current, &g, dt),
            };
        }
        prev_time = time;
        let step_px = (sigma_px.round() as usize).max(1);
        let (lx, ly, det) = match levels.last() {
            Some(prev) if smoothed_reused && prev.step_px == step_px => {
                (prev.lx.clone(), prev.ly.clone(), prev.det.clone())
            }
            _ => level_derivatives(&smoothed, step_px, &mut scratch),
        };
        levels.push(Level {
            octave,
            sublevel,
            sigma_px,
            step_px,
            lx,
            ly,
            det,
        });
        // Level i + 1 uses Lσ of level i; level 0 is not diffused, so level 1 uses the same Lσ as level 0.
        smoothed_reused = i == 0;
        if i > 0 && i + 1 < n {
            smoothed = gaussian_blur(&current, p.derivative_sigma);
            gradient = scharr_gradient(&smoothed, &mut scratch);
        }
    }
    ScaleSpace { levels, contrast_k }
}

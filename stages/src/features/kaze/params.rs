//! KAZE parameters (Alcantarilla, Bartoli & Davison 2012 table; defaults = OpenCV `KAZE::create`, thesis 3.4.5.2 overrides
//! upright / extended / one octave per stage).

use serde::{Deserialize, Serialize};

/// Conductance function g(|∇Lσ|²/k²) of the nonlinear diffusion (Alcantarilla, Bartoli & Davison 2012).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Diffusivity {
    /// Perona–Malik 1 ("sharpedge"): g = exp(−m).
    PmG1,
    /// Perona–Malik 2 ("region", default): g = 1 / (1 + m).
    PmG2,
    /// Weickert ("edge"): g = 1 − exp(−3.315 / m⁴), g = 1 for m = 0.
    Weickert,
    /// Charbonnier: g = 1 / sqrt(1 + m).
    Charbonnier,
}

/// Numerical scheme of the diffusion step between two evolution times.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Scheme {
    /// Fast Explicit Diffusion: one FED cycle per level (OpenCV / KAZE ≥ 1.6 default).
    Fed,
    /// Additive Operator Splitting (semi-implicit, the KAZE paper's scheme).
    Aos,
}

/// All KAZE settings. `threshold` is absolute on the scale-normalised det(Hessian) of a 0..1 image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct KazeParams {
    /// Detector threshold on det(Hessian) (OpenCV 0.001).
    pub threshold: f32,
    /// Number of octaves O (thesis: 1).
    pub octaves: usize,
    /// Sub-levels per octave S.
    pub sublevels: usize,
    pub diffusivity: Diffusivity,
    pub scheme: Scheme,
    /// No orientation: descriptors in the image frame (thesis: true).
    pub upright: bool,
    /// 128-value descriptor instead of 64 (thesis: true for MM↔aerial).
    pub extended: bool,
    /// Base scale σ0 (px) of the pre-smoothing and the scale space.
    pub sigma0: f32,
    /// σ (px) of the Gaussian applied before gradients for conductance and detector derivatives.
    pub derivative_sigma: f32,
    /// Percentile of the gradient-magnitude histogram giving the contrast factor k.
    pub k_percentile: f32,
}

impl Default for KazeParams {
    fn default() -> Self {
        Self {
            threshold: 0.001,
            octaves: 4,
            sublevels: 4,
            diffusivity: Diffusivity::PmG2,
            scheme: Scheme::Fed,
            upright: false,
            extended: false,
            sigma0: 1.6,
            derivative_sigma: 1.0,
            k_percentile: 0.7,
        }
    }
}

impl KazeParams {
    /// Number of evolution levels N = O·S.
    pub fn levels(&self) -> usize {
        self.octaves * self.sublevels
    }

    /// σ_i = σ0 · 2^(o + s/S) for level i = o·S + s (fractional `sublevel` allowed for refined scales).
    pub fn sigma_of(&self, octave: usize, sublevel: f32) -> f32 {
        let s = self.sublevels.max(1) as f32;
        self.sigma0 * (octave as f32 + sublevel / s).exp2()
    }

    /// Descriptor length (64 or 128).
    pub fn descriptor_len(&self) -> usize {
        if self.extended {
            128
        } else {
            64
        }
    }
}

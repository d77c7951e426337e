//! Contrast factor k of the conductance (Alcantarilla, Bartoli & Davison 2012, KAZE paper §4.1): the `percentile` point of the
//! gradient-magnitude histogram of the Gaussian-smoothed base level.

use crate::imaging::gaussian::gaussian_blur;
use crate::imaging::gradient::{scharr_gradient, Gradient};
use crate::imaging::GrayImage;

/// Histogram bins of the magnitude histogram (OpenCV `KCONTRAST_NBINS`).
pub const CONTRAST_BINS: usize = 300;
/// k used when the histogram walk fails (flat image).
pub const FALLBACK_CONTRAST: f32 = 0.03;

/// k from `base` (L0): |∇(G(derivative_sigma) * L0)| with the unit-gain Scharr operator over interior pixels
/// (1-px border skipped), zero magnitudes excluded, [`CONTRAST_BINS`] bins on [0, max]; walk bins until the count
/// reaches floor(percentile · count); with j bins consumed, k = max · j / bins.
///
/// The gradient gain does not matter as long as the conductance uses the same operator (it does: unit-gain
/// Scharr in [`super::diffusion::conductance`]); OpenCV's raw Scharr differs by a factor 32 in both places.
pub fn contrast_factor(base: &GrayImage, derivative_sigma: f32, percentile: f32) -> f32 {
    let (w, h) = (base.width, base.height);
    if w < 3 || h < 3 {
        return FALLBACK_CONTRAST;
    }
    let smoothed = gaussian_blur(base, derivative_sigma);
    contrast_factor_from_gradient(&scharr_gradient(&smoothed), percentile)
}

/// [`contrast_factor`] from the unit-gain Scharr gradient `g` of G(derivative_sigma) * L0 (the scale space
/// computes that gradient once for the contrast factor and the first conductance).
pub fn contrast_factor_from_gradient(g: &Gradient, percentile: f32) -> f32 {
    let (w, h) = (g.dx.width, g.dx.height);
    if w < 3 || h < 3 {
        return FALLBACK_CONTRAST;
    }
    let magnitude = |col: usize, row: usize| {
        let i = row * w + col;
        (g.dx.data[i] * g.dx.data[i] + g.dy.data[i] * g.dy.data[i]).sqrt()
    };
    let mut max_mag = 0.0f32;
    for row in 1..h - 1 {
        for col in 1..w - 1 {
            max_mag = max_mag.max(magnitude(col, row));
        }
    }
    if !(max_mag > 0.0 && max_mag.is_finite()) {
        return FALLBACK_CONTRAST;
    }
    let mut hist = [0usize; CONTRAST_BINS];
    let mut count = 0usize;
    for row in 1..h - 1 {
        for col in 1..w - 1 {
            let m = magnitude(col, row);
            if m > 0.0 {
                let bin = ((m / max_mag) * CONTRAST_BINS as f32) as usize;
                hist[bin.min(CONTRAST_BINS - 1)] += 1;
                count += 1;
            }
        }
    }
    let target = (percentile.clamp(0.0, 1.0) as f64 * count as f64).floor() as usize;
    let mut sum = 0usize;
    let mut bins_used = 0usize;
    while sum < target && bins_used < CONTRAST_BINS {
        sum += hist[bins_used];
        bins_used += 1;
    }
    if sum < target || bins_used == 0 {
        return FALLBACK_CONTRAST;
    }
    max_mag * bins_used as f32 / CONTRAST_BINS as f32
}

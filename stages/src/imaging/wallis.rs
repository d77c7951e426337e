//! Wallis filter: local radiometric normalisation to a target mean and standard deviation (thesis 3.4.5.2,
//! Wallis 1976; Baltsavias 1991; Wallis 1976 in the photogrammetric form of Baltsavias 1991).
//!
//! Parameterisation implemented (and no other): with local mean m_g and std s_g over a W × W window,
//! `g_w = r1·(g − m_g) + b·m_f + (1 − b)·m_g`, `r1 = c·s_f / (c·s_g + (1 − c)·s_f)`, which is the same as
//! `g·r1 + r0`, `r0 = b·m_f + (1 − b − r1)·m_g`, and as the "maximum gain" form with `A = c/(1 − c)`.
//! Local statistics come from f64 integral images (values shifted by the global mean against cancellation),
//! borders are reflected. Output is not clipped.

use rayon::prelude::*;
use thiserror::Error;

use super::border::reflect_index;
use super::image::GrayImage;
use crate::params::{describe, Params};

crate::params! {
    /// Wallis parameters; intensities in the image's own units (0..1 for loaded 8-bit images). Defaults: 127/40
    /// of 255, c = 0.94, b = 1, 21 px window, scaled to 0..1 intensities.
    #[derive(Copy)]
    pub struct WallisParams {
        /// Target mean m_f.
        target_mean: f32 = 127.0 / 255.0;
        /// Target standard deviation s_f.
        target_std: f32 = 40.0 / 255.0, above 0.0;
        /// Contrast expansion constant c (1 forces the target std; maximum gain c/(1 − c)).
        contrast_c: f32 = 0.94, min 0.0, max 1.0;
        /// Brightness forcing constant b (1 forces the target mean, 0 keeps the local mean).
        brightness_b: f32 = 1.0, min 0.0, max 1.0;
        /// Side of the square statistics window; odd (an even value is rounded up to the next odd one).
        window_px: usize = 21, unit "px", min 1;
    }
    check(p, v) {
        crate::params::check_finite("target_mean", &p.target_mean, v);
    }
}

impl WallisParams {
    /// Parameters in the "maximum gain" form: `A = c/(1 − c)` ⇔ `c = A/(1 + A)` (A ≥ 0; A = ∞ gives c = 1).
    pub fn with_max_gain(mut self, max_gain_a: f32) -> Self {
        self.contrast_c = if max_gain_a.is_infinite() {
            1.0
        } else {
            max_gain_a / (1.0 + max_gain_a)
        };
        self
    }

    /// The range checks of [`Params::validate`] as a [`WallisError`].
    fn checked(&self) -> Result<(), WallisError> {
        self.validate().map_err(|v| WallisError::InvalidParameters {
            problems: describe(&v),
        })
    }
}

#[derive(Debug, Error, PartialEq)]
pub enum WallisError {
    #[error("invalid Wallis parameters: {problems}")]
    InvalidParameters { problems: String },
    #[error("Wallis statistics images are {got_w}×{got_h} but the image is {want_w}×{want_h}")]
    SizeMismatch {
        got_w: usize,
        got_h: usize,
        want_w: usize,
        want_h: usize,
    },
}

/// Gain r1 and offset r0 of `g_w = g·r1 + r0` for local statistics (m_g, s_g). A flat window with c = 1
/// (s_g = 0, nothing to stretch) gets r1 = 0, i.e. the output is the forced mean.
pub fn wallis_gain_offset(p: &WallisParams, local_mean: f64, local_std: f64) -> (f64, f64) {
    let (c, b) = (p.contrast_c as f64, p.brightness_b as f64);
    let (m_f, s_f) = (p.target_mean as f64, p.target_std as f64);
    let denom = c * local_std + (1.0 - c) * s_f;
    let r1 = if denom > 0.0 { c * s_f / denom } else { 0.0 };
    let r0 = b * m_f + (1.0 - b - r1) * local_mean;
    (r1, r0)
}

/// Local mean and standard deviation over a `window_px × window_px` box (rounded up to odd) centred on each
/// pixel, with reflected borders; f64 integral images. Returns (mean, std).
pub fn local_mean_std(img: &GrayImage, window_px: usize) -> (GrayImage, GrayImage) {
    let (w, h) = (img.width, img.height);
    if w == 0 || h == 0 {
        return (img.clone(), img.clone());
    }
    let r = window_px.max(1) / 2;
    let (pw, ph) = (w + 2 * r, h + 2 * r);
    let shift = img.data.iter().map(|&v| v as f64).sum::<f64>() / img.data.len() as f64;
    // Integral images of the reflected, mean-shifted image, (pw + 1) × (ph + 1), first row/col zero.
    let stride = pw + 1;
    let mut s1 = vec![0.0f64; stride * (ph + 1)];
    let mut s2 = vec![0.0f64; stride * (ph + 1)];
    for y in 0..ph {
        let src = img.row(reflect_index(y as isize - r as isize, h));
        let (mut a1, mut a2) = (0.0f64, 0.0f64);
        for x in 0..pw {
            let g = src[reflect_index(x as isize - r as isize, w)] as f64 - shift;
            a1 += g;
            a2 += g * g;
            let i = (y + 1) * stride + x + 1;
            s1[i] = s1[i - stride] + a1;
            s2[i] = s2[i - stride] + a2;
        }
    }
    let n = ((2 * r + 1) * (2 * r + 1)) as f64;
    let mut mean = GrayImage::filled(w, h, 0.0);
    let mut std = GrayImage::filled(w, h, 0.0);
    mean.data
        .par_chunks_mut(w)
        .zip(std.data.par_chunks_mut(w))
        .enumerate()
        .for_each(|(row, (mrow, srow))| {
            // Window rows row..row+2r (padded coords) → integral rows row and row+2r+1.
            let (top, bottom) = (row * stride, (row + 2 * r + 1) * stride);
            for col in 0..w {
                let (left, right) = (col, col + 2 * r + 1);
                let box_sum = |s: &[f64]| {
                    s[bottom + right] - s[bottom + left] - s[top + right] + s[top + left]
                };
                let m = box_sum(&s1) / n;
                let var = (box_sum(&s2) / n - m * m).max(0.0);
                // Rounding noise of the integral images on a flat window: treat as exactly flat.
                let scale = (m + shift).abs().max(1e-30);
                let var = if var < 1e-10 * scale * scale {
                    0.0
                } else {
                    var
                };
                mrow[col] = (m + shift) as f32;
                srow[col] = var.sqrt() as f32;
            }
        });
    (mean, std)
}

/// Apply the Wallis transform with given local statistics images (same size as `img`); e.g. pass images filled
/// with the global mean/std for a global normalisation.
pub fn wallis_apply(
    img: &GrayImage,
    local_mean: &GrayImage,
    local_std: &GrayImage,
    p: &WallisParams,
) -> Result<GrayImage, WallisError> {
    p.checked()?;
    for s in [local_mean, local_std] {
        if s.width != img.width || s.height != img.height {
            return Err(WallisError::SizeMismatch {
                got_w: s.width,
                got_h: s.height,
                want_w: img.width,
                want_h: img.height,
            });
        }
    }
    let (b, m_f) = (p.brightness_b as f64, p.target_mean as f64);
    let data = img
        .data
        .par_iter()
        .zip(local_mean.data.par_iter().zip(local_std.data.par_iter()))
        .map(|(&g, (&m, &s))| {
            let (r1, _) = wallis_gain_offset(p, m as f64, s as f64);
            (r1 * (g as f64 - m as f64) + b * m_f + (1.0 - b) * m as f64) as f32
        })
        .collect();
    Ok(GrayImage {
        width: img.width,
        height: img.height,
        data,
    })
}

/// Wallis filter with local statistics over `p.window_px` (thesis 3.4.5.2: applied to MM and aerial patches).
pub fn wallis_filter(img: &GrayImage, p: &WallisParams) -> Result<GrayImage, WallisError> {
    p.checked()?;
    let (m, s) = local_mean_std(img, p.window_px);
    wallis_apply(img, &m, &s, p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_stats_match_brute_force_with_reflection() {
        let (w, h) = (11, 7);
        let data: Vec<f32> = (0..w * h)
            .map(|k| ((k * 53 % 31) as f32) / 31.0 + 100.0)
            .collect();
        let img = GrayImage::from_vec(w, h, data).unwrap();
        let (m, s) = local_mean_std(&img, 5);
        for row in 0..h {
            for col in 0..w {
                let mut vals = vec![];
                for dy in -2..=2isize {
                    for dx in -2..=2isize {
                        let c = reflect_index(col as isize + dx, w);
                        let r = reflect_index(row as isize + dy, h);
                        vals.push(img.get(c, r) as f64);
                    }
                }
                let mean = vals.iter().sum::<f64>() / 25.0;
                let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 25.0;
                assert!((m.get(col, row) as f64 - mean).abs() < 1e-4);
                assert!((s.get(col, row) as f64 - var.sqrt()).abs() < 1e-4);
            }
        }
    }

    #[test]
    fn invalid_parameters_are_named() {
        let p = WallisParams {
            contrast_c: 1.5,
            ..Default::default()
        };
        let e = wallis_filter(&GrayImage::filled(4, 4, 0.5), &p).unwrap_err();
        assert!(e.to_string().contains("contrast_c"));
    }
}

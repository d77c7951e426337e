//! Normalised cross-correlation template matching with OpenCV `TM_CCOEFF_NORMED` semantics and a sub-pixel
//! peak (thesis 3.4.4.4: MM↔MM corner tracking; OpenCV TM_CCOEFF_NORMED).
//!
//! `R(x, y) = Σ T'·I'(x,y) / sqrt(Σ T'² · Σ I'(x,y)²)` over the window whose top-left pixel is (x, y); the map is
//! `(W − w + 1) × (H − h + 1)`. The numerator is computed directly (Σ T'·I, the template zero-mean) in f64, the
//! window energies from mean-shifted f64 integral images. Flat windows or templates give 0 (OpenCV's rule:
//! energy ≤ min(0.5, 10·FLT_EPSILON·Σ I²) counts as flat; |num| slightly above the bound clamps to ±1).
//! A template cut at pixel (x, y) has its centre at continuous (x + w/2, y + h/2).

use rayon::prelude::*;
use thiserror::Error;

use super::subpixel::{refine_peak, PeakFit};
use crate::imaging::GrayImage;

#[derive(Debug, Error, PartialEq)]
pub enum NccError {
    #[error("template {t_w}×{t_h} is empty or larger than the image {i_w}×{i_h}")]
    TemplateDoesNotFit {
        t_w: usize,
        t_h: usize,
        i_w: usize,
        i_h: usize,
    },
    #[error("image or template contains non-finite values (NaN/inf); fill them before matching")]
    NonFinite,
}

/// Best match of a template.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NccMatch {
    /// Template centre in image pixel coordinates (continuous, sub-pixel).
    pub u_px: f64,
    pub v_px: f64,
    /// NCC at the integer peak, in [−1, 1].
    pub score: f32,
}

/// The full `TM_CCOEFF_NORMED` map, `(W − w + 1) × (H − h + 1)`; pixel (x, y) is the score of the window
/// whose top-left pixel is (x, y).
pub fn ncc_map(image: &GrayImage, template: &GrayImage) -> Result<GrayImage, NccError> {
    let (iw, ih, tw, th) = (image.width, image.height, template.width, template.height);
    if tw == 0 || th == 0 || tw > iw || th > ih {
        return Err(NccError::TemplateDoesNotFit {
            t_w: tw,
            t_h: th,
            i_w: iw,
            i_h: ih,
        });
    }
    if !image
        .data
        .iter()
        .chain(&template.data)
        .all(|v| v.is_finite())
    {
        return Err(NccError::NonFinite);
    }
    let n = (tw * th) as f64;
    let t_mean = template.data.iter().map(|&v| v as f64).sum::<f64>() / n;
    let t_zero: Vec<f64> = template.data.iter().map(|&v| v as f64 - t_mean).collect();
    let t_norm = t_zero.iter().map(|v| v * v).sum::<f64>().sqrt();

    // Integral images of (I − shift) and (I − shift)², (iw + 1) × (ih + 1).
    let shift = image.data.iter().map(|&v| v as f64).sum::<f64>() / image.data.len() as f64;
    let stride = iw + 1;
    let mut s1 = vec![0.0f64; stride * (ih + 1)];
    let mut s2 = vec![0.0f64; stride * (ih + 1)];
    for y in 0..ih {
        let (mut a1, mut a2) = (0.0, 0.0);
        for (x, &g) in image.row(y).iter().enumerate() {
            let d = g as f64 - shift;
            a1 += d;
            a2 += d * d;
            let i = (y + 1) * stride + x + 1;
            s1[i] = s1[i - stride] + a1;
            s2[i] = s2[i - stride] + a2;
        }
    }

    let (mw, mh) = (iw - tw + 1, ih - th + 1);
    let mut map = GrayImage::filled(mw, mh, 0.0);
    map.data
        .par_chunks_mut(mw)
        .enumerate()
        .for_each(|(y, out_row)| {
            for (x, out) in out_row.iter_mut().enumerate() {
                let mut num = 0.0f64;
                for (j, t_row) in t_zero.chunks_exact(tw).enumerate() {
                    let i_row = &image.row(y + j)[x..x + tw];
                    for (&t, &g) in t_row.iter().zip(i_row) {
                        num += t * g as f64;
                    }
                }
                let (top, bottom) = (y * stride, (y + th) * stride);
                let box_sum =
                    |s: &[f64]| s[bottom + x + tw] - s[bottom + x] - s[top + x + tw] + s[top + x];
                let (d1, d2) = (box_sum(&s1), box_sum(&s2));
                // Window energy Σ(I − mean)² = Σ d² − (Σ d)²/n (shift-invariant); raw Σ I² for OpenCV's flat test.
                let diff = (d2 - d1 * d1 / n).max(0.0);
                let raw_sq = d2 + 2.0 * shift * d1 + n * shift * shift;
                let flat_limit = (0.5f64).min(10.0 * f32::EPSILON as f64 * raw_sq);
                let t = if diff <= flat_limit {
                    0.0
                } else {
                    diff.sqrt() * t_norm
                };
                *out = if num.abs() < t {
                    (num / t) as f32
                } else if num.abs() < 1.125 * t {
                    num.signum() as f32
                } else {
                    0.0
                };
            }
        });
    Ok(map)
}

/// Best match (first maximum in raster order) with the sub-pixel peak from a quadratic fit to the 3 × 3 map
/// neighbourhood (per-axis parabolas at the map border; none on a 1-wide axis).
pub fn match_template(image: &GrayImage, template: &GrayImage) -> Result<NccMatch, NccError> {
    let map = ncc_map(image, template)?;
    let mut best = 0usize;
    for (i, &v) in map.data.iter().enumerate() {
        if v > map.data[best] {
            best = i;
        }
    }
    let (px, py) = (best % map.width, best / map.width);
    let (dx, dy) = subpixel_offset(&map, px, py);
    Ok(NccMatch {
        u_px: px as f64 + dx + template.width as f64 / 2.0,
        v_px: py as f64 + dy + template.height as f64 / 2.0,
        score: map.data[best],
    })
}

fn subpixel_offset(map: &GrayImage, px: usize, py: usize) -> (f64, f64) {
    let inside_x = px >= 1 && px + 1 < map.width;
    let inside_y = py >= 1 && py + 1 < map.height;
    let at = |x: usize, y: usize| map.get(x, y) as f64;
    if inside_x && inside_y {
        let mut n = [[0.0f64; 3]; 3];
        for (j, row) in n.iter_mut().enumerate() {
            for (i, v) in row.iter_mut().enumerate() {
                *v = at(px + i - 1, py + j - 1);
            }
        }
        return refine_peak(&n, PeakFit::Quadratic);
    }
    let dx = if inside_x {
        super::subpixel::parabola_peak_1d(at(px - 1, py), at(px, py), at(px + 1, py)).unwrap_or(0.0)
    } else {
        0.0
    };
    let dy = if inside_y {
        super::subpixel::parabola_peak_1d(at(px, py - 1), at(px, py), at(px, py + 1)).unwrap_or(0.0)
    } else {
        0.0
    };
    (dx, dy)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors() {
        let img = GrayImage::filled(5, 5, 0.0);
        let big = GrayImage::filled(6, 2, 0.0);
        assert!(matches!(
            ncc_map(&img, &big),
            Err(NccError::TemplateDoesNotFit { .. })
        ));
        let mut bad = GrayImage::filled(2, 2, 0.0);
        bad.data[0] = f32::INFINITY;
        assert_eq!(ncc_map(&img, &bad), Err(NccError::NonFinite));
    }
}

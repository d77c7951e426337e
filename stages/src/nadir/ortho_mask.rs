//! The masked pixels of an MM ortho image (the recording vehicle, outside the panorama's ground): filled
//! before filtering, so that the Wallis filter and the detectors see no artificial edge at the mask border
//! (thesis 3.4.5.2, step 2), and kept clear of keypoints.

use super::ortho::OrthoImage;
use crate::imaging::GrayImage;

/// `ortho.image` with masked (and non-finite) pixels replaced by the mean of the valid pixels.
pub fn fill_masked(ortho: &OrthoImage) -> GrayImage {
    let img = &ortho.image;
    let n = img.data.len();
    let is_valid =
        |i: usize| ortho.valid.get(i).is_some_and(|&v| v != 0) && img.data[i].is_finite();
    let (mut sum, mut count) = (0.0f64, 0usize);
    for i in 0..n {
        if is_valid(i) {
            sum += img.data[i] as f64;
            count += 1;
        }
    }
    let mean = if count > 0 {
        (sum / count as f64) as f32
    } else {
        0.0
    };
    GrayImage {
        width: img.width,
        height: img.height,
        data: (0..n)
            .map(|i| if is_valid(i) { img.data[i] } else { mean })
            .collect(),
    }
}

/// True if a masked pixel (valid = 0) lies within `radius_px` of the continuous pixel (u, v).
pub fn near_mask(
    valid: &[u8],
    width: usize,
    height: usize,
    u: f64,
    v: f64,
    radius_px: f64,
) -> bool {
    if width == 0 || height == 0 {
        return false;
    }
    let r2 = radius_px * radius_px;
    let clamp = |x: f64, n: usize| x.clamp(0.0, n as f64 - 1.0) as usize;
    let (c0, c1) = (
        clamp((u - radius_px - 0.5).floor(), width),
        clamp((u + radius_px - 0.5).ceil(), width),
    );
    let (r0, r1) = (
        clamp((v - radius_px - 0.5).floor(), height),
        clamp((v + radius_px - 0.5).ceil(), height),
    );
    for row in r0..=r1 {
        let dv = row as f64 + 0.5 - v;
        for col in c0..=c1 {
            let du = col as f64 + 0.5 - u;
            if du * du + dv * dv <= r2 && valid[row * width + col] == 0 {
                return true;
            }
        }
    }
    false
}

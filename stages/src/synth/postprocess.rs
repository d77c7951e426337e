//! Per-epoch camera response applied to rendered linear radiance: optical blur, gain and colour balance,
//! haze, gamma and sensor noise. Mobile-mapping and aerial epochs get deliberately different looks, so that
//! matching across them has to cope with radiometric differences as in the thesis' data (thesis 3.4).
//!
//! Noise is drawn from a per-pixel hash of (seed, image key, pixel, channel): no shared RNG, so the result is
//! the same for any thread count.

use super::rng::{hash_keys, normal_from_hash};
use crate::imaging::RgbImage;
use rayon::prelude::*;

/// The radiometric look of one acquisition epoch.
#[derive(Clone, Debug, PartialEq)]
pub struct EpochLook {
    /// Gaussian optical blur before the sensor, pixels (0 = none).
    pub blur_sigma_px: f32,
    /// Per-channel gain (exposure × white balance) on linear values.
    pub gain_rgb: [f32; 3],
    /// Added linear haze / flare per channel.
    pub haze_rgb: [f32; 3],
    /// Encoding exponent: output = linear^(1/gamma).
    pub gamma: f32,
    /// SD of additive Gaussian noise on the encoded 0..1 values.
    pub noise_sigma: f32,
}

impl EpochLook {
    /// Mobile-mapping panoramas: slightly warm, sRGB-like gamma, little noise, no extra blur.
    pub fn mobile_mapping() -> Self {
        Self {
            blur_sigma_px: 0.0,
            gain_rgb: [1.06, 1.0, 0.93],
            haze_rgb: [0.0, 0.0, 0.0],
            gamma: 2.2,
            noise_sigma: 0.008,
        }
    }

    /// Aerial frames: slight optical blur (σ ≈ 0.6 px), cooler and hazier (atmosphere), flatter gamma, more noise.
    pub fn aerial() -> Self {
        Self {
            blur_sigma_px: 0.6,
            gain_rgb: [0.90, 0.96, 1.05],
            haze_rgb: [0.025, 0.03, 0.045],
            gamma: 1.9,
            noise_sigma: 0.012,
        }
    }
}

impl EpochLook {
    /// This look with every channel's gain multiplied by `gain` (an image's own exposure).
    pub fn exposed(mut self, gain: f32) -> Self {
        self.gain_rgb = self.gain_rgb.map(|g| g * gain);
        self
    }
}

/// Normalised 1-D Gaussian kernel of radius ⌈3σ⌉.
fn gaussian_kernel(sigma_px: f32) -> Vec<f32> {
    let radius = (3.0 * sigma_px).ceil().max(1.0) as i64;
    let mut k: Vec<f32> = (-radius..=radius)
        .map(|i| (-(i * i) as f32 / (2.0 * sigma_px * sigma_px)).exp())
        .collect();
    let sum: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    k
}

/// Separable Gaussian blur of an RGB image (edges clamped). Rows are processed in parallel, each output value
/// is a fixed-order sum, so the result does not depend on the thread count.
pub fn gaussian_blur_rgb(img: &RgbImage, sigma_px: f32) -> RgbImage {
    if sigma_px <= 0.0 || img.width == 0 || img.height == 0 {
        return img.clone();
    }
    let k = gaussian_kernel(sigma_px);
    let r = (k.len() / 2) as i64;
    let (w, h) = (img.width, img.height);
    let mut tmp = vec![0.0f32; w * h * 3];
    tmp.par_chunks_mut(w * 3)
        .enumerate()
        .for_each(|(row, out)| {
            let src = &img.data[row * w * 3..(row + 1) * w * 3];
            for col in 0..w {
                let mut acc = [0.0f32; 3];
                for (j, kv) in k.iter().enumerate() {
                    let c = (col as i64 + j as i64 - r).clamp(0, w as i64 - 1) as usize;
                    for ch in 0..3 {
                        acc[ch] += kv * src[c * 3 + ch];
                    }
                }
                out[col * 3..col * 3 + 3].copy_from_slice(&acc);
            }
        });
    let mut data = vec![0.0f32; w * h * 3];
    data.par_chunks_mut(w * 3)
        .enumerate()
        .for_each(|(row, out)| {
            for (j, kv) in k.iter().enumerate() {
                let rr = (row as i64 + j as i64 - r).clamp(0, h as i64 - 1) as usize;
                let src = &tmp[rr * w * 3..(rr + 1) * w * 3];
                for (o, s) in out.iter_mut().zip(src) {
                    *o += kv * s;
                }
            }
        });
    RgbImage {
        width: w,
        height: h,
        data,
    }
}

/// Apply `look` to a linear rendering: blur, gain, haze, gamma, noise; result clamped to 0..1.
/// `seed` and `image_key` (e.g. a hash of the image id) key the per-pixel noise.
pub fn apply_look(img: &RgbImage, look: &EpochLook, seed: u64, image_key: u64) -> RgbImage {
    let mut out = gaussian_blur_rgb(img, look.blur_sigma_px);
    let w = out.width;
    let inv_gamma = 1.0 / look.gamma;
    out.data
        .par_chunks_mut((w * 3).max(1))
        .enumerate()
        .for_each(|(row, line)| {
            for (i, v) in line.iter_mut().enumerate() {
                let ch = i % 3;
                let lin = (look.gain_rgb[ch] * *v + look.haze_rgb[ch]).max(0.0);
                let mut e = lin.powf(inv_gamma);
                if look.noise_sigma > 0.0 {
                    let idx = (row * w * 3 + i) as u64;
                    e += look.noise_sigma
                        * normal_from_hash(hash_keys(&[seed, image_key, idx])) as f32;
                }
                *v = e.clamp(0.0, 1.0);
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blur_preserves_flat_images_and_mass_and_spreads_an_impulse() {
        let flat = RgbImage::filled(9, 7, [0.25, 0.5, 0.75]);
        let b = gaussian_blur_rgb(&flat, 0.6);
        assert!(b
            .data
            .iter()
            .zip(&flat.data)
            .all(|(a, c)| (a - c).abs() < 1e-6));
        let mut imp = RgbImage::filled(9, 9, [0.0; 3]);
        imp.set(4, 4, [1.0, 1.0, 1.0]);
        let b = gaussian_blur_rgb(&imp, 0.6);
        let total: f32 = b.data.iter().step_by(3).sum();
        assert!((total - 1.0).abs() < 1e-5);
        // Centre weight of a sampled σ = 0.6 Gaussian, squared (2-D): (1 / Σ exp(−i²/0.72))².
        let c1 = 1.0 / (1.0 + 2.0 * (-1.0f32 / 0.72).exp() + 2.0 * (-4.0f32 / 0.72).exp());
        assert!((b.get(4, 4)[0] - c1 * c1).abs() < 1e-5);
        assert!(
            (b.get(3, 4)[0] - b.get(5, 4)[0]).abs() < 1e-7
                && (b.get(4, 3)[0] - b.get(4, 5)[0]).abs() < 1e-7
        );
    }

    #[test]
    fn look_without_noise_is_gain_then_gamma_and_noise_has_its_sigma() {
        let img = RgbImage::filled(64, 64, [0.2, 0.2, 0.2]);
        let mut look = EpochLook::mobile_mapping();
        look.noise_sigma = 0.0;
        let out = apply_look(&img, &look, 1, 2);
        let want = (1.06f32 * 0.2).powf(1.0 / 2.2);
        assert!((out.get(10, 10)[0] - want).abs() < 1e-6);
        let look = EpochLook::mobile_mapping();
        let noisy = apply_look(&img, &look, 1, 2);
        let d: Vec<f64> = noisy
            .data
            .iter()
            .zip(&out.data)
            .map(|(a, b)| (a - b) as f64)
            .collect();
        let sd = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
        assert!((sd - 0.008).abs() < 0.0004, "noise SD {sd}");
        assert_ne!(
            noisy,
            apply_look(&img, &look, 1, 3),
            "different image keys give different noise"
        );
    }
}

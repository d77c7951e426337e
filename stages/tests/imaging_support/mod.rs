//! Shared generators for the imaging/matching/feature known-answer tests: a deterministic RNG and a periodic,
//! band-limited random texture that can be translated by any sub-pixel amount exactly (Fourier shift).

#![allow(dead_code)]

use rustfft::num_complex::Complex;
use rustfft::{FftDirection, FftPlanner};
use skytie_stages::imaging::GrayImage;

/// SplitMix64: tiny deterministic PRNG for tests.
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// Periodic band-limited random texture defined by its spectrum on a `period × period` grid: white noise,
/// amplitude ∝ 1/|k| (natural-image-like), zero beyond `max_freq` cycles per period (and at DC).
/// Rendering a translated copy multiplies the spectrum by the phase ramp `exp(−i2π k·t / period)` and inverts
/// it: an exact Fourier shift of the periodic texture.
pub struct Texture {
    period: usize,
    spectrum: Vec<Complex<f64>>,
}

impl Texture {
    pub fn new(period_px: usize, max_freq: i32, seed: u64) -> Self {
        let n = period_px;
        let mut rng = SplitMix64(seed);
        let mut buf: Vec<Complex<f64>> = (0..n * n)
            .map(|_| Complex::new(rng.normal(), 0.0))
            .collect();
        fft_2d(&mut buf, n, FftDirection::Forward);
        let mut power = 0.0;
        for ky in 0..n {
            for kx in 0..n {
                let k = (wrap(kx, n).powi(2) + wrap(ky, n).powi(2)).sqrt();
                let i = ky * n + kx;
                let gain = if k < 1.0 || k > max_freq as f64 {
                    0.0
                } else {
                    1.0 / k
                };
                buf[i] *= gain;
                power += buf[i].norm_sqr();
            }
        }
        // Unit standard deviation in the image domain (Parseval: Σ|x|² = Σ|X|²/N²).
        let scale = 1.0 / (power / (n * n) as f64 / (n * n) as f64).sqrt();
        for v in &mut buf {
            *v *= scale;
        }
        Self {
            period: n,
            spectrum: buf,
        }
    }

    /// The `w × h` window of the texture whose top-left corner is at the sub-pixel position `(ox, oy)`.
    pub fn crop_at(&self, w: usize, h: usize, (ox, oy): (f64, f64)) -> GrayImage {
        self.render(
            w,
            h,
            ox.floor(),
            oy.floor(),
            ox.floor() - ox,
            oy.floor() - oy,
        )
    }

    /// `w × h` image, pixel (i, j) = `0.5 + 0.15·f(x0 + i + 0.5 − tx, y0 + j + 0.5 − ty)` with integer crop
    /// origin (x0, y0) (rounded to integers; put fractions into t): the crop of the texture translated by
    /// (tx, ty). Sample positions wrap periodically.
    pub fn render(&self, w: usize, h: usize, x0: f64, y0: f64, tx: f64, ty: f64) -> GrayImage {
        let n = self.period;
        let mut buf = self.spectrum.clone();
        // Pixel index p sits at continuous p + 0.5; the texture's own sample k is at position k, so translate
        // by t − 0.5 and read index x0 + i.
        let (sx, sy) = (tx - 0.5, ty - 0.5);
        for ky in 0..n {
            for kx in 0..n {
                let phase =
                    -2.0 * std::f64::consts::PI * (wrap(kx, n) * sx + wrap(ky, n) * sy) / n as f64;
                buf[ky * n + kx] *= Complex::from_polar(1.0, phase);
            }
        }
        fft_2d(&mut buf, n, FftDirection::Inverse);
        let inv = 1.0 / (n * n) as f64;
        let (x0, y0) = (x0.round() as i64, y0.round() as i64);
        let data = (0..w * h)
            .map(|k| {
                let x = (x0 + (k % w) as i64).rem_euclid(n as i64) as usize;
                let y = (y0 + (k / w) as i64).rem_euclid(n as i64) as usize;
                (0.5 + 0.15 * buf[y * n + x].re * inv) as f32
            })
            .collect();
        GrayImage::from_vec(w, h, data).unwrap()
    }
}

fn wrap(k: usize, n: usize) -> f64 {
    if 2 * k >= n {
        k as f64 - n as f64
    } else {
        k as f64
    }
}

fn fft_2d(buf: &mut [Complex<f64>], n: usize, dir: FftDirection) {
    let fft = FftPlanner::new().plan_fft(n, dir);
    fft.process(buf);
    let mut t = vec![Complex::new(0.0, 0.0); n * n];
    for y in 0..n {
        for x in 0..n {
            t[x * n + y] = buf[y * n + x];
        }
    }
    fft.process(&mut t);
    for y in 0..n {
        for x in 0..n {
            buf[y * n + x] = t[x * n + y];
        }
    }
}

/// Radiometric change: gain, offset, gamma on [0, 1] (clamped), plus Gaussian noise of `noise_std`.
pub fn radiometric(
    img: &GrayImage,
    gain: f64,
    offset: f64,
    gamma: f64,
    noise_std: f64,
    seed: u64,
) -> GrayImage {
    let mut rng = SplitMix64(seed);
    let data = img
        .data
        .iter()
        .map(|&g| {
            let v = (gain * g as f64 + offset).clamp(0.0, 1.0).powf(gamma);
            (v + noise_std * rng.normal()) as f32
        })
        .collect();
    GrayImage::from_vec(img.width, img.height, data).unwrap()
}

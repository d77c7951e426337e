//! Mattes mutual information between a fixed and a translated moving image (Mattes et al. 2001, as ITK v3
//! `MattesMutualInformationImageToImageMetric`), the similarity of the fine patch registration
//! (thesis 4.4.6).
//!
//! - A fixed sample set of fixed-image pixels is drawn once ([`MattesMi::new`]): all valid pixels, or `N`
//!   distinct valid pixels drawn with a seeded generator.
//! - Intensity ranges come from the whole valid part of each image; `B` bins with padding `P = 2`:
//!   `Δ = (max − min)/(B − 2P)`, bin term `τ(g) = (g − min)/Δ + P`.
//! - Fixed image: box Parzen window (`ι = clamp(⌊τ_F⌋, 2, B − 3)`); moving image: cubic B-spline Parzen window
//!   over the bins `κ0 − 1 … κ0 + 2` (`κ0 = clamp(⌊τ_M⌋, 2, B − 3)`, weight `β3(κ − τ_M)`).
//! - The moving image is sampled by bilinear interpolation at `x + t` (a translation `t`, pixels); samples
//!   whose position is outside the moving image (pixel-centre grid `[0.5, W − 0.5] × [0.5, H − 0.5]`, as ITK's
//!   linear interpolator) or touch a masked moving pixel are skipped. Fewer than 1/16 of the samples landing is
//!   an error (as ITK).
//!
//! Masks: a pixel without data (e.g. a patch pixel outside its source image) is NaN in either image
//! ([`apply_mask`] turns a validity mask into NaNs). Evaluation allocates nothing: the histograms live in the
//! [`MattesMi`] value and are reused.
//!
//! Translation convention: `t` is the translation of the moving image's content relative to the fixed image's,
//! in pixels: fixed pixel `x` is compared with the moving image at `x + t`, so a moving image whose content is
//! the fixed content moved by `d` gives the best MI at `t = d`.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::estimators::one_plus_one::{minimize, OnePlusOneParams};
use crate::estimators::SplitMix64;
use crate::imaging::GrayImage;
use thiserror::Error;

/// Histogram padding of the Parzen windows (ITK: 2).
pub const PADDING_BINS: usize = 2;

/// Values below this are treated as zero probability in the MI sum (ITK's `closeToZero` idea).
const PROBABILITY_EPS: f64 = 1e-16;

/// Why a metric could not be set up or evaluated.
#[derive(Debug, Error, PartialEq)]
pub enum MiError {
    #[error("{bins} histogram bins: need at least {min} (2 × padding {PADDING_BINS} + 1)", min = 2 * PADDING_BINS + 1)]
    TooFewBins { bins: usize },
    #[error("the {which} image has no valid (finite) pixel")]
    NoValidPixels { which: &'static str },
    #[error("the {which} image is constant (all valid pixels equal {value}): mutual information is undefined")]
    ConstantImage { which: &'static str, value: f32 },
    #[error("only {landed} of {samples} fixed samples landed in the moving image (need ≥ 1/16)")]
    TooFewSamplesLanded { landed: usize, samples: usize },
    #[error("translation ({0}, {1}) is not finite")]
    NonFiniteTranslation(f64, f64),
    #[error("the best scanned shift ({0}, {1}) px lies on the border of the search window: the similarity still grows outwards, so the true shift is probably larger than the window (enlarge it if that is plausible)")]
    MaximumOnBorder(f64, f64),
}

/// Cubic B-spline kernel β3(u) (Mattes et al. 2001; Styner et al. 2000).
#[inline]
pub fn bspline3(u: f64) -> f64 {
    let a = u.abs();
    if a < 1.0 {
        (4.0 - 6.0 * a * a + 3.0 * a * a * a) / 6.0
    } else if a < 2.0 {
        let b = 2.0 - a;
        b * b * b / 6.0
    } else {
        0.0
    }
}

/// A copy of `img` with the pixels whose `valid` flag is false set to NaN (no data). `valid` is row-major,
/// one flag per pixel; a length mismatch returns `None`.
pub fn apply_mask(img: &GrayImage, valid: &[bool]) -> Option<GrayImage> {
    if valid.len() != img.data.len() {
        return None;
    }
    let data = img
        .data
        .iter()
        .zip(valid)
        .map(|(&v, &ok)| if ok { v } else { f32::NAN })
        .collect();
    GrayImage::from_vec(img.width, img.height, data)
}

/// Minimum and maximum of the finite pixels, `None` if there is none.
fn finite_range(img: &GrayImage) -> Option<(f64, f64)> {
    let mut lo = f32::INFINITY;
    let mut hi = f32::NEG_INFINITY;
    for &v in &img.data {
        if v.is_finite() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    (lo <= hi).then_some((f64::from(lo), f64::from(hi)))
}

/// Bin geometry of one image: `τ(g) = (g − min)/Δ + P`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct BinScale {
    min: f64,
    max: f64,
    delta: f64,
}

impl BinScale {
    fn of(img: &GrayImage, bins: usize, which: &'static str) -> Result<Self, MiError> {
        let (min, max) = finite_range(img).ok_or(MiError::NoValidPixels { which })?;
        if !(max > min) {
            return Err(MiError::ConstantImage {
                which,
                value: min as f32,
            });
        }
        Ok(Self {
            min,
            max,
            delta: (max - min) / (bins - 2 * PADDING_BINS) as f64,
        })
    }

    #[inline]
    fn term(&self, g: f64) -> f64 {
        (g - self.min) / self.delta + PADDING_BINS as f64
    }
}

/// One fixed-image sample: its pixel-centre position and its (box-window) fixed bin.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FixedSample {
    /// The fixed pixel (its centre is the sample position).
    col: usize,
    row: usize,
    bin: usize,
}

/// A translation split into whole pixels and the bilinear weights of its fractional part. Every sample is a
/// fixed pixel centre, so every sample lands at the same fractional position between moving pixel centres:
/// the weights are computed once per evaluation.
#[derive(Clone, Copy, Debug)]
struct Shift {
    dx: i64,
    dy: i64,
    /// 1 when the translation has a fractional part along the axis (the next pixel gets weight), else 0.
    step_x: i64,
    step_y: i64,
    /// Weights of the moving pixels (c, r), (c + 1, r), (c, r + 1), (c + 1, r + 1).
    weights: [f64; 4],
}

impl Shift {
    fn new(tx: f64, ty: f64) -> Self {
        let (ix, iy) = (tx.floor(), ty.floor());
        let (fx, fy) = (tx - ix, ty - iy);
        Self {
            dx: ix as i64,
            dy: iy as i64,
            step_x: i64::from(fx > 0.0),
            step_y: i64::from(fy > 0.0),
            weights: [
                (1.0 - fx) * (1.0 - fy),
                fx * (1.0 - fy),
                (1.0 - fx) * fy,
                fx * fy,
            ],
        }
    }

    fn is_integral(&self) -> bool {
        self.step_x == 0 && self.step_y == 0
    }
}

/// Mattes MI of a fixed image against a moving image under translations; built once per image pair, then
/// evaluated for many translations without allocating.
#[derive(Clone, Debug)]
pub struct MattesMi<'a> {
    moving: &'a GrayImage,
    bins: usize,
    moving_scale: BinScale,
    samples: Vec<FixedSample>,
    /// Joint histogram, `bins × bins`, row = fixed bin, column = moving bin (scratch).
    joint: Vec<f64>,
    /// Fixed marginal counts (scratch).
    fixed_counts: Vec<f64>,
    /// Moving marginal (scratch).
    moving_marginal: Vec<f64>,
    /// Per moving pixel, its Parzen terms for integral translations (built on the first one; empty before).
    pixel_parzen: Vec<PixelParzen>,
}

/// The moving-image Parzen terms of one moving pixel: `κ0` and the B-spline weights of the bins
/// `κ0 − 1 … κ0 + 2`; `k0 == NO_BIN` for a masked pixel. At an integral translation every fixed sample (a pixel
/// centre) lands exactly on a moving pixel centre, the bilinear interpolation returns that pixel's value, and
/// these terms are what [`MattesMi::evaluate`] would compute for it — so the integer scans of the patch
/// registration (thesis 4.4.6) skip the interpolation and the B-spline evaluation with identical results.
#[derive(Clone, Copy, Debug)]
struct PixelParzen {
    k0: u32,
    weights: [f64; 4],
}

const NO_BIN: u32 = u32::MAX;

impl<'a> MattesMi<'a> {
    /// Prepare the metric: ranges of both images, the fixed sample set (`samples = None`: every valid fixed
    /// pixel in row-major order; `Some(n)`: `n` distinct valid pixels drawn with `seed`, all of them if there
    /// are fewer) and their fixed bins.
    pub fn new(
        fixed: &GrayImage,
        moving: &'a GrayImage,
        bins: usize,
        samples: Option<usize>,
        seed: u64,
    ) -> Result<Self, MiError> {
        if bins < 2 * PADDING_BINS + 1 {
            return Err(MiError::TooFewBins { bins });
        }
        let fixed_scale = BinScale::of(fixed, bins, "fixed")?;
        let moving_scale = BinScale::of(moving, bins, "moving")?;
        let valid: Vec<usize> = (0..fixed.data.len())
            .filter(|&i| fixed.data[i].is_finite())
            .collect();
        let chosen: Vec<usize> = match samples {
            Some(n) if n < valid.len() => {
                // Partial Fisher–Yates: n distinct indices, deterministic for the seed.
                let mut pool = valid;
                let mut rng = SplitMix64::new(seed);
                for i in 0..n {
                    let j = i + rng.below((pool.len() - i) as u64) as usize;
                    pool.swap(i, j);
                }
                pool.truncate(n);
                pool
            }
            _ => valid,
        };
        let top = (bins - PADDING_BINS - 1) as f64;
        let samples = chosen
            .into_iter()
            .map(|i| {
                let tau = fixed_scale.term(f64::from(fixed.data[i]));
                let bin = tau.floor().clamp(PADDING_BINS as f64, top) as usize;
                FixedSample {
                    col: i % fixed.width,
                    row: i / fixed.width,
                    bin,
                }
            })
            .collect();
        Ok(Self {
            moving,
            bins,
            moving_scale,
            samples,
            joint: vec![0.0; bins * bins],
            fixed_counts: vec![0.0; bins],
            moving_marginal: vec![0.0; bins],
            pixel_parzen: Vec::new(),
        })
    }

    /// Number of fixed samples.
    pub fn sample_count(&self) -> usize {
        self.samples.len()
    }

    /// The moving pixel (column, row) under the sample `s` moved by `shift` (the top-left of its bilinear
    /// neighbourhood), `None` when the position is outside the pixel-centre grid `[0.5, W − 0.5] × [0.5, H − 0.5]`.
    #[inline]
    fn landing(&self, s: &FixedSample, shift: &Shift) -> Option<(usize, usize)> {
        // Saturating: a huge (finite) translation must land outside, not wrap around.
        let (c, r) = (
            (s.col as i64).saturating_add(shift.dx),
            (s.row as i64).saturating_add(shift.dy),
        );
        let (w, h) = (self.moving.width as i64, self.moving.height as i64);
        (c >= 0 && r >= 0 && c < w - shift.step_x && r < h - shift.step_y)
            .then_some((c as usize, r as usize))
    }

    /// Bilinear moving value at the sample `s` moved by `shift`; `None` outside the moving image or when a pixel
    /// with non-zero weight is masked (NaN).
    #[inline]
    fn moving_value(&self, s: &FixedSample, shift: &Shift) -> Option<f64> {
        let (c, r) = self.landing(s, shift)?;
        let img = self.moving;
        let p = |c: usize, r: usize, w: f64| -> Option<f64> {
            if w == 0.0 {
                return Some(0.0);
            }
            let v = img.data[r * img.width + c];
            v.is_finite().then(|| w * f64::from(v))
        };
        let w = &shift.weights;
        Some(p(c, r, w[0])? + p(c + 1, r, w[1])? + p(c, r + 1, w[2])? + p(c + 1, r + 1, w[3])?)
    }

    /// `κ0` (the first bin of the B-spline window, clamped to the padded range) and the four weights of the
    /// moving value `m` (already checked to lie in the moving range, so `τ ≥ P` and truncation is the floor).
    #[inline]
    fn parzen_terms(&self, m: f64) -> (usize, [f64; 4]) {
        let tau = self.moving_scale.term(m);
        let k0 = (tau as usize).clamp(PADDING_BINS, self.bins - PADDING_BINS - 1);
        let mut weights = [0.0; 4];
        for (i, w) in weights.iter_mut().enumerate() {
            *w = bspline3((k0 + i - 1) as f64 - tau);
        }
        (k0, weights)
    }

    /// Fills [`Self::pixel_parzen`] (once).
    fn build_pixel_parzen(&mut self) {
        let (m_min, m_max) = (self.moving_scale.min, self.moving_scale.max);
        let table: Vec<PixelParzen> = self
            .moving
            .data
            .iter()
            .map(|&v| {
                let m = f64::from(v);
                if v.is_finite() && m >= m_min && m <= m_max {
                    let (k0, weights) = self.parzen_terms(m);
                    PixelParzen {
                        k0: k0 as u32,
                        weights,
                    }
                } else {
                    PixelParzen {
                        k0: NO_BIN,
                        weights: [0.0; 4],
                    }
                }
            })
            .collect();
        self.pixel_parzen = table;
    }

    /// The Parzen terms of the moving pixel the sample `s` lands on under the integral `shift`, `None` outside
    /// the moving image or on a masked pixel — as [`Self::moving_value`] decides.
    #[inline]
    fn pixel_terms(&self, s: &FixedSample, shift: &Shift) -> Option<(usize, [f64; 4])> {
        let (c, r) = self.landing(s, shift)?;
        let p = self.pixel_parzen[r * self.moving.width + c];
        (p.k0 != NO_BIN).then_some((p.k0 as usize, p.weights))
    }

    /// Mattes MI (nats, ≥ 0; higher = more similar) with the moving image translated by `(tx, ty)` pixels.
    pub fn evaluate(&mut self, tx: f64, ty: f64) -> Result<f64, MiError> {
        if !(tx.is_finite() && ty.is_finite()) {
            return Err(MiError::NonFiniteTranslation(tx, ty));
        }
        let bins = self.bins;
        self.joint.fill(0.0);
        self.fixed_counts.fill(0.0);
        self.moving_marginal.fill(0.0);
        let (m_min, m_max) = (self.moving_scale.min, self.moving_scale.max);
        // Every sample is a fixed pixel centre, so an integral translation lands on moving pixel centres.
        let shift = Shift::new(tx, ty);
        let integral = shift.is_integral();
        if integral && self.pixel_parzen.is_empty() {
            self.build_pixel_parzen();
        }
        let mut landed = 0usize;
        for k in 0..self.samples.len() {
            let s = self.samples[k];
            let terms = if integral {
                self.pixel_terms(&s, &shift)
            } else {
                self.moving_value(&s, &shift)
                    .filter(|&m| m >= m_min && m <= m_max)
                    .map(|m| self.parzen_terms(m))
            };
            let Some((k0, weights)) = terms else {
                continue;
            };
            let row = &mut self.joint[s.bin * bins..(s.bin + 1) * bins];
            for (cell, w) in row[k0 - 1..=k0 + 2].iter_mut().zip(weights) {
                *cell += w;
            }
            self.fixed_counts[s.bin] += 1.0;
            landed += 1;
        }
        if landed == 0 || landed < self.samples.len() / 16 {
            return Err(MiError::TooFewSamplesLanded {
                landed,
                samples: self.samples.len(),
            });
        }
        let total = landed as f64;
        for r in 0..bins {
            for c in 0..bins {
                self.moving_marginal[c] += self.joint[r * bins + c];
            }
        }
        let mut mi = 0.0;
        for r in 0..bins {
            let pf = self.fixed_counts[r] / total;
            if !(pf > PROBABILITY_EPS) {
                continue;
            }
            for c in 0..bins {
                let pj = self.joint[r * bins + c] / total;
                let pm = self.moving_marginal[c] / total;
                if pj > PROBABILITY_EPS && pm > PROBABILITY_EPS {
                    mi += pj * (pj.ln() - pm.ln() - pf.ln());
                }
            }
        }
        Ok(mi)
    }
}

/// Result of an MI translation registration.
#[derive(Clone, Debug, PartialEq)]
pub struct MiRegistration {
    /// Translation of the moving image relative to the fixed image, pixels (see the module doc).
    pub translation_px: [f64; 2],
    /// MI at the translation, nats.
    pub mi: f64,
    /// ES iterations run.
    pub iterations: usize,
    /// The ES stopped by its ε rule (rather than the iteration limit).
    pub converged: bool,
}

/// Register `moving` to `fixed` by a translation: Mattes MI maximised by the (1+1)-ES from `start_px`
/// (translation-only, unit scales, so `es.initial_radius` and `es.epsilon` are in pixels). Candidate
/// translations farther than `max_offset_px` from the start (per axis) or with too few landing samples count as
/// invalid (`None` to the ES). Errors if the metric cannot be set up or the start is invalid.
pub fn register_translation(
    fixed: &GrayImage,
    moving: &GrayImage,
    bins: usize,
    samples: Option<usize>,
    start_px: [f64; 2],
    max_offset_px: f64,
    es: &OnePlusOneParams,
) -> Result<MiRegistration, MiError> {
    let mut metric = MattesMi::new(fixed, moving, bins, samples, es.seed)?;
    maximize_translation(&mut metric, start_px, max_offset_px, es)
}

/// The (1+1)-ES part of [`register_translation`] on a prepared metric (so a caller that evaluates the metric
/// elsewhere too, e.g. an integer scan for the start, builds it once): MI maximised from `start_px`,
/// candidates farther than `max_offset_px` from the start (per axis) invalid. Errors if the start is invalid.
pub fn maximize_translation(
    metric: &mut MattesMi,
    start_px: [f64; 2],
    max_offset_px: f64,
    es: &OnePlusOneParams,
) -> Result<MiRegistration, MiError> {
    // The start must be valid: report its error rather than an ES failure.
    metric.evaluate(start_px[0], start_px[1])?;
    let result = minimize(
        |x: &[f64]| {
            if (x[0] - start_px[0]).abs() > max_offset_px
                || (x[1] - start_px[1]).abs() > max_offset_px
            {
                return None;
            }
            metric.evaluate(x[0], x[1]).ok().map(|mi| -mi)
        },
        &start_px,
        &[1.0, 1.0],
        es,
    );
    let Some(result) = result else {
        // Only possible if the start became invalid, which a deterministic metric cannot do; report it as such.
        return Err(metric
            .evaluate(start_px[0], start_px[1])
            .err()
            .unwrap_or(MiError::NonFiniteTranslation(start_px[0], start_px[1])));
    };
    Ok(MiRegistration {
        translation_px: [result.x[0], result.x[1]],
        mi: -result.value,
        iterations: result.iterations,
        converged: result.converged,
    })
}

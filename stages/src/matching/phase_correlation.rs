//! Phase correlation: translation between two images from the normalised cross-power spectrum
//! (thesis 3.4.5.3, eq. 3/1; Kuglin & Hines 1975, Reddy & Chatterji 1996; ALGORITHMS.md §4).
//!
//! Convention (same sign and axis order as OpenCV's `phaseCorrelate`): if `moving(x) = reference(x − t)`, i.e.
//! content at p in `reference` appears at p + t in `moving`, the result is `(dx, dy) = t` in pixels.
//! Steps: subtract each image's mean, multiply by a separable window (Hann by default), zero-pad to an FFT size
//! of the form 2^a·3^b·5^c, `Q = F_mov·conj(F_ref) / |F_mov·conj(F_ref)|`, optionally weighted by a Gaussian
//! low-pass (which turns the correlation peak into a sampled Gaussian of `lowpass_sigma_px`), inverse FFT,
//! integer peak, sub-pixel vertex of a second-order polynomial fitted to the 3 × 3 neighbourhood (on the
//! logarithm by default, exact for the Gaussian-shaped peak). Shifts are only defined modulo the padded size;
//! they are returned in `[−N/2, N/2)`. The estimate is then repeated with the moving image's window shifted
//! by the current estimate (`refinements`), which removes the bias a fixed window causes.
//!
//! FFT plans are cached per thread (rustfft's planner), so concurrent calls from rayon are fine and
//! deterministic.

use std::cell::RefCell;

use rustfft::num_complex::Complex;
use rustfft::{FftDirection, FftPlanner};
use thiserror::Error;

use super::subpixel::{refine_peak, PeakFit};
use crate::imaging::window::{window_value, WindowKind};
use crate::imaging::GrayImage;

/// Settings of [`phase_correlate`] and [`locate_template`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseCorrelationParams {
    /// Taper applied after mean removal (kills the wrap-around edge).
    pub window: WindowKind,
    /// σ (pixels) of the Gaussian low-pass applied to the cross-power spectrum; 0 disables it (the peak is then
    /// a Dirichlet kernel, which a quadratic fit locates with a bias of up to ~0.1 px).
    pub lowpass_sigma_px: f64,
    /// Surface the sub-pixel quadratic is fitted to.
    pub peak_fit: PeakFit,
    /// Re-estimations with the moving image's window re-centred on the content found so far. A window fixed
    /// in both frames correlates with itself and biases the shift towards zero (by ~10 % of the shift on
    /// textured images); moving it with the estimate removes that. 0 = single pass. Ignored for
    /// [`WindowKind::Rectangular`] (no taper: the images are treated as periodic).
    pub refinements: usize,
}

impl Default for PhaseCorrelationParams {
    fn default() -> Self {
        Self {
            window: WindowKind::Hann,
            lowpass_sigma_px: 1.0,
            peak_fit: PeakFit::LogQuadratic,
            refinements: 3,
        }
    }
}

/// Result of [`phase_correlate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseShift {
    /// Shift of `moving` relative to `reference` along u (pixels, + right).
    pub dx_px: f64,
    /// Shift along v (pixels, + down).
    pub dy_px: f64,
    /// Height of the correlation peak at its integer position, scaled so that identical images give 1.
    pub peak: f64,
}

/// Result of [`locate_template`]: where the template's centre lies in the search window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemplateLocation {
    /// Template centre in search-window pixel coordinates (continuous, pixel centres at +0.5).
    pub u_px: f64,
    pub v_px: f64,
    /// Correlation peak height (see [`PhaseShift::peak`]).
    pub peak: f64,
}

#[derive(Debug, Error, PartialEq)]
pub enum PhaseCorrelationError {
    #[error("phase correlation needs images of equal size, got {ref_w}×{ref_h} (reference) and {mov_w}×{mov_h} (moving)")]
    SizeMismatch {
        ref_w: usize,
        ref_h: usize,
        mov_w: usize,
        mov_h: usize,
    },
    #[error("phase correlation needs images of at least 3×3 pixels, got {width}×{height}")]
    TooSmall { width: usize, height: usize },
    #[error("template {t_w}×{t_h} does not fit into the search window {s_w}×{s_h}")]
    TemplateLarger {
        t_w: usize,
        t_h: usize,
        s_w: usize,
        s_h: usize,
    },
    #[error(
        "image contains non-finite values (NaN/inf); mask or fill them before phase correlation"
    )]
    NonFinite,
}

thread_local! {
    static PLANNER: RefCell<FftPlanner<f64>> = RefCell::new(FftPlanner::new());
}

/// Smallest n' ≥ n whose only prime factors are 2, 3 and 5 (sizes rustfft handles fastest).
pub fn fft_friendly_size(n: usize) -> usize {
    let mut m = n.max(1);
    loop {
        let mut r = m;
        for p in [2, 3, 5] {
            while r % p == 0 {
                r /= p;
            }
        }
        if r == 1 {
            return m;
        }
        m += 1;
    }
}

/// In-place 2-D FFT of a `w × h` row-major buffer; the result is left TRANSPOSED (`h`-long rows, `w` of them),
/// which is all the element-wise cross-power spectrum needs. `inverse_2d` undoes it.
fn forward_2d(buf: &mut Vec<Complex<f64>>, tmp: &mut Vec<Complex<f64>>, w: usize, h: usize) {
    fft_rows(buf, w, FftDirection::Forward);
    transpose(buf, tmp, w, h);
    std::mem::swap(buf, tmp);
    fft_rows(buf, h, FftDirection::Forward);
}

/// Inverse of [`forward_2d`] (input transposed, output `w × h` row-major), scaled by 1/(w·h).
fn inverse_2d(buf: &mut Vec<Complex<f64>>, tmp: &mut Vec<Complex<f64>>, w: usize, h: usize) {
    fft_rows(buf, h, FftDirection::Inverse);
    transpose(buf, tmp, h, w);
    std::mem::swap(buf, tmp);
    fft_rows(buf, w, FftDirection::Inverse);
    let s = 1.0 / (w * h) as f64;
    for v in buf.iter_mut() {
        *v *= s;
    }
}

fn fft_rows(buf: &mut [Complex<f64>], len: usize, dir: FftDirection) {
    let fft = PLANNER.with(|p| p.borrow_mut().plan_fft(len, dir));
    fft.process(buf);
}

/// `src` is `w × h` row-major; `dst` becomes `h × w` row-major (its transpose).
fn transpose(src: &[Complex<f64>], dst: &mut Vec<Complex<f64>>, w: usize, h: usize) {
    dst.clear();
    dst.resize(w * h, Complex::new(0.0, 0.0));
    for y in 0..h {
        for x in 0..w {
            dst[x * h + y] = src[y * w + x];
        }
    }
}

/// Where and how large the taper is, in the image's own pixel-index frame: the window's first sample sits at
/// continuous index `origin` (may be fractional or partly outside the image; outside the window weights are 0).
#[derive(Clone, Copy)]
struct Taper {
    kind: WindowKind,
    origin: (f64, f64),
    size: (usize, usize),
}

/// Windowed copy of `img` with the window-weighted mean removed, placed at (x0, y0) in a zero `pw × ph` canvas.
fn prepare(
    img: &GrayImage,
    taper: Taper,
    pw: usize,
    ph: usize,
    x0: usize,
    y0: usize,
) -> Vec<Complex<f64>> {
    let wx: Vec<f64> = (0..img.width)
        .map(|c| window_value(taper.kind, taper.size.0, c as f64 - taper.origin.0))
        .collect();
    let wy: Vec<f64> = (0..img.height)
        .map(|r| window_value(taper.kind, taper.size.1, r as f64 - taper.origin.1))
        .collect();
    let (mut sum_w, mut sum_wg) = (0.0f64, 0.0f64);
    for (row, &ky) in wy.iter().enumerate() {
        for (&g, &kx) in img.row(row).iter().zip(&wx) {
            sum_w += kx * ky;
            sum_wg += kx * ky * g as f64;
        }
    }
    let mean = if sum_w > 0.0 { sum_wg / sum_w } else { 0.0 };
    let mut out = vec![Complex::new(0.0, 0.0); pw * ph];
    for (row, &ky) in wy.iter().enumerate() {
        let src = img.row(row);
        let dst = &mut out[(y0 + row) * pw + x0..(y0 + row) * pw + x0 + img.width];
        for ((d, &s), &kx) in dst.iter_mut().zip(src).zip(&wx) {
            d.re = (s as f64 - mean) * kx * ky;
        }
    }
    out
}

/// Spectrum (transposed layout, see [`forward_2d`]) of a prepared `pw × ph` canvas.
fn spectrum(mut canvas: Vec<Complex<f64>>, pw: usize, ph: usize) -> Vec<Complex<f64>> {
    let mut tmp = Vec::with_capacity(pw * ph);
    forward_2d(&mut canvas, &mut tmp, pw, ph);
    canvas
}

/// Correlation surface (`pw × ph`, row-major, peak 1 for identical inputs) of the reference spectrum and a
/// prepared moving canvas.
fn correlation_surface(
    f_ref: &[Complex<f64>],
    moving: Vec<Complex<f64>>,
    pw: usize,
    ph: usize,
    lowpass_sigma_px: f64,
) -> Vec<f64> {
    let mut f_mov = moving;
    let mut tmp = Vec::with_capacity(pw * ph);
    forward_2d(&mut f_mov, &mut tmp, pw, ph);
    // Transposed layout: index kx·ph + ky.
    let max_abs = f_ref
        .iter()
        .zip(&f_mov)
        .map(|(a, b)| (b * a.conj()).norm())
        .fold(0.0f64, f64::max);
    let floor = (max_abs * 1e-12).max(f64::MIN_POSITIVE);
    let freq = |k: usize, n: usize| if 2 * k >= n { k as f64 - n as f64 } else { k as f64 } / n as f64;
    let s2 = 2.0 * std::f64::consts::PI.powi(2) * lowpass_sigma_px.max(0.0).powi(2);
    let mut weight_sum = 0.0f64;
    for kx in 0..pw {
        let fx = freq(kx, pw);
        for ky in 0..ph {
            let fy = freq(ky, ph);
            let i = kx * ph + ky;
            let cross = f_mov[i] * f_ref[i].conj();
            let mag = cross.norm();
            let weight = (-s2 * (fx * fx + fy * fy)).exp();
            weight_sum += weight;
            f_mov[i] = if mag > floor {
                cross * (weight / mag)
            } else {
                Complex::new(0.0, 0.0)
            };
        }
    }
    inverse_2d(&mut f_mov, &mut tmp, pw, ph);
    let norm = (pw * ph) as f64 / weight_sum;
    f_mov.iter().map(|c| c.re * norm).collect()
}

/// Integer peak (first maximum in raster order) and its sub-pixel refinement, wrapped to `[−N/2, N/2)`.
fn find_peak(r: &[f64], pw: usize, ph: usize, fit: PeakFit) -> PhaseShift {
    let mut best = 0usize;
    for (i, &v) in r.iter().enumerate() {
        if v > r[best] {
            best = i;
        }
    }
    let (px, py) = (best % pw, best / pw);
    let mut n = [[0.0f64; 3]; 3];
    for (j, row) in n.iter_mut().enumerate() {
        let y = (py + ph + j - 1) % ph;
        for (i, v) in row.iter_mut().enumerate() {
            let x = (px + pw + i - 1) % pw;
            *v = r[y * pw + x];
        }
    }
    let (dx, dy) = refine_peak(&n, fit);
    let wrap = |p: usize, n: usize| {
        if 2 * p >= n {
            p as f64 - n as f64
        } else {
            p as f64
        }
    };
    PhaseShift {
        dx_px: wrap(px, pw) + dx,
        dy_px: wrap(py, ph) + dy,
        peak: r[best],
    }
}

fn check_finite(img: &GrayImage) -> Result<(), PhaseCorrelationError> {
    if img.data.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(PhaseCorrelationError::NonFinite)
    }
}

/// Shift t of `moving` relative to `reference` (equal sizes): `moving(x) ≈ reference(x − t)`.
pub fn phase_correlate(
    reference: &GrayImage,
    moving: &GrayImage,
    params: &PhaseCorrelationParams,
) -> Result<PhaseShift, PhaseCorrelationError> {
    let (w, h) = (reference.width, reference.height);
    if (moving.width, moving.height) != (w, h) {
        return Err(PhaseCorrelationError::SizeMismatch {
            ref_w: w,
            ref_h: h,
            mov_w: moving.width,
            mov_h: moving.height,
        });
    }
    if w < 3 || h < 3 {
        return Err(PhaseCorrelationError::TooSmall {
            width: w,
            height: h,
        });
    }
    check_finite(reference)?;
    check_finite(moving)?;
    let (pw, ph) = (fft_friendly_size(w), fft_friendly_size(h));
    let full = Taper {
        kind: params.window,
        origin: (0.0, 0.0),
        size: (w, h),
    };
    let f_ref = spectrum(prepare(reference, full, pw, ph, 0, 0), pw, ph);
    let mut shift = PhaseShift {
        dx_px: 0.0,
        dy_px: 0.0,
        peak: 0.0,
    };
    let refinements = if params.window == WindowKind::Rectangular {
        0
    } else {
        params.refinements
    };
    for pass in 0..=refinements {
        // Pass 0: both windows in place; then the moving window follows the content found so far.
        let taper = Taper {
            origin: (shift.dx_px, shift.dy_px),
            ..full
        };
        let b = prepare(moving, taper, pw, ph, 0, 0);
        let r = correlation_surface(&f_ref, b, pw, ph, params.lowpass_sigma_px);
        let next = find_peak(&r, pw, ph, params.peak_fit);
        let converged =
            pass > 0 && (next.dx_px - shift.dx_px).hypot(next.dy_px - shift.dy_px) < 1e-3;
        shift = next;
        if converged {
            break;
        }
    }
    Ok(shift)
}

/// Locate a (smaller or equal) `template` inside `search` by phase correlation (thesis 3.4.5.3: MM template,
/// aerial search window). The windowed template is zero-padded to the search size, centred; the result is the
/// template centre in search coordinates (a template cut at pixel (x, y) has its centre at (x + w/2, y + h/2)).
pub fn locate_template(
    template: &GrayImage,
    search: &GrayImage,
    params: &PhaseCorrelationParams,
) -> Result<TemplateLocation, PhaseCorrelationError> {
    let (tw, th, sw, sh) = (template.width, template.height, search.width, search.height);
    if tw > sw || th > sh {
        return Err(PhaseCorrelationError::TemplateLarger {
            t_w: tw,
            t_h: th,
            s_w: sw,
            s_h: sh,
        });
    }
    if tw < 3 || th < 3 {
        return Err(PhaseCorrelationError::TooSmall {
            width: tw,
            height: th,
        });
    }
    check_finite(template)?;
    check_finite(search)?;
    let (pw, ph) = (fft_friendly_size(sw), fft_friendly_size(sh));
    let (ox, oy) = ((sw - tw) / 2, (sh - th) / 2);
    let a = prepare(
        template,
        Taper {
            kind: params.window,
            origin: (0.0, 0.0),
            size: (tw, th),
        },
        pw,
        ph,
        ox,
        oy,
    );
    let f_ref = spectrum(a, pw, ph);
    let mut shift = PhaseShift {
        dx_px: 0.0,
        dy_px: 0.0,
        peak: 0.0,
    };
    let refinements = if params.window == WindowKind::Rectangular {
        0
    } else {
        params.refinements
    };
    for pass in 0..=refinements {
        // Pass 0: the whole search window tapered; then a template-sized taper on the content found so far.
        let taper = if pass == 0 {
            Taper {
                kind: params.window,
                origin: (0.0, 0.0),
                size: (sw, sh),
            }
        } else {
            Taper {
                kind: params.window,
                origin: (ox as f64 + shift.dx_px, oy as f64 + shift.dy_px),
                size: (tw, th),
            }
        };
        let b = prepare(search, taper, pw, ph, 0, 0);
        let r = correlation_surface(&f_ref, b, pw, ph, params.lowpass_sigma_px);
        let next = find_peak(&r, pw, ph, params.peak_fit);
        let converged =
            pass > 0 && (next.dx_px - shift.dx_px).hypot(next.dy_px - shift.dy_px) < 1e-3;
        shift = next;
        if converged {
            break;
        }
    }
    Ok(TemplateLocation {
        u_px: ox as f64 + tw as f64 / 2.0 + shift.dx_px,
        v_px: oy as f64 + th as f64 / 2.0 + shift.dy_px,
        peak: shift.peak,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn friendly_sizes() {
        assert_eq!(fft_friendly_size(64), 64);
        assert_eq!(fft_friendly_size(97), 100);
        assert_eq!(fft_friendly_size(121), 125);
        assert_eq!(fft_friendly_size(7), 8);
        assert_eq!(fft_friendly_size(0), 1);
    }

    #[test]
    fn fft_round_trip_is_identity() {
        let (w, h) = (6, 5);
        let orig: Vec<Complex<f64>> = (0..w * h)
            .map(|k| Complex::new((k * 7 % 11) as f64, 0.0))
            .collect();
        let mut buf = orig.clone();
        let mut tmp = Vec::new();
        forward_2d(&mut buf, &mut tmp, w, h);
        // DC term equals the sum.
        assert!((buf[0].re - orig.iter().map(|c| c.re).sum::<f64>()).abs() < 1e-9);
        inverse_2d(&mut buf, &mut tmp, w, h);
        for (a, b) in buf.iter().zip(&orig) {
            assert!((a - b).norm() < 1e-9);
        }
    }

    #[test]
    fn errors_are_reported() {
        let a = GrayImage::filled(8, 8, 0.0);
        let b = GrayImage::filled(8, 9, 0.0);
        let p = PhaseCorrelationParams::default();
        assert!(matches!(
            phase_correlate(&a, &b, &p),
            Err(PhaseCorrelationError::SizeMismatch { .. })
        ));
        assert!(matches!(
            locate_template(&b, &a, &p),
            Err(PhaseCorrelationError::TemplateLarger { .. })
        ));
        let mut c = a.clone();
        c.data[3] = f32::NAN;
        assert_eq!(
            phase_correlate(&a, &c, &p),
            Err(PhaseCorrelationError::NonFinite)
        );
        // Flat images: no NaN, some finite answer.
        let s = phase_correlate(&a, &a, &p).unwrap();
        assert!(s.dx_px.is_finite() && s.dy_px.is_finite() && s.peak.is_finite());
    }
}

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
//! For repeated use, [`PhaseCorrelator`] holds the rustfft plans, the window and low-pass tables and every
//! buffer for one image size, so a call allocates nothing; the free functions [`phase_correlate`] and
//! [`locate_template`] use a small per-thread cache of correlators, so concurrent calls from rayon are fine and
//! deterministic. The 2-D FFTs run on the half spectrum of the real images (`real_fft_2d`).

mod real_fft_2d;

use std::cell::RefCell;

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use thiserror::Error;

use real_fft_2d::{Cplx, Real, RealFft2d};

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
    #[error("this phase correlator was built for {expected_w}×{expected_h} images, got {got_w}×{got_h}; build one per size")]
    CorrelatorSize {
        expected_w: usize,
        expected_h: usize,
        got_w: usize,
        got_h: usize,
    },
}

thread_local! {
    static PLANNER: RefCell<FftPlanner<Real>> = RefCell::new(FftPlanner::new());
    static CORRELATORS: RefCell<Vec<PhaseCorrelator>> = const { RefCell::new(Vec::new()) };
}

/// Correlators kept per thread by the free functions (one per image size and parameter set, oldest dropped).
const CACHED_CORRELATORS: usize = 8;

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

/// Where and how large the taper is, in the image's own pixel-index frame: the window's first sample sits at
/// continuous index `origin` (may be fractional or partly outside the image; outside the window weights are 0).
#[derive(Clone, Copy)]
struct Taper {
    kind: WindowKind,
    origin: (f64, f64),
    size: (usize, usize),
}

/// Phase correlation for one image size with everything a call needs prepared once: rustfft plans, the
/// low-pass table and all buffers (no allocation per call). Use one per thread (it is `Send`, not shared);
/// results are identical to [`phase_correlate`] / [`locate_template`] with the same parameters.
pub struct PhaseCorrelator {
    width: usize,
    height: usize,
    params: PhaseCorrelationParams,
    pw: usize,
    ph: usize,
    fft: RealFft2d,
    /// Gaussian low-pass weight per half-spectrum bin divided by the weight sum over the full spectrum; the
    /// division also scales the unnormalised inverse FFT so that identical images give a peak of 1.
    lowpass: Vec<Real>,
    ref_spectrum: Vec<Cplx>,
    spectrum: Vec<Cplx>,
    surface: Vec<Real>,
    window_x: WindowTable,
    window_y: WindowTable,
}

impl PhaseCorrelator {
    /// A correlator for `width × height` images ([`Self::correlate`]) or search windows
    /// ([`Self::locate_template`]); both must be ≥ 3.
    pub fn new(
        width: usize,
        height: usize,
        params: PhaseCorrelationParams,
    ) -> Result<Self, PhaseCorrelationError> {
        if width < 3 || height < 3 {
            return Err(PhaseCorrelationError::TooSmall { width, height });
        }
        let (pw, ph) = (fft_friendly_size(width), fft_friendly_size(height));
        let fft = PLANNER.with(|p| RealFft2d::new(pw, ph, &mut p.borrow_mut()));
        let hw = fft.half_width();
        // Signed frequency in cycles per pixel.
        let freq = |k: usize, n: usize| if 2 * k >= n { k as f64 - n as f64 } else { k as f64 } / n as f64;
        let s2 = 2.0 * std::f64::consts::PI.powi(2) * params.lowpass_sigma_px.max(0.0).powi(2);
        let weight = |kx: usize, ky: usize| {
            let (fx, fy) = (freq(kx, pw), freq(ky, ph));
            (-s2 * (fx * fx + fy * fy)).exp()
        };
        let mut weight_sum = 0.0f64;
        for ky in 0..ph {
            for kx in 0..pw {
                weight_sum += weight(kx, ky);
            }
        }
        let mut lowpass = vec![0.0; hw * ph];
        for kx in 0..hw {
            for ky in 0..ph {
                lowpass[kx * ph + ky] = (weight(kx, ky) / weight_sum) as Real;
            }
        }
        let zero = Complex::new(0.0, 0.0);
        Ok(Self {
            width,
            height,
            params,
            pw,
            ph,
            lowpass,
            ref_spectrum: vec![zero; fft.spectrum_len()],
            spectrum: vec![zero; fft.spectrum_len()],
            surface: vec![0.0; pw * ph],
            window_x: WindowTable::with_capacity(width),
            window_y: WindowTable::with_capacity(height),
            fft,
        })
    }

    /// Image (or search-window) width this correlator was built for.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Image (or search-window) height this correlator was built for.
    pub fn height(&self) -> usize {
        self.height
    }

    pub fn params(&self) -> &PhaseCorrelationParams {
        &self.params
    }

    /// Shift t of `moving` relative to `reference` (both `width × height`): `moving(x) ≈ reference(x − t)`.
    /// Same result as [`phase_correlate`].
    pub fn correlate(
        &mut self,
        reference: &GrayImage,
        moving: &GrayImage,
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
        self.check_size(w, h)?;
        check_finite(reference)?;
        check_finite(moving)?;
        let full = Taper {
            kind: self.params.window,
            origin: (0.0, 0.0),
            size: (w, h),
        };
        self.load(reference, full, 0, 0);
        self.fft.forward(&mut self.ref_spectrum);
        // Pass 0: both windows in place; then the moving window follows the content found so far.
        Ok(self.refine(moving, full, |dx, dy| Taper {
            origin: (dx, dy),
            ..full
        }))
    }

    /// Centre of `template` (at most `width × height`) in `search` (`width × height`); same result as
    /// [`locate_template`].
    pub fn locate_template(
        &mut self,
        template: &GrayImage,
        search: &GrayImage,
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
        self.check_size(sw, sh)?;
        check_finite(template)?;
        check_finite(search)?;
        let (ox, oy) = ((sw - tw) / 2, (sh - th) / 2);
        let kind = self.params.window;
        let template_taper = Taper {
            kind,
            origin: (0.0, 0.0),
            size: (tw, th),
        };
        self.load(template, template_taper, ox, oy);
        self.fft.forward(&mut self.ref_spectrum);
        // Pass 0: the whole search window tapered; then a template-sized taper on the content found so far.
        let whole = Taper {
            kind,
            origin: (0.0, 0.0),
            size: (sw, sh),
        };
        let shift = self.refine(search, whole, |dx, dy| Taper {
            kind,
            origin: (ox as f64 + dx, oy as f64 + dy),
            size: (tw, th),
        });
        Ok(TemplateLocation {
            u_px: ox as f64 + tw as f64 / 2.0 + shift.dx_px,
            v_px: oy as f64 + th as f64 / 2.0 + shift.dy_px,
            peak: shift.peak,
        })
    }

    fn check_size(&self, w: usize, h: usize) -> Result<(), PhaseCorrelationError> {
        if (w, h) == (self.width, self.height) {
            Ok(())
        } else {
            Err(PhaseCorrelationError::CorrelatorSize {
                expected_w: self.width,
                expected_h: self.height,
                got_w: w,
                got_h: h,
            })
        }
    }

    /// The estimate loop shared by both entry points (the reference spectrum is already in place): pass 0 with
    /// the `first` taper on `moving`, then up to `refinements` passes with `follow(dx, dy)` re-centred on the
    /// shift found so far, until it changes by less than 1e-3 px.
    fn refine(
        &mut self,
        moving: &GrayImage,
        first: Taper,
        follow: impl Fn(f64, f64) -> Taper,
    ) -> PhaseShift {
        let refinements = if self.params.window == WindowKind::Rectangular {
            0
        } else {
            self.params.refinements
        };
        let mut shift = PhaseShift {
            dx_px: 0.0,
            dy_px: 0.0,
            peak: 0.0,
        };
        for pass in 0..=refinements {
            let taper = if pass == 0 {
                first
            } else {
                follow(shift.dx_px, shift.dy_px)
            };
            self.load(moving, taper, 0, 0);
            self.fft.forward(&mut self.spectrum);
            self.normalised_cross_power();
            self.fft.inverse(&mut self.spectrum, &mut self.surface);
            let next = find_peak(&self.surface, self.pw, self.ph, self.params.peak_fit);
            let converged =
                pass > 0 && (next.dx_px - shift.dx_px).hypot(next.dy_px - shift.dy_px) < 1e-3;
            shift = next;
            if converged {
                break;
            }
        }
        shift
    }

    /// Writes the windowed copy of `img` with the window-weighted mean removed at (x0, y0) into the zeroed FFT
    /// canvas.
    fn load(&mut self, img: &GrayImage, taper: Taper, x0: usize, y0: usize) {
        self.window_x
            .fill(img.width, taper.kind, taper.size.0, taper.origin.0);
        self.window_y
            .fill(img.height, taper.kind, taper.size.1, taper.origin.1);
        let (wx, wy) = (&self.window_x.values, &self.window_y.values);
        let sum_w: f64 = wx.iter().sum::<f64>() * wy.iter().sum::<f64>();
        let mut sum_wg = 0.0f64;
        for (row, &ky) in wy.iter().enumerate() {
            if ky != 0.0 {
                let s: f64 = img
                    .row(row)
                    .iter()
                    .zip(wx)
                    .map(|(&g, &kx)| kx * g as f64)
                    .sum();
                sum_wg += ky * s;
            }
        }
        let mean = if sum_w > 0.0 { sum_wg / sum_w } else { 0.0 };
        self.fft.clear_input();
        for (row, &ky) in wy.iter().enumerate() {
            if ky != 0.0 {
                let values = img
                    .row(row)
                    .iter()
                    .zip(wx)
                    .map(|(&s, &kx)| ((s as f64 - mean) * kx * ky) as Real);
                self.fft.set_row(y0 + row, x0, values);
            }
        }
    }

    /// `spectrum ← F_mov·conj(F_ref) / |F_mov·conj(F_ref)| · low-pass` (thesis eq. 3/1), bins whose magnitude is
    /// not above 1e-12 of the largest set to 0. Magnitudes via `sqrt(re² + im²)` (no `hypot`: the spectra are
    /// far from overflow, and `hypot` dominated the run time).
    fn normalised_cross_power(&mut self) {
        let mut max_sq: Real = 0.0;
        for (m, r) in self.spectrum.iter_mut().zip(&self.ref_spectrum) {
            *m *= r.conj();
            max_sq = max_sq.max(m.norm_sqr());
        }
        let floor = max_sq.sqrt() * 1e-12;
        let floor_sq = floor * floor;
        // Branch-free select so that the loop vectorises.
        for (m, &weight) in self.spectrum.iter_mut().zip(&self.lowpass) {
            let mag_sq = m.norm_sqr();
            let scale = weight / mag_sq.sqrt();
            *m *= if mag_sq > floor_sq { scale } else { 0.0 };
        }
    }
}

/// A 1-D window table `values[c] = window(c − origin)`, `c ∈ [0, n)` (0 outside the window), remembering what it
/// was filled for so that an unchanged taper costs no cosines.
struct WindowTable {
    values: Vec<f64>,
    key: Option<(usize, WindowKind, usize, u64)>,
}

impl WindowTable {
    fn with_capacity(n: usize) -> Self {
        Self {
            values: Vec::with_capacity(n),
            key: None,
        }
    }

    fn fill(&mut self, n: usize, kind: WindowKind, size: usize, origin: f64) {
        let key = Some((n, kind, size, origin.to_bits()));
        if self.key != key {
            self.values.clear();
            self.values
                .extend((0..n).map(|c| window_value(kind, size, c as f64 - origin)));
            self.key = key;
        }
    }
}

/// Integer peak (first maximum in raster order) and its sub-pixel refinement, wrapped to `[−N/2, N/2)`.
fn find_peak(r: &[Real], pw: usize, ph: usize, fit: PeakFit) -> PhaseShift {
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
            *v = r[y * pw + x] as f64;
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
        peak: r[best] as f64,
    }
}

fn check_finite(img: &GrayImage) -> Result<(), PhaseCorrelationError> {
    if img.data.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(PhaseCorrelationError::NonFinite)
    }
}

/// Runs `f` on this thread's cached correlator for (`width`, `height`, `params`), building it if needed.
fn with_cached_correlator<R>(
    width: usize,
    height: usize,
    params: &PhaseCorrelationParams,
    f: impl FnOnce(&mut PhaseCorrelator) -> Result<R, PhaseCorrelationError>,
) -> Result<R, PhaseCorrelationError> {
    CORRELATORS.with(|cell| {
        let mut cache = cell.borrow_mut();
        let found = cache
            .iter()
            .position(|c| (c.width, c.height) == (width, height) && c.params == *params);
        let index = match found {
            Some(i) => i,
            None => {
                if cache.len() >= CACHED_CORRELATORS {
                    cache.remove(0);
                }
                cache.push(PhaseCorrelator::new(width, height, *params)?);
                cache.len() - 1
            }
        };
        f(&mut cache[index])
    })
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
    with_cached_correlator(w, h, params, |c| c.correlate(reference, moving))
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
    with_cached_correlator(sw, sh, params, |c| c.locate_template(template, search))
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

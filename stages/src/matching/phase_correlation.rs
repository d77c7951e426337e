//! Phase correlation: translation between two images from the normalised cross-power spectrum
//! (thesis 3.4.5.3, eq. 3/1; Kuglin & Hines 1975; Reddy & Chatterji 1996).
//!
//! Convention (same sign and axis order as OpenCV's `phaseCorrelate`): if `moving(x) = reference(x − t)`, i.e.
//! content at p in `reference` appears at p + t in `moving`, the result is `(dx, dy) = t` in pixels.
//! Steps: subtract each image's mean, multiply by a separable window (Hann by default), zero-pad to an FFT size
//! of the form 2^a·3^b·5^c, `Q = F_mov·conj(F_ref) / |F_mov·conj(F_ref)|`, optionally weighted by a Gaussian
//! low-pass (which turns the correlation peak into a sampled Gaussian of `lowpass_sigma_px`), inverse FFT,
//! integer peak, sub-pixel vertex of a second-order polynomial fitted to the 3 × 3 neighbourhood (on the
//! logarithm by default, exact for the Gaussian-shaped peak). Shifts are only defined modulo the padded size;
//! they are returned in `[−N/2, N/2)`. The estimate is then repeated with the moving image's window shifted
//! by the current estimate (`refinements`, default 1), which removes the bias a fixed window causes. A
//! refinement pass needs the surface only next to the known peak: it evaluates the inverse DFT directly on the
//! 3 × 3 pixels around the previous estimate (the matrix-multiply DFT of Guizar-Sicairos, Thurman & Fienup
//! 2008, at upsampling 1; re-centred while a neighbour is higher), not a full inverse FFT and peak scan.
//!
//! For repeated use, [`PhaseCorrelator`] holds the rustfft plans, the window and low-pass tables and every
//! buffer for one image size, so a call allocates nothing; the free functions [`phase_correlate`] and
//! [`locate_template`] use a small per-thread cache of correlators, so concurrent calls from rayon are fine and
//! deterministic. The 2-D FFTs run on the half spectrum of the real images (`real_fft_2d`). Cost per call:
//! three forward half-spectrum FFTs (reference, moving in pass 0 and in the refinement), one inverse, two
//! cross-power normalisations and the 3 × 3 evaluation; measured against `cv2.phaseCorrelate` in
//! `benches/README.md`.

mod peak;
mod real_fft_2d;
mod windowed_load;

use std::cell::RefCell;

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use thiserror::Error;

use peak::{find_peak, peak_from_neighbourhood, LocalSurface};
use real_fft_2d::{Cplx, Real, RealFft2d};
use windowed_load::{load, TaperTables};

use super::subpixel::PeakFit;
use crate::imaging::window::WindowKind;
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
    /// textured images); moving it with the estimate removes that. 0 = single pass. Stops early once the
    /// estimate changes by less than 1e-3 px. Ignored for [`WindowKind::Rectangular`] (no taper: the images are
    /// treated as periodic). Default 1: on the `phasecorr` bench pairs a second re-estimation moves the result
    /// by at most 0.0018 px at 64² and 0.00014 px at 128² (RMS error unchanged to 1e-4 px) and by at most
    /// 0.018 px at 32² (RMS 0.0625 → 0.0612 px), i.e. each pass shrinks the remaining bias ~50× at 64², 10–20×
    /// at 32².
    pub refinements: usize,
}

impl Default for PhaseCorrelationParams {
    fn default() -> Self {
        Self {
            window: WindowKind::Hann,
            lowpass_sigma_px: 1.0,
            peak_fit: PeakFit::LogQuadratic,
            refinements: 1,
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
            while r.is_multiple_of(p) {
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
/// low-pass table, window tables, twiddles and all buffers (no allocation per call). Use one per thread (it is
/// `Send`, not shared); results are identical to [`phase_correlate`] / [`locate_template`] with the same
/// parameters.
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
    /// Spectrum of the current reference (shared by all passes of a call) and its energy Σ v².
    ref_spectrum: Vec<Cplx>,
    ref_energy: Real,
    spectrum: Vec<Cplx>,
    surface: Vec<Real>,
    /// Tapers of the reference, of the first pass on the moving image and of the passes that follow the
    /// estimate: separate tables, so the first two are computed once per correlator, not per call.
    ref_taper: TaperTables,
    first_taper: TaperTables,
    follow_taper: TaperTables,
    local: LocalSurface,
}

/// Defines the public method `$name(&mut self, …)` that runs `$imp` compiled with AVX2 (through `$avx`) when
/// the CPU has it, and plainly otherwise. AVX2 only widens the vectors of the loading, packing, normalisation
/// and 3 × 3 loops (no FMA), so every operation and hence every result is the same either way.
macro_rules! avx2_dispatch {
    (
        $(#[$meta:meta])*
        pub fn $name:ident / $avx:ident => $imp:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty
    ) => {
        $(#[$meta])*
        pub fn $name(&mut self, $($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2 (checked just above).
                return unsafe { self.$avx($($arg),*) };
            }
            self.$imp($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        unsafe fn $avx(&mut self, $($arg: $ty),*) -> $ret {
            self.$imp($($arg),*)
        }
    };
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
            ref_energy: 0.0,
            spectrum: vec![zero; fft.spectrum_len()],
            surface: vec![0.0; pw * ph],
            ref_taper: TaperTables::new(width),
            first_taper: TaperTables::new(width),
            follow_taper: TaperTables::new(width),
            local: LocalSurface::new(pw, ph, hw),
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

    avx2_dispatch! {
        /// Shift t of `moving` relative to `reference` (both `width × height`): `moving(x) ≈ reference(x − t)`.
        /// Same result as [`phase_correlate`].
        pub fn correlate / correlate_avx2 => correlate_impl(
            reference: &GrayImage,
            moving: &GrayImage,
        ) -> Result<PhaseShift, PhaseCorrelationError>
    }

    #[inline(always)]
    fn correlate_impl(
        &mut self,
        reference: &GrayImage,
        moving: &GrayImage,
    ) -> Result<PhaseShift, PhaseCorrelationError> {
        let (w, h) = (reference.width, reference.height);
        check_same_size(reference, moving)?;
        self.check_size(w, h)?;
        check_finite(reference)?;
        check_finite(moving)?;
        let full = Taper {
            kind: self.params.window,
            origin: (0.0, 0.0),
            size: (w, h),
        };
        self.set_reference(reference, full, 0, 0);
        // Pass 0: both windows in place; then the moving window follows the content found so far.
        Ok(self.estimate(moving, full, |dx, dy| Taper {
            origin: (dx, dy),
            ..full
        }))
    }

    avx2_dispatch! {
        /// Centre of `template` (at most `width × height`) in `search` (`width × height`); same result as
        /// [`locate_template`].
        pub fn locate_template / locate_template_avx2 => locate_template_impl(
            template: &GrayImage,
            search: &GrayImage,
        ) -> Result<TemplateLocation, PhaseCorrelationError>
    }

    #[inline(always)]
    fn locate_template_impl(
        &mut self,
        template: &GrayImage,
        search: &GrayImage,
    ) -> Result<TemplateLocation, PhaseCorrelationError> {
        let (tw, th, sw, sh) = (template.width, template.height, search.width, search.height);
        check_template_fits(template, search)?;
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
        self.set_reference(template, template_taper, ox, oy);
        // Pass 0: the whole search window tapered; then a template-sized taper on the content found so far.
        let whole = Taper {
            kind,
            origin: (0.0, 0.0),
            size: (sw, sh),
        };
        let shift = self.estimate(search, whole, |dx, dy| Taper {
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

    /// Transforms the tapered reference (placed at (x0, y0) in the canvas) into `ref_spectrum`.
    #[inline(always)]
    fn set_reference(&mut self, img: &GrayImage, taper: Taper, x0: usize, y0: usize) {
        self.ref_energy = load(&mut self.fft, &mut self.ref_taper, img, taper, x0, y0);
        self.fft.forward(&mut self.ref_spectrum);
    }

    /// The estimate shared by both entry points (the reference spectrum is already in place). Pass 0: the
    /// `first` taper on `moving`, full inverse FFT, global integer peak. Then up to `refinements` passes with
    /// `follow(dx, dy)` re-centred on the shift found so far, until it changes by less than 1e-3 px; these only
    /// evaluate the surface on the 3 × 3 pixels around the expected peak by a direct inverse DFT
    /// ([`LocalSurface`]), walking to a higher neighbour if the centre is not the maximum.
    #[inline(always)]
    fn estimate(
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
        let energy = load(&mut self.fft, &mut self.first_taper, moving, first, 0, 0);
        self.cross_power(energy);
        self.fft.inverse(&mut self.spectrum, &mut self.surface);
        let mut shift = find_peak(&self.surface, self.pw, self.ph, self.params.peak_fit);
        for _ in 0..refinements {
            let taper = follow(shift.dx_px, shift.dy_px);
            let energy = load(&mut self.fft, &mut self.follow_taper, moving, taper, 0, 0);
            self.cross_power(energy);
            let next = self.local_peak(shift);
            let converged = (next.dx_px - shift.dx_px).hypot(next.dy_px - shift.dy_px) < 1e-3;
            shift = next;
            if converged {
                break;
            }
        }
        shift
    }

    /// Forward FFT of the loaded moving image (canvas energy `energy`), then
    /// `spectrum ← P·lowpass/|P|`, `P = F_mov·conj(F_ref)` (thesis eq. 3/1). Bins with `|P|` not above 1e-12 of
    /// the product of both spectra's RMS bin magnitudes (`sqrt(energy)`, Parseval) are set to 0. Magnitudes via
    /// `sqrt(re² + im²)` (no `hypot`: the spectra are far from overflow, and `hypot` dominated the run time).
    #[inline(always)]
    fn cross_power(&mut self, energy: Real) {
        self.fft.forward(&mut self.spectrum);
        let floor_sq = energy * self.ref_energy * 1e-24;
        for ((m, r), &weight) in self
            .spectrum
            .iter_mut()
            .zip(&self.ref_spectrum)
            .zip(&self.lowpass)
        {
            let p = *m * r.conj();
            let q = p.norm_sqr();
            let s = weight / q.sqrt();
            *m = p * if q > floor_sq { s } else { 0.0 };
        }
    }

    /// Peak of the current cross-power spectrum near `guess` (a previous estimate of the same shift): the
    /// surface on the 3 × 3 pixels around the rounded guess, re-centred on the highest of them until the
    /// centre is the maximum (at most 4 steps, else the full surface as in pass 0).
    #[inline(always)]
    fn local_peak(&mut self, guess: PhaseShift) -> PhaseShift {
        let (pw, ph) = (self.pw, self.ph);
        let to_index = |v: f64, n: usize| (v.round() as i64).rem_euclid(n as i64) as usize;
        let (mut cx, mut cy) = (to_index(guess.dx_px, pw), to_index(guess.dy_px, ph));
        for _ in 0..4 {
            let n = self.local.surface_3x3(&self.spectrum, cx, cy);
            let (mut bi, mut bj) = (1, 1);
            for (j, row) in n.iter().enumerate() {
                for (i, &v) in row.iter().enumerate() {
                    if v > n[bj][bi] {
                        (bi, bj) = (i, j);
                    }
                }
            }
            if (bi, bj) == (1, 1) {
                return peak_from_neighbourhood(&n, cx, cy, pw, ph, self.params.peak_fit);
            }
            cx = (cx + pw + bi - 1) % pw;
            cy = (cy + ph + bj - 1) % ph;
        }
        self.fft.inverse(&mut self.spectrum, &mut self.surface);
        find_peak(&self.surface, pw, ph, self.params.peak_fit)
    }
}

#[inline(always)]
fn check_finite(img: &GrayImage) -> Result<(), PhaseCorrelationError> {
    // A value is NaN or ±inf iff all its exponent bits are set; an integer OR over 0/1 flags vectorises.
    const EXPONENT: u32 = 0x7f80_0000;
    let non_finite = img.data.iter().fold(0u32, |acc, v| {
        acc | u32::from(v.to_bits() & EXPONENT == EXPONENT)
    });
    if non_finite == 0 {
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
    check_same_size(reference, moving)?;
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
    let (sw, sh) = (search.width, search.height);
    check_template_fits(template, search)?;
    with_cached_correlator(sw, sh, params, |c| c.locate_template(template, search))
}

/// `Err` unless `moving` has the size of `reference`.
fn check_same_size(reference: &GrayImage, moving: &GrayImage) -> Result<(), PhaseCorrelationError> {
    if (moving.width, moving.height) != (reference.width, reference.height) {
        return Err(PhaseCorrelationError::SizeMismatch {
            ref_w: reference.width,
            ref_h: reference.height,
            mov_w: moving.width,
            mov_h: moving.height,
        });
    }
    Ok(())
}

/// `Err` unless `template` fits into `search` and is at least 3 × 3 pixels.
fn check_template_fits(
    template: &GrayImage,
    search: &GrayImage,
) -> Result<(), PhaseCorrelationError> {
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
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn friendly_sizes() {
        for (n, friendly) in [(64, 64), (97, 100), (121, 125), (7, 8), (0, 1)] {
            assert_eq!(fft_friendly_size(n), friendly, "size {n}");
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

    #[test]
    fn avx2_and_baseline_builds_give_identical_results() {
        let img = |w: usize, h: usize, phase: f32| {
            let data = (0..w * h)
                .map(|k| {
                    let (x, y) = ((k % w) as f32, (k / w) as f32);
                    0.5 + 0.2 * (0.31 * x + 0.17 * y + phase).sin() + 0.1 * (0.07 * x * y).cos()
                })
                .collect();
            GrayImage::from_vec(w, h, data).unwrap()
        };
        let p = PhaseCorrelationParams::default();
        for (w, h) in [(32, 32), (45, 37), (64, 48)] {
            let (a, b) = (img(w, h, 0.0), img(w, h, 0.9));
            let mut c = PhaseCorrelator::new(w, h, p).unwrap();
            let dispatched = c.correlate(&a, &b).unwrap();
            let baseline = c.correlate_impl(&a, &b).unwrap();
            assert_eq!(dispatched, baseline, "{w}x{h}");
            let t = img(w / 2, h / 2, 0.4);
            let dispatched = c.locate_template(&t, &b).unwrap();
            let baseline = c.locate_template_impl(&t, &b).unwrap();
            assert_eq!(dispatched, baseline, "{w}x{h} template");
        }
    }
}

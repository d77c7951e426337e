//! Known-answer tests of phase correlation (Kuglin & Hines 1975; Reddy & Chatterji 1996, thesis 3.4.5.3).
//!
//! Shifted images are produced by exact Fourier shift: the test texture is a sum of sinusoids that are periodic
//! over the texture size, evaluated analytically at the translated pixel centres (see `imaging_support`).

mod imaging_support;

use imaging_support::{radiometric, SplitMix64, Texture};
use skytie_stages::imaging::window::WindowKind;
use skytie_stages::imaging::GrayImage;
use skytie_stages::matching::phase_correlation::{
    locate_template, phase_correlate, PhaseCorrelationParams, PhaseShift,
};
use skytie_stages::matching::subpixel::PeakFit;

/// Default parameters without the spatial window (a rectangular one): circular shifts stay exact.
fn unwindowed() -> PhaseCorrelationParams {
    PhaseCorrelationParams {
        window: WindowKind::Rectangular,
        ..Default::default()
    }
}

/// A `size × size` crop of `tex` at `origin` and the same crop with its content moved by `shift` px.
fn shifted_pair(
    tex: &Texture,
    size: usize,
    (x0, y0): (f64, f64),
    (tx, ty): (f64, f64),
) -> (GrayImage, GrayImage) {
    (
        tex.render(size, size, x0, y0, 0.0, 0.0),
        tex.render(size, size, x0, y0, tx, ty),
    )
}

/// Asserts that `s` is the shift `want` (dx, dy) within `tol_px` on each axis.
fn assert_shift(s: &PhaseShift, want: (f64, f64), tol_px: f64) {
    assert!(
        (s.dx_px - want.0).abs() < tol_px && (s.dy_px - want.1).abs() < tol_px,
        "{s:?} vs {want:?}"
    );
}

/// A 128 × 128 crop of the periodic texture of `seed`, the same crop circularly shifted by `shift` px, and their
/// unwindowed phase correlation.
fn circular_pair(seed: u64, shift: (f64, f64)) -> (GrayImage, GrayImage, PhaseShift) {
    let tex = Texture::new(128, 32, seed);
    let (f1, f2) = shifted_pair(&tex, 128, (0.0, 0.0), shift);
    let s = phase_correlate(&f1, &f2, &unwindowed()).unwrap();
    (f1, f2, s)
}

#[test]
fn integer_circular_shift_gives_exact_peak() {
    let (f1, f2, s) = circular_pair(1, (5.0, -3.0));
    assert_shift(&s, (5.0, -3.0), 1e-6);
    assert!(s.peak > 0.2, "{s:?}");
    // Windowed: the taper cuts the circularly wrapped seam differently in both images, so only the integer
    // peak is exact; the sub-pixel part stays small.
    let s = phase_correlate(&f1, &f2, &PhaseCorrelationParams::default()).unwrap();
    assert_eq!((s.dx_px.round(), s.dy_px.round()), (5.0, -3.0), "{s:?}");
    assert_shift(&s, (5.0, -3.0), 0.05);
}

#[test]
fn circular_fourier_shift_is_recovered() {
    let (f1, f2, s) = circular_pair(2, (2.3, -1.7));
    assert_shift(&s, (2.3, -1.7), 0.02);
    // Plain quadratic on the unweighted spectrum (thesis' fit): the bound of 0.15 px.
    let p = PhaseCorrelationParams {
        window: WindowKind::Rectangular,
        lowpass_sigma_px: 0.0,
        peak_fit: PeakFit::Quadratic,
        refinements: 0,
    };
    let s = phase_correlate(&f1, &f2, &p).unwrap();
    assert_shift(&s, (2.3, -1.7), 0.15);
}

/// RMS error over random sub-pixel shifts of crops (non-circular content) with gain/offset/gamma and noise.
fn rms_error(size: usize, trials: usize, noise_std: f64, seed: u64) -> f64 {
    let tex = Texture::new(512, 128, seed);
    let mut rng = SplitMix64(seed ^ 0xABCD);
    let p = PhaseCorrelationParams::default();
    let mut sum_sq = 0.0;
    for trial in 0..trials {
        let (tx, ty) = (rng.range(-4.0, 4.0), rng.range(-4.0, 4.0));
        let (x0, y0) = (rng.range(0.0, 300.0).floor(), rng.range(0.0, 300.0).floor());
        let reference = tex.render(size, size, x0, y0, 0.0, 0.0);
        let moved = tex.render(size, size, x0, y0, tx, ty);
        let moving = radiometric(&moved, 0.6, 0.25, 0.7, noise_std, seed + trial as u64);
        let s = phase_correlate(&reference, &moving, &p).unwrap();
        sum_sq += (s.dx_px - tx).powi(2) + (s.dy_px - ty).powi(2);
    }
    (sum_sq / trials as f64).sqrt()
}

#[test]
fn subpixel_shifts_under_radiometric_change_and_noise_64() {
    let rms = rms_error(64, 40, 0.01, 7);
    eprintln!("RMS {rms:.4} px");
    assert!(rms <= 0.05, "RMS {rms:.4} px");
}

#[test]
fn subpixel_shifts_under_radiometric_change_and_noise_128() {
    let rms = rms_error(128, 20, 0.02, 11);
    eprintln!("RMS {rms:.4} px");
    assert!(rms <= 0.05, "RMS {rms:.4} px");
}

#[test]
fn illumination_change_gives_the_same_shift() {
    let tex = Texture::new(256, 64, 3);
    let (f1, f2) = shifted_pair(&tex, 96, (20.0, 30.0), (1.4, 2.6));
    let p = PhaseCorrelationParams::default();
    let a = phase_correlate(&f1, &f2, &p).unwrap();
    let f2b = radiometric(&f2, 0.5, 0.3, 1.0, 0.0, 0);
    let b = phase_correlate(&f1, &f2b, &p).unwrap();
    // Identical up to the f32 rounding of the transformed image.
    assert_shift(&a, (b.dx_px, b.dy_px), 1e-5);
    assert_shift(&a, (1.4, 2.6), 0.05);
}

#[test]
fn sign_convention_matches_opencv() {
    // Content moves right/down in `moving` ⇒ positive (dx, dy), x first.
    let tex = Texture::new(256, 64, 4);
    let (f1, f2) = shifted_pair(&tex, 64, (50.0, 50.0), (3.0, 1.0));
    let s = phase_correlate(&f1, &f2, &PhaseCorrelationParams::default()).unwrap();
    assert!(s.dx_px > 2.5 && s.dy_px > 0.5 && s.dy_px < 1.5, "{s:?}");
}

#[test]
fn template_is_located_in_a_larger_search_window() {
    let tex = Texture::new(256, 64, 5);
    let search = tex.render(48, 48, 100.0, 80.0, 0.0, 0.0);
    let mut rng = SplitMix64(99);
    let p = PhaseCorrelationParams::default();
    let mut sum_sq = 0.0;
    let n = 20;
    for _ in 0..n {
        // Template = the texture around search position (cx, cy), i.e. a 24×24 crop with a sub-pixel origin.
        let (cx, cy) = (rng.range(20.0, 28.0), rng.range(20.0, 28.0));
        let (ox, oy) = (100.0 + cx - 12.0, 80.0 + cy - 12.0);
        let template = tex.crop_at(24, 24, (ox, oy));
        let loc = locate_template(&template, &search, &p).unwrap();
        sum_sq += (loc.u_px - cx).powi(2) + (loc.v_px - cy).powi(2);
        assert!(loc.peak > 0.2, "{loc:?}");
    }
    let rms = (sum_sq / n as f64).sqrt();
    assert!(rms < 0.1, "RMS {rms:.4} px");
}

#[test]
fn reused_correlator_gives_the_free_functions_results() {
    use skytie_stages::matching::phase_correlation::{PhaseCorrelationError, PhaseCorrelator};
    let tex = Texture::new(256, 64, 6);
    let p = PhaseCorrelationParams::default();
    let mut c = PhaseCorrelator::new(64, 64, p).unwrap();
    // Several different pairs through one correlator: no state leaks from one call into the next.
    for (k, (tx, ty)) in [(1.3, -0.7), (-2.6, 3.1), (0.4, 0.2)]
        .into_iter()
        .enumerate()
    {
        let x0 = 30.0 * k as f64;
        let (a, b) = shifted_pair(&tex, 64, (x0, 40.0), (tx, ty));
        let reused = c.correlate(&a, &b).unwrap();
        assert_eq!(reused, phase_correlate(&a, &b, &p).unwrap());
        assert_shift(&reused, (tx, ty), 0.05);
    }
    // Template location through a correlator sized for the search window.
    let search = tex.render(48, 48, 100.0, 80.0, 0.0, 0.0);
    let template = tex.render(24, 24, 112.0, 92.0, -0.3, 0.6);
    let mut s = PhaseCorrelator::new(48, 48, p).unwrap();
    let loc = s.locate_template(&template, &search).unwrap();
    assert_eq!(loc, locate_template(&template, &search, &p).unwrap());
    // render() samples at x0 + i − t: the template starts at (112.3, 91.4) in the texture, (12.3, 11.4) in the
    // search window ⇒ centre at (24.3, 23.4).
    assert!(
        (loc.u_px - 24.3).abs() < 0.1 && (loc.v_px - 23.4).abs() < 0.1,
        "{loc:?}"
    );
    // Wrong sizes are errors, not panics.
    let small = tex.render(32, 32, 0.0, 0.0, 0.0, 0.0);
    assert!(matches!(
        c.correlate(&small, &small),
        Err(PhaseCorrelationError::CorrelatorSize { .. })
    ));
    assert!(matches!(
        PhaseCorrelator::new(2, 64, p),
        Err(PhaseCorrelationError::TooSmall { .. })
    ));
}

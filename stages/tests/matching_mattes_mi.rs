//! Known-answer tests of Mattes MI and the (1+1)-ES (Mattes et al. 2001; Styner et al. 2000 KATs; the sub-pixel shift under a
//! gamma change and noise).

use skytie_stages::estimators::one_plus_one::{minimize, OnePlusOneParams};
use skytie_stages::estimators::SplitMix64;
use skytie_stages::imaging::GrayImage;
use skytie_stages::matching::mattes_mi::{
    apply_mask, bspline3, register_translation, MattesMi, MiError, MiRegistration,
};
use skytie_stages::params::Params;

/// A smooth random texture (sum of Gaussian blobs, σ 2.5–7 px), as a function of continuous position, scaled to
/// roughly [0, 255].
struct Texture {
    blobs: Vec<(f64, f64, f64, f64)>,
}

impl Texture {
    fn new(seed: u64, extent_px: f64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let blobs = (0..(extent_px * extent_px / 25.0) as usize)
            .map(|_| {
                (
                    rng.next_f64() * (extent_px + 20.0) - 10.0,
                    rng.next_f64() * (extent_px + 20.0) - 10.0,
                    2.5 + 4.5 * rng.next_f64(),
                    rng.next_f64() * 2.0 - 1.0,
                )
            })
            .collect();
        Self { blobs }
    }

    fn value(&self, x: f64, y: f64) -> f64 {
        let s: f64 = self
            .blobs
            .iter()
            .map(|&(cx, cy, sigma, a)| {
                a * (-((x - cx).powi(2) + (y - cy).powi(2)) / (2.0 * sigma * sigma)).exp()
            })
            .sum();
        (128.0 + 60.0 * s).clamp(0.0, 255.0)
    }

    /// A texture of `size` × `size` pixels with its image as it is (unmoved, no intensity map).
    fn with_image(seed: u64, size: usize) -> (Self, GrayImage) {
        let tex = Self::new(seed, size as f64);
        let image = tex.render(size, [0.0, 0.0], |v| v);
        (tex, image)
    }

    /// Image whose pixel centre (c + 0.5, r + 0.5) shows the texture at (c + 0.5 − d_x, r + 0.5 − d_y), i.e. the
    /// content moved by d, with an intensity map applied.
    fn render(&self, size: usize, d: [f64; 2], map: impl Fn(f64) -> f64) -> GrayImage {
        let mut img = GrayImage::filled(size, size, 0.0);
        for r in 0..size {
            for c in 0..size {
                let v = self.value(c as f64 + 0.5 - d[0], r as f64 + 0.5 - d[1]);
                img.set(c, r, map(v) as f32);
            }
        }
        img
    }
}

fn es_params(seed: u64, max_iterations: usize) -> OnePlusOneParams {
    OnePlusOneParams {
        max_iterations,
        seed,
        ..OnePlusOneParams::default()
    }
}

/// Mattes MI (50 bins) of `moving` against `fixed` at translation `t_px`, with `samples` drawn by `seed`.
fn mi_at(
    fixed: &GrayImage,
    moving: &GrayImage,
    samples: Option<usize>,
    seed: u64,
    t_px: [f64; 2],
) -> f64 {
    MattesMi::new(fixed, moving, 50, samples, seed)
        .unwrap()
        .evaluate(t_px[0], t_px[1])
        .unwrap()
}

/// `got` equals the MI `want` to 1e-9; `what` names the case.
fn assert_same_mi(got: f64, want: f64, what: std::fmt::Arguments) {
    assert!((got - want).abs() < 1e-9, "{what}: {got} vs {want}");
}

/// The translation of `moving` against `fixed` registered by the (1+1)-ES (50 bins, every sample, from zero,
/// at most `max_offset_px`, `es_params(es_seed, 300)`), and its distance from `d`, px.
fn registered(
    fixed: &GrayImage,
    moving: &GrayImage,
    max_offset_px: f64,
    es_seed: u64,
    d: [f64; 2],
) -> (MiRegistration, f64) {
    let reg = register_translation(
        fixed,
        moving,
        50,
        None,
        [0.0, 0.0],
        max_offset_px,
        &es_params(es_seed, 300),
    )
    .unwrap();
    let err =
        ((reg.translation_px[0] - d[0]).powi(2) + (reg.translation_px[1] - d[1]).powi(2)).sqrt();
    (reg, err)
}

#[test]
fn bspline3_is_a_partition_of_unity() {
    let mut rng = SplitMix64::new(7);
    for _ in 0..1000 {
        let u = rng.next_f64() * 100.0 - 50.0;
        let k0 = u.floor() as i64;
        let sum: f64 = (k0 - 3..=k0 + 3).map(|k| bspline3(u - k as f64)).sum();
        assert!((sum - 1.0).abs() < 1e-12, "u = {u}: Σ β3 = {sum}");
    }
    assert!((bspline3(0.0) - 4.0 / 6.0).abs() < 1e-15);
    assert!((bspline3(1.0) - 1.0 / 6.0).abs() < 1e-15);
    assert_eq!(bspline3(2.0), 0.0);
    assert_eq!(bspline3(-2.5), 0.0);
}

#[test]
fn mi_is_invariant_under_affine_intensity_remaps() {
    let tex = Texture::new(1, 64.0);
    // Integer-valued pixels keep a·F + b exact in f32.
    let fixed = tex.render(64, [0.0, 0.0], |v| v.round());
    for samples in [None, Some(1500)] {
        let mi_ff = mi_at(&fixed, &fixed, samples, 3, [0.0, 0.0]);
        assert!(mi_ff > 1.0, "MI(F, F) = {mi_ff}");
        for (a, b) in [(2.0f32, 10.0f32), (-1.0, 255.0), (0.5, -3.0), (-3.0, 7.0)] {
            let mut moving = fixed.clone();
            moving.data.iter_mut().for_each(|v| *v = a * *v + b);
            let mi = mi_at(&fixed, &moving, samples, 3, [0.0, 0.0]);
            assert_same_mi(
                mi,
                mi_ff,
                format_args!("a = {a}, b = {b}, samples {samples:?}"),
            );
        }
    }
}

#[test]
fn mi_against_independent_noise_is_small_and_shrinks_with_more_samples() {
    let (_, fixed) = Texture::with_image(2, 128);
    let mut rng = SplitMix64::new(99);
    let noise = GrayImage::from_vec(
        128,
        128,
        (0..128 * 128)
            .map(|_| (rng.next_f64() * 255.0) as f32)
            .collect(),
    )
    .unwrap();
    let mi_ff = mi_at(&fixed, &fixed, None, 0, [0.0, 0.0]);
    let mi_noise = |samples: Option<usize>| mi_at(&fixed, &noise, samples, 5, [0.0, 0.0]);
    let (few, many, all) = (mi_noise(Some(500)), mi_noise(Some(4000)), mi_noise(None));
    assert!(few > many && many > all, "{few} > {many} > {all}");
    assert!(all < 0.05 * mi_ff, "MI(F, noise) {all} vs MI(F, F) {mi_ff}");
    // The positive bias of the plug-in estimate is at most ≈ (B − 1)²/(2N) (less with Parzen smoothing).
    assert!(all < 49.0 * 49.0 / (2.0 * 128.0 * 128.0), "{all}");
}

#[test]
fn es_recovers_a_translation_under_a_non_monotone_remap() {
    let tex = Texture::new(3, 96.0);
    let d = [3.4, -2.1];
    let fixed = tex.render(96, [0.0, 0.0], |v| v);
    let moving = tex.render(96, d, |g| (g - 128.0).powi(2) / 128.0);
    let (reg, err) = registered(&fixed, &moving, 10.0, 11, d);
    assert!(err < 0.1, "found {:?}, error {err} px", reg.translation_px);
    assert!(reg.mi > 0.5, "MI {}", reg.mi);
}

#[test]
fn mi_registration_recovers_a_subpixel_shift_of_a_gamma_changed_noisy_copy() {
    // ≤ 0.2 px.
    for (seed, d) in [(4u64, [0.6, -0.3]), (5, [-0.35, 0.8]), (6, [1.25, 0.45])] {
        let (tex, fixed) = Texture::with_image(seed, 80);
        let mut rng = SplitMix64::new(seed + 100);
        let mut moving = tex.render(80, d, |g| 255.0 * (g / 255.0).powf(0.6));
        moving
            .data
            .iter_mut()
            .for_each(|v| *v += (4.0 * rng.next_gaussian()) as f32);
        let (reg, err) = registered(&fixed, &moving, 5.0, seed, d);
        assert!(err <= 0.2, "d = {d:?}: found {:?}", reg.translation_px);
    }
}

#[test]
fn masked_pixels_are_skipped_on_both_images() {
    let tex = Texture::new(8, 80.0);
    let d = [1.7, 2.2];
    let fixed = tex.render(80, [0.0, 0.0], |v| v);
    let moving = tex.render(80, d, |v| 255.0 - v);
    // Mask a block of the fixed image and another of the moving image: no data there.
    let fixed_valid: Vec<bool> = (0..80 * 80)
        .map(|i| !(i % 80 < 25 && i / 80 < 30))
        .collect();
    let moving_valid: Vec<bool> = (0..80 * 80)
        .map(|i| !(i % 80 > 50 && i / 80 > 45))
        .collect();
    let fixed_m = apply_mask(&fixed, &fixed_valid).unwrap();
    let moving_m = apply_mask(&moving, &moving_valid).unwrap();
    let metric = MattesMi::new(&fixed_m, &moving_m, 50, None, 0).unwrap();
    assert_eq!(metric.sample_count(), 80 * 80 - 25 * 30);
    let (reg, err) = registered(&fixed_m, &moving_m, 6.0, 2, d);
    assert!(err < 0.1, "found {:?}", reg.translation_px);
    // Garbage in the masked area must not matter: same MI whatever the masked pixels held.
    let mut moving_garbage = moving.clone();
    for (v, &ok) in moving_garbage.data.iter_mut().zip(&moving_valid) {
        if !ok {
            *v = f32::NAN;
        }
    }
    let a = mi_at(&fixed_m, &moving_m, None, 0, [1.0, 2.0]);
    let b = mi_at(&fixed_m, &moving_garbage, None, 0, [1.0, 2.0]);
    assert_eq!(a, b);
}

#[test]
fn too_little_overlap_and_degenerate_inputs_are_errors() {
    let (_, fixed) = Texture::with_image(9, 32);
    let mut metric = MattesMi::new(&fixed, &fixed, 50, None, 0).unwrap();
    // 31 px off: only one column of 32² samples overlaps (< 1/16).
    assert!(matches!(
        metric.evaluate(31.0, 0.0),
        Err(MiError::TooFewSamplesLanded { .. })
    ));
    assert!(metric.evaluate(f64::NAN, 0.0).is_err());
    let flat = GrayImage::filled(32, 32, 3.0);
    assert!(matches!(
        MattesMi::new(&fixed, &flat, 50, None, 0),
        Err(MiError::ConstantImage { .. })
    ));
    let empty = GrayImage::filled(32, 32, f32::NAN);
    assert!(matches!(
        MattesMi::new(&empty, &fixed, 50, None, 0),
        Err(MiError::NoValidPixels { .. })
    ));
    assert!(matches!(
        MattesMi::new(&fixed, &fixed, 4, None, 0),
        Err(MiError::TooFewBins { .. })
    ));
}

#[test]
fn sampled_metric_is_deterministic_for_a_seed() {
    let (tex, fixed) = Texture::with_image(10, 64);
    let moving = tex.render(64, [0.5, 0.5], |v| v);
    let eval = |seed| mi_at(&fixed, &moving, Some(700), seed, [0.3, 0.2]);
    assert_eq!(eval(1).to_bits(), eval(1).to_bits());
    assert_ne!(eval(1).to_bits(), eval(2).to_bits());
}

#[test]
fn es_minimises_a_quadratic_by_the_epsilon_rule_with_a_reproducible_trace() {
    let c = [3.0, -2.0];
    let x0 = [c[0] + 0.6, c[1] + 0.8];
    let f = |x: &[f64]| Some((x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2));
    let p = OnePlusOneParams {
        record_trace: true,
        ..es_params(42, 5000)
    };
    let r1 = minimize(f, &x0, &[1.0, 1.0], &p).unwrap();
    assert!(r1.converged, "stopped after {} iterations", r1.iterations);
    assert!(r1.iterations < 5000);
    let dist = ((r1.x[0] - c[0]).powi(2) + (r1.x[1] - c[1]).powi(2)).sqrt();
    assert!(dist < 1e-2, "‖x − c‖ = {dist}");
    let r2 = minimize(f, &x0, &[1.0, 1.0], &p).unwrap();
    assert_eq!(r1, r2, "rerun must give an identical trace");
    assert_eq!(r1.trace.len(), r1.iterations);
    // 100 iterations are not enough from 1 unit away.
    let short = minimize(f, &x0, &[1.0, 1.0], &es_params(42, 100)).unwrap();
    assert!(!short.converged);
    assert_eq!(short.iterations, 100);
}

#[test]
fn es_treats_invalid_children_as_failures_and_rejects_bad_input() {
    let p = es_params(1, 2000);
    // Minimum of (x − 2)² constrained to x ≤ 1.5 (None beyond): converges to the boundary.
    let f = |x: &[f64]| (x[0] <= 1.5).then(|| (x[0] - 2.0).powi(2));
    let r = minimize(f, &[0.0], &[1.0], &p).unwrap();
    assert!(r.x[0] <= 1.5 && r.x[0] > 1.4, "{:?}", r.x);
    assert!(minimize(|_: &[f64]| None, &[0.0], &[1.0], &p).is_none());
    assert!(minimize(f, &[0.0], &[1.0, 1.0], &p).is_none());
    assert!(minimize(f, &[0.0], &[0.0], &p).is_none());
    assert!(OnePlusOneParams::default().validate().is_ok());
    let bad = OnePlusOneParams {
        shrink_factor: 1.2,
        epsilon: -1.0,
        ..OnePlusOneParams::default()
    };
    assert_eq!(bad.validate().unwrap_err().len(), 2);
}

/// Mattes MI at an integral translation written out from the module's definition (all fixed pixels, box
/// window on the fixed side, cubic B-spline on the moving side, samples on masked or outside pixels skipped):
/// the reference for the per-moving-pixel table path of `MattesMi::evaluate`.
fn reference_mi_integral(fixed: &GrayImage, moving: &GrayImage, bins: usize, t: [i64; 2]) -> f64 {
    let range = |img: &GrayImage| {
        let v: Vec<f64> = img
            .data
            .iter()
            .filter(|v| v.is_finite())
            .map(|&v| f64::from(v))
            .collect();
        let lo = v.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        (lo, (hi - lo) / (bins - 4) as f64)
    };
    let ((fmin, fd), (mmin, md)) = (range(fixed), range(moving));
    let mut joint = vec![0.0; bins * bins];
    let mut n = 0.0;
    for r in 0..fixed.height as i64 {
        for c in 0..fixed.width as i64 {
            let f = f64::from(fixed.data[(r * fixed.width as i64 + c) as usize]);
            let (mr, mc) = (r + t[1], c + t[0]);
            if !f.is_finite()
                || mr < 0
                || mc < 0
                || mr >= moving.height as i64
                || mc >= moving.width as i64
            {
                continue;
            }
            let m = f64::from(moving.data[(mr * moving.width as i64 + mc) as usize]);
            if !m.is_finite() {
                continue;
            }
            let fb = ((f - fmin) / fd + 2.0)
                .floor()
                .clamp(2.0, (bins - 3) as f64) as usize;
            let tau = (m - mmin) / md + 2.0;
            let k0 = tau.floor().clamp(2.0, (bins - 3) as f64) as usize;
            for k in k0 - 1..=k0 + 2 {
                joint[fb * bins + k] += bspline3(k as f64 - tau);
            }
            n += 1.0;
        }
    }
    let pf: Vec<f64> = (0..bins)
        .map(|r| joint[r * bins..(r + 1) * bins].iter().sum::<f64>() / n)
        .collect();
    let pm: Vec<f64> = (0..bins)
        .map(|c| (0..bins).map(|r| joint[r * bins + c]).sum::<f64>() / n)
        .collect();
    let mut mi = 0.0;
    for r in 0..bins {
        for c in 0..bins {
            let pj = joint[r * bins + c] / n;
            if pj > 1e-16 && pf[r] > 1e-16 && pm[c] > 1e-16 {
                mi += pj * (pj / (pf[r] * pm[c])).ln();
            }
        }
    }
    mi
}

/// The integer-translation path (per-moving-pixel Parzen table) against the reference, at shifts that push
/// samples over the border and onto masked moving pixels.
#[test]
fn integral_translations_match_the_definition() {
    let (tex, fixed) = Texture::with_image(11, 60);
    let moving = tex.render(60, [2.3, -1.4], |v| (v / 255.0).powf(0.8) * 200.0 + 20.0);
    let moving_valid: Vec<bool> = (0..60 * 60)
        .map(|i| !(i % 60 > 40 && i / 60 > 35))
        .collect();
    let moving_m = apply_mask(&moving, &moving_valid).unwrap();
    let mut metric = MattesMi::new(&fixed, &moving_m, 50, None, 4).unwrap();
    for t in [[0, 0], [2, -1], [-7, 5], [12, 12], [-3, -11]] {
        let got = metric.evaluate(t[0] as f64, t[1] as f64).unwrap();
        let want = reference_mi_integral(&fixed, &moving_m, 50, t);
        assert_same_mi(
            got,
            want,
            format_args!("shift {t:?} (got vs the definition's)"),
        );
    }
}

/// A huge but finite translation lands no sample (an error), neither wrapping around nor panicking.
#[test]
fn huge_translations_land_nothing() {
    let (_, fixed) = Texture::with_image(12, 32);
    let mut metric = MattesMi::new(&fixed, &fixed, 50, None, 0).unwrap();
    for t in [
        [1e300, 0.0],
        [0.0, -1e300],
        [9.3e18, 9.3e18],
        [-9.3e18, 0.5],
    ] {
        assert!(
            matches!(
                metric.evaluate(t[0], t[1]),
                Err(MiError::TooFewSamplesLanded { landed: 0, .. })
            ),
            "translation {t:?}"
        );
    }
}

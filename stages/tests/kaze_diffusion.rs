//! Known-answer tests of KAZE's scale-space numerics (Alcantarilla, Bartoli & Davison 2012 KAT): Thomas solver vs dense LU, AOS
//! mean conservation and constant preservation, g ≡ 1 diffusion ≈ Gaussian blur (AOS and FED), FED step
//! sizes, contrast factor on a ramp.

use skytie_stages::features::kaze::contrast::{contrast_factor, CONTRAST_BINS};
use skytie_stages::features::kaze::diffusion::{
    aos_step, conductance_value, fed_diffuse, fed_step_sizes, thomas_solve,
};
use skytie_stages::features::kaze::Diffusivity;
use skytie_stages::imaging::gaussian::gaussian_blur;
use skytie_stages::imaging::GrayImage;
use skytie_stages::rng::SplitMix64;

/// Dense Gaussian elimination with partial pivoting (reference solver).
fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        b.swap(c, p);
        for r in c + 1..n {
            let f = a[r][c] / a[c][c];
            for k in c..n {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

#[test]
fn thomas_matches_dense_lu_on_random_diagonally_dominant_systems() {
    let mut rng = SplitMix64::new(7);
    for trial in 0..50 {
        let n: usize = 1 + trial * 3;
        let off: Vec<f64> = (0..n.saturating_sub(1))
            .map(|_| rng.next_f64() * 4.0 - 2.0)
            .collect();
        let diag: Vec<f64> = (0..n)
            .map(|k| {
                let left = if k > 0 { off[k - 1].abs() } else { 0.0 };
                let right = if k + 1 < n { off[k].abs() } else { 0.0 };
                left + right + 0.1 + rng.next_f64()
            })
            .collect();
        let rhs: Vec<f64> = (0..n).map(|_| rng.next_f64() * 10.0 - 5.0).collect();
        let mut x = vec![0.0; n];
        let mut scratch = vec![0.0; n];
        thomas_solve(&diag, &off, &rhs, &mut x, &mut scratch);
        let mut a = vec![vec![0.0; n]; n];
        for k in 0..n {
            a[k][k] = diag[k];
            if k + 1 < n {
                a[k][k + 1] = off[k];
                a[k + 1][k] = off[k];
            }
        }
        let reference = dense_solve(a, rhs);
        for k in 0..n {
            assert!(
                (x[k] - reference[k]).abs() < 1e-10,
                "n={n} k={k}: {} vs {}",
                x[k],
                reference[k]
            );
        }
    }
}

fn random_image(w: usize, h: usize, seed: u64) -> GrayImage {
    let mut rng = SplitMix64::new(seed);
    let data = (0..w * h).map(|_| rng.next_f64() as f32).collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

/// A smooth random image: sum of random low-frequency sinusoids, range ≈ [0, 1].
fn smooth_image(w: usize, h: usize, seed: u64) -> GrayImage {
    let mut rng = SplitMix64::new(seed);
    let waves: Vec<[f64; 4]> = (0..6)
        .map(|_| {
            let angle = rng.next_f64() * std::f64::consts::TAU;
            let freq = 0.03 + 0.04 * rng.next_f64(); // rad/px: wavelengths 90..200 px
            [
                freq * angle.cos(),
                freq * angle.sin(),
                rng.next_f64() * std::f64::consts::TAU,
                0.5 + rng.next_f64(),
            ]
        })
        .collect();
    let total_amp: f64 = waves.iter().map(|w| w[3]).sum();
    let data = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
            let s: f64 = waves
                .iter()
                .map(|wv| wv[3] * (wv[0] * x + wv[1] * y + wv[2]).sin())
                .sum();
            (0.5 + 0.5 * s / total_amp) as f32
        })
        .collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

#[test]
fn aos_conserves_the_mean_and_keeps_constants() {
    let img = random_image(61, 47, 3);
    let g = random_image(61, 47, 4); // any conductance in (0, 1)
    let sum0: f64 = img.data.iter().map(|&v| v as f64).sum();
    for tau in [0.1f32, 1.0, 10.0, 100.0] {
        let out = aos_step(&img, &g, tau);
        let sum1: f64 = out.data.iter().map(|&v| v as f64).sum();
        assert!(
            ((sum1 - sum0) / sum0).abs() < 1e-6,
            "tau {tau}: {sum0} → {sum1}"
        );
        // Diffusion smooths: the range shrinks.
        let (lo, hi) = out
            .data
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(lo >= -1e-6 && hi <= 1.0 + 1e-6);
        let fed = fed_diffuse(&img, &g, tau);
        let sum_fed: f64 = fed.data.iter().map(|&v| v as f64).sum();
        assert!(
            ((sum_fed - sum0) / sum0).abs() < 1e-5,
            "FED tau {tau}: {sum0} → {sum_fed}"
        );
    }
    let constant = GrayImage::filled(40, 30, 0.37);
    for out in [
        aos_step(&constant, &g_crop(&g, 40, 30), 25.0),
        fed_diffuse(&constant, &g_crop(&g, 40, 30), 25.0),
    ] {
        assert!(out.data.iter().all(|&v| (v - 0.37).abs() < 1e-6));
    }
}

fn g_crop(g: &GrayImage, w: usize, h: usize) -> GrayImage {
    let data = (0..w * h).map(|k| g.get(k % w, k / w)).collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

fn rms_interior(a: &GrayImage, b: &GrayImage, margin: usize) -> f64 {
    let (mut s, mut n) = (0.0f64, 0usize);
    for row in margin..a.height - margin {
        for col in margin..a.width - margin {
            s += ((a.get(col, row) - b.get(col, row)) as f64).powi(2);
            n += 1;
        }
    }
    (s / n as f64).sqrt()
}

#[test]
fn unit_conductance_diffusion_is_gaussian_blur_with_sigma_sq_2t() {
    let img = smooth_image(96, 80, 11);
    let range = {
        let (lo, hi) = img
            .data
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        (hi - lo) as f64
    };
    let ones = GrayImage::filled(96, 80, 1.0);
    for t in [0.5f32, 2.0, 4.5] {
        let gauss = gaussian_blur(&img, (2.0 * t).sqrt());
        let aos = aos_step(&img, &ones, t);
        let fed = fed_diffuse(&img, &ones, t);
        let (e_aos, e_fed) = (
            rms_interior(&aos, &gauss, 10),
            rms_interior(&fed, &gauss, 10),
        );
        let e_none = rms_interior(&img, &gauss, 10);
        assert!(e_aos < 0.01 * range, "t={t}: AOS rms {e_aos} range {range}");
        assert!(e_fed < 0.01 * range, "t={t}: FED rms {e_fed} range {range}");
        // Not trivially true: FED is much closer than doing nothing.
        assert!(
            e_fed < 0.2 * e_none,
            "t={t}: FED {e_fed} vs identity {e_none}"
        );
    }
    // A sharper test: an impulse diffused by FED has variance 2t per axis (explicit scheme, no truncation).
    let mut impulse = GrayImage::filled(41, 41, 0.0);
    impulse.set(20, 20, 1.0);
    let ones = GrayImage::filled(41, 41, 1.0);
    let t = 3.0f32;
    let out = fed_diffuse(&impulse, &ones, t);
    let var_x: f64 = (0..41 * 41)
        .map(|k| out.data[k] as f64 * ((k % 41) as f64 - 20.0).powi(2))
        .sum();
    assert!(
        (var_x - 2.0 * t as f64).abs() < 1e-3,
        "impulse variance {var_x}"
    );
}

#[test]
fn fed_step_sizes_sum_to_the_time_and_are_a_permutation() {
    for t in [0.1f64, 0.5, 1.0, 3.7, 40.0, 250.0] {
        let taus = fed_step_sizes(t);
        let sum: f64 = taus.iter().sum();
        assert!((sum - t).abs() < 1e-9 * t.max(1.0), "t={t}: sum {sum}");
        // Reordering keeps the multiset of the FED cycle: sorted values are the cosine formula.
        let n = taus.len();
        let mut sorted = taus.clone();
        sorted.sort_by(f64::total_cmp);
        let mut expected: Vec<f64> = (0..n)
            .map(|k| {
                let h = (std::f64::consts::PI * (2 * k + 1) as f64 / (4 * n + 2) as f64).cos();
                let scale = 3.0 * t / (0.25 * (n * (n + 1)) as f64);
                scale * 0.25 / 2.0 / (h * h)
            })
            .collect();
        expected.sort_by(f64::total_cmp);
        for (a, b) in sorted.iter().zip(&expected) {
            assert!((a - b).abs() < 1e-12 * b.max(1.0));
        }
    }
    assert!(fed_step_sizes(0.0).is_empty());
}

#[test]
fn contrast_factor_on_a_ramp_is_the_gradient_magnitude() {
    // Ramp along u with slope a: interior magnitudes all equal a (unit-gain Scharr); the reflective border
    // lowers the few edge columns, so ≥ 70 % of the magnitudes sit in the top bin ⇒ j = 300, k = max|∇|.
    let (w, h, a) = (200usize, 60usize, 0.004f32);
    let data = (0..w * h).map(|k| a * (k % w) as f32).collect();
    let img = GrayImage::from_vec(w, h, data).unwrap();
    let k = contrast_factor(&img, 1.0, 0.7);
    assert!((k - a).abs() < 1e-5 * a.max(1.0), "k {k} vs slope {a}");
    assert_eq!(CONTRAST_BINS, 300);
    // A flat image has no gradients: fallback.
    assert_eq!(
        contrast_factor(&GrayImage::filled(30, 30, 0.5), 1.0, 0.7),
        0.03
    );
}

#[test]
fn conductance_functions_match_their_formulas() {
    let m = 0.8f32;
    assert!((conductance_value(m, Diffusivity::PmG1) - (-m).exp()).abs() < 1e-7);
    assert!((conductance_value(m, Diffusivity::PmG2) - 1.0 / 1.8).abs() < 1e-7);
    assert!(
        (conductance_value(m, Diffusivity::Weickert) - (1.0 - (-3.315 / m.powi(4)).exp())).abs()
            < 1e-6
    );
    assert!((conductance_value(m, Diffusivity::Charbonnier) - 1.0 / 1.8f32.sqrt()).abs() < 1e-7);
    for d in [
        Diffusivity::PmG1,
        Diffusivity::PmG2,
        Diffusivity::Weickert,
        Diffusivity::Charbonnier,
    ] {
        assert_eq!(conductance_value(0.0, d), 1.0);
    }
}

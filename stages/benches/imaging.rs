//! Timing of imaging's hot paths (plain `fn main`, no harness): phase correlation 64² and 128², NCC 40×40 in
//! 100×100, Gaussian blur of a 4000×3000 image, Förstner on 512². Prints median wall time per call and, for the
//! matchers, the error against the known sub-pixel shift (inputs are exact Fourier shifts of a band-limited
//! texture, see `tests/imaging_support`). Run: `cargo bench -p skytie-stages --bench imaging`.
//! With `SKYTIE_PEER_DIR=dir` the phase-correlation pairs are also written there for `benches/peers/phasecorr.py`.

#[path = "../tests/imaging_support/mod.rs"]
mod imaging_support;
#[path = "peer_support/mod.rs"]
mod peer_support;

use imaging_support::{radiometric, SplitMix64, Texture};
use peer_support::median_wall_ms;
use skytie_stages::features::forstner::{forstner_corners, ForstnerParams};
use skytie_stages::imaging::gaussian::gaussian_blur;
use skytie_stages::imaging::io::{load_gray, save_gray};
use skytie_stages::imaging::GrayImage;
use skytie_stages::matching::ncc::match_template;
use skytie_stages::matching::phase_correlation::{phase_correlate, PhaseCorrelationParams};

fn bench_phase_correlation(size: usize) {
    let tex = Texture::new(512, 128, 42);
    let mut rng = SplitMix64(1);
    let mut pairs = Vec::new();
    for k in 0..10 {
        let (tx, ty) = (rng.range(-4.0, 4.0), rng.range(-4.0, 4.0));
        let (x0, y0) = ((k * 37) as f64, (k * 23) as f64);
        let a = tex.render(size, size, x0, y0, 0.0, 0.0);
        let b = radiometric(
            &tex.render(size, size, x0, y0, tx, ty),
            0.6,
            0.25,
            0.7,
            0.01,
            k as u64,
        );
        pairs.push((a, b, tx, ty));
    }
    let p = PhaseCorrelationParams::default();
    let mut sum_sq = 0.0;
    for (a, b, tx, ty) in &pairs {
        let s = phase_correlate(a, b, &p).unwrap();
        sum_sq += (s.dx_px - tx).powi(2) + (s.dy_px - ty).powi(2);
    }
    if let Some(dir) = std::env::var_os("SKYTIE_PEER_DIR") {
        write_peer_pairs(std::path::Path::new(&dir), size, &pairs, &p);
    }
    let ms = median_wall_ms(50, || {
        std::hint::black_box(phase_correlate(&pairs[0].0, &pairs[0].1, &p).unwrap());
    });
    let single = PhaseCorrelationParams {
        refinements: 0,
        ..p
    };
    let ms1 = median_wall_ms(50, || {
        std::hint::black_box(phase_correlate(&pairs[0].0, &pairs[0].1, &single).unwrap());
    });
    println!(
        "phase correlation {size}x{size}: {ms:.3} ms/call (default, ≤4 passes), {ms1:.3} ms/pass; RMS error {:.4} px over 10 pairs",
        (sum_sq / pairs.len() as f64).sqrt()
    );
}

/// For `benches/peers/phasecorr.py`: write the pairs as 8-bit PNGs plus `truth_{size}.csv` with the true shift
/// and our estimate on the re-loaded (quantised) PNGs, so peers and we see identical inputs.
fn write_peer_pairs(
    dir: &std::path::Path,
    size: usize,
    pairs: &[(GrayImage, GrayImage, f64, f64)],
    p: &PhaseCorrelationParams,
) {
    std::fs::create_dir_all(dir).expect("create SKYTIE_PEER_DIR");
    let mut csv = String::from("reference,moving,tx_px,ty_px,skytie_dx_px,skytie_dy_px\n");
    for (k, (a, b, tx, ty)) in pairs.iter().enumerate() {
        let (na, nb) = (
            format!("pc{size}_{k}_ref.png"),
            format!("pc{size}_{k}_mov.png"),
        );
        save_gray(&dir.join(&na), a).expect("write PNG");
        save_gray(&dir.join(&nb), b).expect("write PNG");
        let (la, lb) = (
            load_gray(&dir.join(&na)).unwrap(),
            load_gray(&dir.join(&nb)).unwrap(),
        );
        let s = phase_correlate(&la, &lb, p).unwrap();
        csv.push_str(&format!(
            "{na},{nb},{tx:.6},{ty:.6},{:.6},{:.6}\n",
            s.dx_px, s.dy_px
        ));
    }
    std::fs::write(dir.join(format!("truth_{size}.csv")), csv).expect("write truth CSV");
}

fn bench_ncc() {
    let tex = Texture::new(256, 48, 7);
    let img = tex.render(100, 100, 0.0, 0.0, 0.0, 0.0);
    let (cx, cy): (f64, f64) = (47.3, 52.6);
    let (ox, oy) = (cx - 20.0, cy - 20.0);
    let t = tex.crop_at(40, 40, (ox, oy));
    let m = match_template(&img, &t).unwrap();
    let ms = median_wall_ms(30, || {
        std::hint::black_box(match_template(&img, &t).unwrap());
    });
    println!(
        "NCC 40x40 template in 100x100: {ms:.3} ms/call; error {:.4} px (score {:.4})",
        (m.u_px - cx).hypot(m.v_px - cy),
        m.score
    );
}

fn bench_blur() {
    let (w, h) = (4000, 3000);
    let mut rng = SplitMix64(3);
    let data: Vec<f32> = (0..w * h).map(|_| rng.uniform() as f32).collect();
    let img = GrayImage::from_vec(w, h, data).unwrap();
    for sigma in [1.0f32, 2.0, 4.0] {
        let ms = median_wall_ms(5, || {
            std::hint::black_box(gaussian_blur(&img, sigma));
        });
        println!(
            "Gaussian blur 4000x3000, sigma {sigma}: {ms:.1} ms ({} threads)",
            rayon::current_num_threads()
        );
    }
}

fn bench_forstner() {
    let tex = Texture::new(512, 64, 9);
    let img = tex.render(512, 512, 0.0, 0.0, 0.0, 0.0);
    let p = ForstnerParams::default();
    let n = forstner_corners(&img, &p).len();
    let ms = median_wall_ms(5, || {
        std::hint::black_box(forstner_corners(&img, &p));
    });
    println!("Förstner (2x tensor) 512x512: {ms:.1} ms, {n} corners");
}

fn main() {
    bench_phase_correlation(64);
    bench_phase_correlation(128);
    bench_ncc();
    bench_blur();
    bench_forstner();
}

//! Mattes MI translation registration benchmark and peer-input writer for `benches/peers/mi_sitk.py`
//! (SimpleITK `ImageRegistrationMethod`). Plain
//! `fn main`, no harness.
//!
//! 20 pairs of 96×96 patches: a crop of a band-limited texture (fixed) and the same crop translated by a random
//! sub-pixel t ∈ [−2, 2)² px (exact Fourier shift, see `tests/imaging_support`), then gain 0.6, offset 0.25,
//! gamma 0.7 and noise σ 0.01 (moving). Written as 8-bit PNGs and re-loaded, so both sides see IDENTICAL
//! pixels. Registration = the MI path of the patch registration and of `skytie tool mi-register`
//! (`oblique::patch_registration::search::mi_search`, no scan): Mattes MI with 50 bins maximised by the
//! (1+1)-ES from (0, 0) with ITK's defaults (initial radius 1.01 px, growth 1.05, shrink 1.05^(−1/4),
//! ε 1.5e-4) and a budget of 200 iterations, in two sampling settings: every pixel, and 2000 random pixels.
//!
//! Prints per setting the RMS error against t and the median (over rounds) of the mean thread CPU time per
//! registration. Writes to `$SKYTIE_PEER_DIR/mi/` (default `<temp>/skytie_peers/mi/`): `mi_{k}_fixed.png`,
//! `mi_{k}_moving.png`, `params.csv` (the settings the peer must use), `truth.csv` (t and skytie's estimates)
//! and `skytie.csv` (RMS, time).
//! Run: `cargo bench -p skytie-stages --bench mi`.

#[path = "../tests/imaging_support/mod.rs"]
mod imaging_support;
#[path = "peer_support/mod.rs"]
mod peer_support;

use peer_support::shifted_pair::ShiftedPair;
use peer_support::{median_round_ms, peer_dir};
use std::path::Path;

use imaging_support::{radiometric, SplitMix64, Texture};
use skytie_stages::estimators::one_plus_one::OnePlusOneParams;
use skytie_stages::matching::mattes_mi::MiRegistration;
use skytie_stages::oblique::patch_registration::search::mi_search;

const PAIRS: usize = 20;
const SIZE_PX: usize = 96;
const MAX_SHIFT_PX: f64 = 2.0;
const BINS: usize = 50;
const ITERATIONS: usize = 200;
/// Candidate translations farther than this from (0, 0), per axis, are invalid (skytie only; ITK has no such
/// window, and with |t| < 2 px the ES never needs to go there).
const WINDOW_PX: f64 = 8.0;
/// Random fixed samples of the sampled setting.
const SAMPLES: usize = 2000;

/// Writes the pairs as PNGs and returns them as re-loaded (8-bit quantised) images.
fn make_pairs(dir: &Path) -> Vec<ShiftedPair> {
    let tex = Texture::new(512, 64, 42);
    let mut rng = SplitMix64(7);
    (0..PAIRS)
        .map(|k| {
            let (tx, ty) = (
                rng.range(-MAX_SHIFT_PX, MAX_SHIFT_PX),
                rng.range(-MAX_SHIFT_PX, MAX_SHIFT_PX),
            );
            let (x0, y0) = (rng.range(0.0, 400.0).floor(), rng.range(0.0, 400.0).floor());
            let a = tex.render(SIZE_PX, SIZE_PX, x0, y0, 0.0, 0.0);
            let b = tex.render(SIZE_PX, SIZE_PX, x0, y0, tx, ty);
            let b = radiometric(&b, 0.6, 0.25, 0.7, 0.01, 1000 + k as u64);
            ShiftedPair::written(
                dir,
                [format!("mi_{k}_fixed.png"), format!("mi_{k}_moving.png")],
                &a,
                &b,
                (tx, ty),
            )
        })
        .collect()
}

/// Median over `reps` rounds of the mean thread CPU time per pair (ms) of `f` on every pair.
fn median_ms_per_call(
    pairs: &[ShiftedPair],
    reps: usize,
    mut f: impl FnMut(usize, &ShiftedPair),
) -> f64 {
    median_round_ms(reps, || {
        for (k, p) in pairs.iter().enumerate() {
            f(k, p);
        }
    }) / pairs.len() as f64
}

/// ES settings: ITK's defaults with the bench's budget and a per-pair seed.
fn es(k: usize) -> OnePlusOneParams {
    OnePlusOneParams {
        max_iterations: ITERATIONS,
        seed: 1 + k as u64,
        ..OnePlusOneParams::default()
    }
}

fn register(p: &ShiftedPair, k: usize, samples: Option<usize>) -> MiRegistration {
    mi_search(
        &p.reference,
        &p.moving,
        BINS,
        samples,
        [0.0, 0.0],
        WINDOW_PX,
        None,
        &es(k),
    )
    .expect("registration")
}

fn main() {
    let dir = peer_dir("mi");
    std::fs::create_dir_all(&dir).expect("create the peer directory");
    let pairs = make_pairs(&dir);
    let d = OnePlusOneParams::default();
    std::fs::write(
        dir.join("params.csv"),
        format!(
            "size_px,bins,samples,iterations,initial_radius_px,growth_factor,shrink_factor,epsilon_px\n\
             {SIZE_PX},{BINS},{SAMPLES},{ITERATIONS},{},{},{},{}\n",
            d.initial_radius, d.growth_factor, d.shrink_factor, d.epsilon
        ),
    )
    .expect("write params.csv");

    let settings: [(&str, Option<usize>); 2] = [("all", None), ("sampled", Some(SAMPLES))];
    let mut truth = String::from("fixed,moving,tx_px,ty_px");
    for (name, _) in &settings {
        truth += &format!(
            ",skytie_{name}_dx_px,skytie_{name}_dy_px,skytie_{name}_mi,skytie_{name}_iterations"
        );
    }
    truth.push('\n');
    let results: Vec<Vec<MiRegistration>> = settings
        .iter()
        .map(|&(_, samples)| {
            pairs
                .iter()
                .enumerate()
                .map(|(k, p)| register(p, k, samples))
                .collect()
        })
        .collect();
    for (k, p) in pairs.iter().enumerate() {
        truth += &format!(
            "mi_{k}_fixed.png,mi_{k}_moving.png,{:.6},{:.6}",
            p.tx_px, p.ty_px
        );
        for r in &results {
            let r = &r[k];
            truth += &format!(
                ",{:.6},{:.6},{:.6},{}",
                r.translation_px[0], r.translation_px[1], r.mi, r.iterations
            );
        }
        truth.push('\n');
    }
    std::fs::write(dir.join("truth.csv"), truth).expect("write truth.csv");

    println!(
        "Mattes MI translation registration, {PAIRS} pairs {SIZE_PX}x{SIZE_PX}, {BINS} bins, (1+1)-ES ITK defaults, \
         {ITERATIONS} iterations (8-bit PNG inputs, 1 thread, thread CPU time)"
    );
    println!("sampling           | RMS err px | max err px | ms/registration");
    let mut csv = String::from("setting,samples,rms_px,max_px,ms_per_registration\n");
    for ((name, samples), res) in settings.iter().zip(&results) {
        let errs: Vec<f64> = pairs
            .iter()
            .zip(res)
            .map(|(p, r)| (r.translation_px[0] - p.tx_px).hypot(r.translation_px[1] - p.ty_px))
            .collect();
        let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt();
        let max = errs.iter().copied().fold(0.0, f64::max);
        let ms = median_ms_per_call(&pairs, 7, |k, p| {
            std::hint::black_box(register(p, k, *samples));
        });
        let label = match samples {
            Some(n) => format!("{n} random px"),
            None => format!("all {} px", SIZE_PX * SIZE_PX),
        };
        println!("{label:<18} | {rms:>10.4} | {max:>10.4} | {ms:>15.3}");
        csv += &format!(
            "{name},{},{rms:.6},{max:.6},{ms:.6}\n",
            samples.map_or("all".to_string(), |n| n.to_string())
        );
    }
    std::fs::write(dir.join("skytie.csv"), csv).expect("write skytie.csv");
    println!("inputs for benches/peers/mi_sitk.py: {}", dir.display());
}

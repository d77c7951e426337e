//! Phase-correlation benchmark and peer-input writer (plain `fn main`, no harness). For 32², 64² and 128² it makes 20 pairs each: a crop of a band-limited texture and the same crop
//! translated by a random sub-pixel t ∈ [−4, 4)² px (exact Fourier shift, see `tests/imaging_support`), then
//! gain 0.6, offset 0.25, gamma 0.7 and noise σ 0.01. The pairs are written as 8-bit PNGs and re-loaded, so the
//! numbers below and `benches/peers/phasecorr.py` (OpenCV, scikit-image) see IDENTICAL inputs.
//!
//! Prints per size: RMS error against t, median time per call of `phase_correlate` (default parameters: a
//! pass and one refinement), of a reused `PhaseCorrelator`, and of a single pass. Writes to `$SKYTIE_PEER_DIR/phasecorr/`
//! (default: `<temp>/skytie_peers/phasecorr/`): `pc{size}_{k}_ref.png`, `pc{size}_{k}_mov.png`,
//! `truth_{size}.csv` (t, skytie's estimate) and `skytie_{size}.csv` (skytie's timings).
//! Run: `cargo bench -p skytie-stages --bench phasecorr`.

#[path = "../tests/imaging_support/mod.rs"]
mod imaging_support;
#[path = "peer_support/mod.rs"]
mod peer_support;

use peer_support::shifted_pair::ShiftedPair;
use peer_support::{median_round_ms, peer_dir};
use std::path::Path;

use imaging_support::{radiometric, SplitMix64, Texture};
use skytie_stages::matching::phase_correlation::{
    phase_correlate, PhaseCorrelationParams, PhaseCorrelator,
};

const PAIRS: usize = 20;

/// Writes the pairs of one size as PNGs and returns them as re-loaded (8-bit quantised) images.
fn make_pairs(size: usize, dir: &Path) -> Vec<ShiftedPair> {
    let tex = Texture::new(512, 128, 42);
    let mut rng = SplitMix64(size as u64);
    (0..PAIRS)
        .map(|k| {
            let (tx, ty) = (rng.range(-4.0, 4.0), rng.range(-4.0, 4.0));
            let (x0, y0) = (rng.range(0.0, 380.0).floor(), rng.range(0.0, 380.0).floor());
            let a = tex.render(size, size, x0, y0, 0.0, 0.0);
            let b = tex.render(size, size, x0, y0, tx, ty);
            let b = radiometric(&b, 0.6, 0.25, 0.7, 0.01, (size * 1000 + k) as u64);
            ShiftedPair::written(
                dir,
                [
                    format!("pc{size}_{k}_ref.png"),
                    format!("pc{size}_{k}_mov.png"),
                ],
                &a,
                &b,
                (tx, ty),
            )
        })
        .collect()
}

/// Median over `reps` rounds of the mean time per pair (ms; thread CPU time, else wall) of `f` on every pair.
fn median_ms_per_call(pairs: &[ShiftedPair], reps: usize, mut f: impl FnMut(&ShiftedPair)) -> f64 {
    median_round_ms(reps, || pairs.iter().for_each(&mut f)) / pairs.len() as f64
}

fn bench_size(size: usize, dir: &Path) {
    let pairs = make_pairs(size, dir);
    let p = PhaseCorrelationParams::default();
    let mut csv =
        String::from("reference,moving,tx_px,ty_px,skytie_dx_px,skytie_dy_px,skytie_peak\n");
    let mut sum_sq = 0.0;
    for (k, pair) in pairs.iter().enumerate() {
        let s = phase_correlate(&pair.reference, &pair.moving, &p).unwrap();
        sum_sq += (s.dx_px - pair.tx_px).powi(2) + (s.dy_px - pair.ty_px).powi(2);
        csv.push_str(&format!(
            "pc{size}_{k}_ref.png,pc{size}_{k}_mov.png,{:.6},{:.6},{:.6},{:.6},{:.6}\n",
            pair.tx_px, pair.ty_px, s.dx_px, s.dy_px, s.peak
        ));
    }
    let rms = (sum_sq / pairs.len() as f64).sqrt();
    std::fs::write(dir.join(format!("truth_{size}.csv")), csv).expect("write truth CSV");

    let reps = if size >= 128 { 30 } else { 100 };
    let free_ms = median_ms_per_call(&pairs, reps, |q| {
        std::hint::black_box(phase_correlate(&q.reference, &q.moving, &p).unwrap());
    });
    let mut correlator = PhaseCorrelator::new(size, size, p).unwrap();
    let reused_ms = median_ms_per_call(&pairs, reps, |q| {
        std::hint::black_box(correlator.correlate(&q.reference, &q.moving).unwrap());
    });
    let single = PhaseCorrelationParams {
        refinements: 0,
        ..p
    };
    let mut one_pass = PhaseCorrelator::new(size, size, single).unwrap();
    let mut sum_sq1 = 0.0;
    for q in &pairs {
        let s = one_pass.correlate(&q.reference, &q.moving).unwrap();
        sum_sq1 += (s.dx_px - q.tx_px).powi(2) + (s.dy_px - q.ty_px).powi(2);
    }
    let rms1 = (sum_sq1 / pairs.len() as f64).sqrt();
    let pass_ms = median_ms_per_call(&pairs, reps, |q| {
        std::hint::black_box(one_pass.correlate(&q.reference, &q.moving).unwrap());
    });
    println!(
        "{size:>3}x{size:<3} | {rms:>10.4} | {free_ms:>14.4} | {reused_ms:>14.4} | {pass_ms:>10.4} | {rms1:>13.4}"
    );
    std::fs::write(
        dir.join(format!("skytie_{size}.csv")),
        format!(
            "method,rms_px,ms_per_call\nskytie phase_correlate (default),{rms:.6},{free_ms:.6}\n\
             skytie PhaseCorrelator (default),{rms:.6},{reused_ms:.6}\nskytie single pass,{rms1:.6},{pass_ms:.6}\n"
        ),
    )
    .expect("write timing CSV");
}

fn main() {
    let dir = peer_dir("phasecorr");
    std::fs::create_dir_all(&dir).expect("create the peer directory");
    println!(
        "phase correlation, {PAIRS} pairs per size (8-bit PNG inputs, 1 thread, thread CPU time)"
    );
    println!(
        "size    | RMS err px | phase_correlate | PhaseCorrelator | 1 pass     | 1-pass RMS px"
    );
    println!("        |            | ms/call         | ms/call         | ms/call    |");
    for size in [32, 64, 128] {
        bench_size(size, &dir);
    }
    println!("inputs for benches/peers/phasecorr.py: {}", dir.display());
}

//! AGAST and DAISY benchmark and peer-input writer for `benches/peers/daisy_agast.py` (OpenCV
//! `AgastFeatureDetector` and `xfeatures2d.DAISY`).
//! Plain `fn main`, no harness.
//!
//! Two 1024×1024 8-bit images (written as PNG and re-loaded, so both sides see IDENTICAL pixels): `noise`
//! (uniform noise blurred with σ = 2 px, stretched to 0..255) and `blocks` (400 random axis-parallel rectangles
//! of random grey on mid-grey, blurred with σ = 0.8 px, noise σ = 1 grey level: window-frame-like corners).
//! AGAST OAST 9-16 at threshold 10 (OpenCV's default) with and without non-maximum suppression; DAISY with
//! OpenCV's default geometry (radius 15, 3 rings, 8 histograms, 8 orientations) and partial normalisation (the
//! pipeline's) at every NMS corner whose pattern fits in the image. Timed in a 1-thread rayon pool by the
//! thread CPU time of that pool's thread (median over rounds); DAISY's time includes its layers (as OpenCV's
//! `compute`).
//!
//! Written to `$SKYTIE_PEER_DIR/daisy_agast/` (default `<temp>/skytie_peers/daisy_agast/`): `{image}.png`,
//! `skytie_agast_{image}_{nms,all}.csv` (x, y, score; pixel centres at +0.5), `skytie_daisy_{image}.csv` (x, y
//! of the described points) with `skytie_daisy_{image}.npy` (their descriptors, float32, one row per point in
//! the same order), `params.csv` and `skytie.csv` (times and counts).
//! Run: `cargo bench -p skytie-stages --bench daisy_agast`.

#[path = "../tests/imaging_support/mod.rs"]
mod imaging_support;
#[path = "peer_support/mod.rs"]
mod peer_support;

use imaging_support::SplitMix64;
use peer_support::{median_round_ms, peer_dir, write_npy_f32};
use std::path::Path;

use skytie_stages::features::agast::{detect_agast, AgastCorner, AgastParams};
use skytie_stages::features::daisy::{describe_points, DaisyNormalization, DaisyParams};
use skytie_stages::imaging::gaussian::gaussian_blur;
use skytie_stages::imaging::io::{load_gray, save_gray};
use skytie_stages::imaging::GrayImage;

const SIZE_PX: usize = 1024;
const THRESHOLD: f32 = 10.0;

/// Stretch to [0, 1] and quantise to 8 bits.
fn stretch(img: &mut GrayImage) {
    let (lo, hi) = img
        .data
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    img.data
        .iter_mut()
        .for_each(|v| *v = ((*v - lo) / (hi - lo) * 255.0).round() / 255.0);
}

fn noise_image(seed: u64) -> GrayImage {
    let mut rng = SplitMix64(seed);
    let data = (0..SIZE_PX * SIZE_PX)
        .map(|_| rng.uniform() as f32)
        .collect();
    let mut img = gaussian_blur(&GrayImage::from_vec(SIZE_PX, SIZE_PX, data).unwrap(), 2.0);
    stretch(&mut img);
    img
}

fn blocks_image(seed: u64) -> GrayImage {
    let mut rng = SplitMix64(seed);
    let mut img = GrayImage::filled(SIZE_PX, SIZE_PX, 0.5);
    for _ in 0..400 {
        let (w, h) = (rng.range(8.0, 80.0) as usize, rng.range(8.0, 80.0) as usize);
        let x0 = rng.range(0.0, (SIZE_PX - w) as f64) as usize;
        let y0 = rng.range(0.0, (SIZE_PX - h) as f64) as usize;
        let g = rng.range(0.1, 0.9) as f32;
        for r in y0..y0 + h {
            for c in x0..x0 + w {
                img.set(c, r, g);
            }
        }
    }
    let mut img = gaussian_blur(&img, 0.8);
    img.data
        .iter_mut()
        .for_each(|v| *v = (*v + (rng.normal() / 255.0) as f32).clamp(0.0, 1.0));
    stretch(&mut img);
    img
}

fn write_corners(path: &Path, corners: &[AgastCorner]) {
    let mut csv = String::from("x,y,score\n");
    for c in corners {
        csv += &format!("{},{},{}\n", c.x_px, c.y_px, c.score);
    }
    std::fs::write(path, csv).expect("write corner CSV");
}

fn main() {
    let dir = peer_dir("daisy_agast");
    std::fs::create_dir_all(&dir).expect("create the peer directory");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("1-thread pool");
    let nms = AgastParams {
        threshold: THRESHOLD,
        ..AgastParams::default()
    };
    let all = AgastParams {
        nonmax_suppression: false,
        ..nms.clone()
    };
    let daisy = DaisyParams {
        normalization: DaisyNormalization::Partial,
        ..DaisyParams::default()
    };
    std::fs::write(
        dir.join("params.csv"),
        format!(
            "threshold,radius,q_radius,q_theta,q_hist,normalization\n{THRESHOLD},{},{},{},{},partial\n",
            daisy.radius_px, daisy.rings, daisy.histograms, daisy.orientations
        ),
    )
    .expect("write params.csv");

    println!("AGAST OAST 9-16 (threshold {THRESHOLD}) and DAISY (R 15, Q 3, T 8, H 8, partial) on {SIZE_PX}x{SIZE_PX} 8-bit images, 1 thread, thread CPU time");
    println!("image  | AGAST ms | corners (NMS) | corners (no NMS) | DAISY ms | described | DAISY µs/point");
    let mut csv =
        String::from("image,agast_ms,corners_nms,agast_all_ms,corners_all,daisy_ms,described\n");
    for (name, img) in [("noise", noise_image(42)), ("blocks", blocks_image(43))] {
        let png = dir.join(format!("{name}.png"));
        save_gray(&png, &img).expect("write PNG");
        let img = load_gray(&png).expect("re-load PNG");
        let corners = detect_agast(&img, &nms);
        let corners_all = detect_agast(&img, &all);
        write_corners(&dir.join(format!("skytie_agast_{name}_nms.csv")), &corners);
        write_corners(
            &dir.join(format!("skytie_agast_{name}_all.csv")),
            &corners_all,
        );
        let points: Vec<(f64, f64)> = corners.iter().map(|c| (c.x_px, c.y_px)).collect();
        let described: Vec<((f64, f64), Vec<f32>)> = describe_points(&img, &points, &daisy)
            .into_iter()
            .zip(&points)
            .filter_map(|(d, &p)| d.map(|d| (p, d)))
            .collect();
        let mut pts_csv = String::from("x,y\n");
        let mut flat = Vec::with_capacity(described.len() * daisy.descriptor_len());
        for ((x, y), d) in &described {
            pts_csv += &format!("{x},{y}\n");
            flat.extend_from_slice(d);
        }
        std::fs::write(dir.join(format!("skytie_daisy_{name}.csv")), pts_csv)
            .expect("write points CSV");
        write_npy_f32(
            &dir.join(format!("skytie_daisy_{name}.npy")),
            described.len(),
            daisy.descriptor_len(),
            &flat,
        );
        let described_points: Vec<(f64, f64)> = described.iter().map(|(p, _)| *p).collect();

        let (agast_ms, agast_all_ms, daisy_ms) = pool.install(|| {
            (
                median_round_ms(21, || {
                    std::hint::black_box(detect_agast(&img, &nms));
                }),
                median_round_ms(21, || {
                    std::hint::black_box(detect_agast(&img, &all));
                }),
                median_round_ms(7, || {
                    std::hint::black_box(describe_points(&img, &described_points, &daisy));
                }),
            )
        });
        println!(
            "{name:<6} | {agast_ms:>8.2} | {:>13} | {:>16} | {daisy_ms:>8.1} | {:>9} | {:>14.2}",
            corners.len(),
            corners_all.len(),
            described.len(),
            daisy_ms * 1e3 / described.len().max(1) as f64
        );
        csv += &format!(
            "{name},{agast_ms:.4},{},{agast_all_ms:.4},{},{daisy_ms:.4},{}\n",
            corners.len(),
            corners_all.len(),
            described.len()
        );
    }
    std::fs::write(dir.join("skytie.csv"), csv).expect("write skytie.csv");
    println!("inputs for benches/peers/daisy_agast.py: {}", dir.display());
}

//! Benchmark of KAZE detect + describe on a 1000×1000 textured image with the thesis setting (one octave,
//! upright, extended 128; thesis 3.4.5.2), FED and AOS, with 1 thread and the default pool.
//! Run: `cargo bench -p skytie-stages --bench kaze`. Writes the test image as PNG to
//! `$SKYTIE_KAZE_BENCH_DIR/kaze_bench.png` (default: the system temp dir) with the keypoints as CSV
//! (`kaze_bench_keypoints.csv`: u_px, v_px, size_px, response; campaign pixel convention) for peer comparison.

use skytie_stages::features::kaze::{detect_and_describe, Features, KazeParams, Scheme};
use skytie_stages::imaging::gaussian::gaussian_blur;
use skytie_stages::imaging::io::save_gray;
use skytie_stages::imaging::GrayImage;
use std::time::Instant;

/// Process CPU seconds (user + system, Linux /proc/self/stat; None elsewhere).
fn process_cpu_s() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let after = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = after.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// Band-limited noise: uniform noise blurred with σ = 2.5 px, stretched to [0, 1] (8-bit quantised, so the
/// PNG the peer reads is exactly the image measured here).
fn textured(w: usize, h: usize, seed: u64) -> GrayImage {
    let mut state = seed;
    let noise: Vec<f32> = (0..w * h)
        .map(|_| {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        })
        .collect();
    let mut img = gaussian_blur(&GrayImage::from_vec(w, h, noise).unwrap(), 2.5);
    let (lo, hi) = img
        .data
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    img.data
        .iter_mut()
        .for_each(|v| *v = ((*v - lo) / (hi - lo) * 255.0).round() / 255.0);
    img
}

fn run(img: &GrayImage, p: &KazeParams, threads: usize) -> (Features, f64, Option<f64>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let cpu0 = process_cpu_s();
    let t0 = Instant::now();
    let f = pool.install(|| detect_and_describe(img, p));
    let wall = t0.elapsed().as_secs_f64();
    let cpu = process_cpu_s().zip(cpu0).map(|(b, a)| b - a);
    (f, wall, cpu)
}

fn main() {
    let img = textured(1000, 1000, 42);
    let dir = std::env::var_os("SKYTIE_KAZE_BENCH_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    let png = dir.join("kaze_bench.png");
    if let Err(e) = save_gray(&png, &img) {
        eprintln!("could not write {}: {e}", png.display());
    }
    let threads = rayon::current_num_threads();
    for scheme in [Scheme::Fed, Scheme::Aos] {
        let p = KazeParams {
            octaves: 1,
            upright: true,
            extended: true,
            scheme,
            ..KazeParams::default()
        };
        for t in [1, threads] {
            let (f, wall, cpu) = run(&img, &p, t);
            println!(
                "kaze 1000x1000 {scheme:?} 1 octave upright extended, {t} thread(s): {wall:.3} s wall, {} CPU, {} keypoints",
                cpu.map_or("n/a".to_string(), |c| format!("{c:.2} s")),
                f.len()
            );
            if scheme == Scheme::Fed && t == 1 {
                let mut csv = String::from("u_px,v_px,size_px,response\n");
                for k in &f.keypoints {
                    csv += &format!("{},{},{},{}\n", k.u_px, k.v_px, k.size_px, k.response);
                }
                let path = dir.join("kaze_bench_keypoints.csv");
                if let Err(e) = std::fs::write(&path, csv) {
                    eprintln!("could not write {}: {e}", path.display());
                }
            }
        }
    }
    println!("image: {}", png.display());
}

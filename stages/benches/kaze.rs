//! KAZE benchmark and peer-input writer for `benches/peers/kaze.py` (`cv2.xfeatures2d.KAZE_create`). Plain `fn main`, no harness.
//!
//! Image A is a 1000×1000 crop of band-limited noise (8-bit); image B is the crop of the same noise at
//! (+SHIFT_X, +SHIFT_Y), i.e. A's content at p appears in B at p − shift (an integer shift: no resampling). Both
//! are written as PNG and re-loaded, so the peer sees identical pixels. KAZE with the thesis setting (one
//! octave, upright, extended 128; thesis 3.4.5.2), FED and AOS, timed with 1 thread and the default pool (wall
//! time and process CPU time; one warm-up run, then the median of 5 runs). Repeatability: the share of A's keypoints whose shifted position lies ≥ 10 px
//! inside B that have a B keypoint within 1.5 px (the same rule `kaze.py` applies to OpenCV).
//!
//! Written to `$SKYTIE_PEER_DIR/kaze/` (default `<temp>/skytie_peers/kaze/`): `kaze_a.png`, `kaze_b.png`,
//! `skytie_keypoints_{a,b}.csv` (u_px, v_px, size_px, response; campaign pixel convention: centres at +0.5),
//! `skytie_kaze.csv` (timings, counts, repeatability) and `shift.csv`.
//! Run: `cargo bench -p skytie-stages --bench kaze`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use skytie_stages::features::kaze::{detect_and_describe, Features, KazeParams, Scheme};
use skytie_stages::imaging::io::{load_gray, save_gray};
use skytie_stages::imaging::GrayImage;
use skytie_stages::synth::test_texture::band_limited_noise;

const SIZE: usize = 1000;
const SHIFT_X: usize = 17;
const SHIFT_Y: usize = 9;
/// Keypoints closer than this to B's border (after shifting) are not counted.
const BORDER_PX: f32 = 10.0;
/// Largest distance (px) at which a B keypoint counts as the same point.
const MATCH_RADIUS_PX: f32 = 1.5;

fn peer_dir() -> PathBuf {
    std::env::var_os("SKYTIE_PEER_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("skytie_peers"))
        .join("kaze")
}

/// Process CPU seconds (user + system, Linux /proc/self/stat; None elsewhere).
fn process_cpu_s() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let after = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = after.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// Band-limited noise: uniform noise blurred with σ = 2.5 px, stretched to [0, 1] and 8-bit quantised.
fn textured(w: usize, h: usize, seed: u64) -> GrayImage {
    let mut img = band_limited_noise(w, h, 2.5, seed);
    img.data
        .iter_mut()
        .for_each(|v| *v = (*v * 255.0).round() / 255.0);
    img
}

fn crop(img: &GrayImage, x0: usize, y0: usize, w: usize, h: usize) -> GrayImage {
    let data = (y0..y0 + h)
        .flat_map(|r| img.row(r)[x0..x0 + w].iter().copied())
        .collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

/// Runs per timing: one untimed warm-up (first-touch page faults, lazy initialisation), then the median of
/// `RUNS` timed runs (wall and process CPU time); `kaze.py` times OpenCV the same way.
const RUNS: usize = 5;

fn run(img: &GrayImage, p: &KazeParams, threads: usize) -> (Features, f64, Option<f64>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut f = pool.install(|| detect_and_describe(img, p));
    let mut walls = Vec::with_capacity(RUNS);
    let mut cpus = Vec::with_capacity(RUNS);
    for _ in 0..RUNS {
        let cpu0 = process_cpu_s();
        let t0 = Instant::now();
        f = pool.install(|| detect_and_describe(img, p));
        walls.push(t0.elapsed().as_secs_f64());
        if let Some(c) = process_cpu_s().zip(cpu0).map(|(b, a)| b - a) {
            cpus.push(c);
        }
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (!v.is_empty()).then(|| v[v.len() / 2])
    };
    (f, median(walls).unwrap_or(0.0), median(cpus))
}

/// Share of `a`'s keypoints (inside B after the shift) with a `b` keypoint within [`MATCH_RADIUS_PX`].
fn repeatability(a: &Features, b: &Features) -> (f64, usize) {
    let (sx, sy) = (SHIFT_X as f32, SHIFT_Y as f32);
    let inside = |u: f32, v: f32| {
        u >= BORDER_PX
            && v >= BORDER_PX
            && u <= SIZE as f32 - BORDER_PX
            && v <= SIZE as f32 - BORDER_PX
    };
    let (mut counted, mut found) = (0usize, 0usize);
    for k in &a.keypoints {
        let (u, v) = (k.u_px - sx, k.v_px - sy);
        if !inside(u, v) {
            continue;
        }
        counted += 1;
        if b.keypoints
            .iter()
            .any(|q| (q.u_px - u).hypot(q.v_px - v) <= MATCH_RADIUS_PX)
        {
            found += 1;
        }
    }
    (found as f64 / counted.max(1) as f64, counted)
}

fn write_keypoints(path: &Path, f: &Features) {
    let mut csv = String::from("u_px,v_px,size_px,response\n");
    for k in &f.keypoints {
        csv += &format!("{},{},{},{}\n", k.u_px, k.v_px, k.size_px, k.response);
    }
    std::fs::write(path, csv).expect("write keypoint CSV");
}

fn main() {
    let dir = peer_dir();
    std::fs::create_dir_all(&dir).expect("create the peer directory");
    let big = textured(SIZE + SHIFT_X, SIZE + SHIFT_Y, 42);
    let (pa, pb) = (dir.join("kaze_a.png"), dir.join("kaze_b.png"));
    save_gray(&pa, &crop(&big, 0, 0, SIZE, SIZE)).expect("write PNG");
    save_gray(&pb, &crop(&big, SHIFT_X, SHIFT_Y, SIZE, SIZE)).expect("write PNG");
    std::fs::write(
        dir.join("shift.csv"),
        format!("shift_x_px,shift_y_px,border_px,match_radius_px\n{SHIFT_X},{SHIFT_Y},{BORDER_PX},{MATCH_RADIUS_PX}\n"),
    )
    .expect("write shift.csv");
    let a = load_gray(&pa).expect("re-load PNG");
    let b = load_gray(&pb).expect("re-load PNG");

    let threads = rayon::current_num_threads();
    let mut csv = String::from("scheme,threads,wall_s,cpu_s,keypoints_a,repeatability\n");
    for scheme in [Scheme::Fed, Scheme::Aos] {
        let p = KazeParams {
            octaves: 1,
            upright: true,
            extended: true,
            scheme,
            ..KazeParams::default()
        };
        for t in [1, threads] {
            let (fa, wall, cpu) = run(&a, &p, t);
            let (fb, _, _) = run(&b, &p, t);
            let (rep, counted) = repeatability(&fa, &fb);
            println!(
                "kaze {SIZE}x{SIZE} {scheme:?} 1 octave upright extended, {t} thread(s): {wall:.3} s wall, {} CPU, \
                 {} keypoints, repeatability {:.1} % of {counted} (shift {SHIFT_X},{SHIFT_Y} px)",
                cpu.map_or("n/a".to_string(), |c| format!("{c:.2} s")),
                fa.len(),
                100.0 * rep
            );
            csv += &format!(
                "{scheme:?},{t},{wall:.6},{},{},{rep:.6}\n",
                cpu.map_or(String::new(), |c| format!("{c:.3}")),
                fa.len()
            );
            if scheme == Scheme::Fed && t == 1 {
                write_keypoints(&dir.join("skytie_keypoints_a.csv"), &fa);
                write_keypoints(&dir.join("skytie_keypoints_b.csv"), &fb);
            }
        }
    }
    std::fs::write(dir.join("skytie_kaze.csv"), csv).expect("write timing CSV");
    println!("inputs for benches/peers/kaze.py: {}", dir.display());
}

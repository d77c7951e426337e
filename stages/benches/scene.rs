//! Benchmark of the scene's ray caster: single-thread `radiance` calls per second on the demo scene for
//! panorama rays (from the route, 2.5 m above the road) and aerial nadir rays (from 450 m).
//! Run: `cargo bench -p skytie-stages --bench scene`. With `SKYTIE_SCENE_PREVIEW=DIR` it also writes
//! preview PNGs (an equirectangular panorama per epoch and a nadir view) into DIR.

use nalgebra::Vector3;
use skytie_stages::imaging::image::RgbImage;
use skytie_stages::synth::scene::{Epoch, Scene, SceneSpec};
use std::time::Instant;

/// CPU time of this thread in seconds (Linux schedstat; falls back to wall time elsewhere), so the
/// numbers mean "per core" even on a loaded machine.
struct CpuTimer {
    wall: Instant,
    cpu0: Option<f64>,
}

fn thread_cpu_s() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

impl CpuTimer {
    fn start() -> Self {
        Self {
            wall: Instant::now(),
            cpu0: thread_cpu_s(),
        }
    }
    fn secs(&self) -> f64 {
        match (self.cpu0, thread_cpu_s()) {
            (Some(a), Some(b)) => b - a,
            _ => self.wall.elapsed().as_secs_f64(),
        }
    }
}

fn pano_dir(u: usize, v: usize, w: usize, h: usize) -> Vector3<f64> {
    let az = (u as f64 + 0.5) / w as f64 * std::f64::consts::TAU;
    let el = std::f64::consts::FRAC_PI_2 - (v as f64 + 0.5) / h as f64 * std::f64::consts::PI;
    Vector3::new(el.cos() * az.sin(), el.cos() * az.cos(), el.sin())
}

fn to_display(c: [f32; 3]) -> [f32; 3] {
    c.map(|v| v.max(0.0).powf(1.0 / 2.2).min(1.0))
}

fn render_pano(
    scene: &Scene,
    o: &Vector3<f64>,
    w: usize,
    h: usize,
    epoch: Epoch,
) -> (RgbImage, f64) {
    let mut img = RgbImage::filled(w, h, [0.0; 3]);
    let t = CpuTimer::start();
    for v in 0..h {
        for u in 0..w {
            let r = scene.radiance(o, &pano_dir(u, v, w, h), epoch);
            img.set(u, v, r);
        }
    }
    (img, t.secs())
}

fn render_nadir(
    scene: &Scene,
    centre: [f64; 2],
    gsd_m: f64,
    n: usize,
    epoch: Epoch,
) -> (RgbImage, f64) {
    let mut img = RgbImage::filled(n, n, [0.0; 3]);
    let height = 450.0;
    let t = CpuTimer::start();
    for row in 0..n {
        for col in 0..n {
            let x = (col as f64 - 0.5 * n as f64) * gsd_m;
            let y = (0.5 * n as f64 - row as f64) * gsd_m;
            // pinhole from `height` above the centre
            let d = Vector3::new(x, y, -height);
            let o = Vector3::new(centre[0], centre[1], height);
            img.set(col, row, scene.radiance(&o, &d, epoch));
        }
    }
    (img, t.secs())
}

/// Prints the speed of the rendering `img` that took `secs` of CPU time (one radiance call per pixel); with a
/// preview folder, also writes it there as the display-encoded PNG `file`, for looking at the scene.
fn report(label: &str, img: &RgbImage, secs: f64, preview: Option<&std::path::Path>, file: &str) {
    println!(
        "{label}: {secs:.3} s, {:.2} M radiance calls/s (1 thread, CPU time)",
        (img.width * img.height) as f64 / secs / 1e6
    );
    if let Some(dir) = preview {
        let mut disp = img.clone();
        disp.data
            .chunks_exact_mut(3)
            .for_each(|c| c.copy_from_slice(&to_display([c[0], c[1], c[2]])));
        skytie_stages::imaging::io::save_rgb(&dir.join(file), &disp, 95).expect("write preview");
    }
}

fn main() {
    let t = Instant::now();
    let scene = Scene::generate(&SceneSpec::demo(), 1);
    println!("generate demo: {:.1} ms", t.elapsed().as_secs_f64() * 1e3);
    let route = scene.route_world().to_vec();
    let p = route[0];
    let mid = [
        0.5 * (route[0][0] + route[route.len() - 1][0]),
        0.5 * (route[0][1] + route[route.len() - 1][1]),
    ];
    let start = scene.local_to_world_xy([60.0, -1.5]);
    let _ = p;
    let o = Vector3::new(
        start[0],
        start[1],
        scene.ground_height_m(start[0], start[1]) + 2.5,
    );
    let (w, h) = (1024, 512);
    let preview = std::env::var_os("SKYTIE_SCENE_PREVIEW").map(std::path::PathBuf::from);
    for epoch in [Epoch::MobileMapping, Epoch::Aerial] {
        let (img, secs) = render_pano(&scene, &o, w, h, epoch);
        let label = format!("panorama {w}x{h} {epoch:?}");
        report(
            &label,
            &img,
            secs,
            preview.as_deref(),
            &format!("pano_{epoch:?}.png"),
        );
    }
    let centre = scene.local_to_world_xy([100.0, 0.0]);
    let _ = mid;
    for epoch in [Epoch::MobileMapping, Epoch::Aerial] {
        let n = 768;
        let (img, secs) = render_nadir(&scene, centre, 0.1, n, epoch);
        let label = format!("nadir {n}x{n} from 450 m, 10 cm GSD {epoch:?}");
        report(
            &label,
            &img,
            secs,
            preview.as_deref(),
            &format!("nadir_{epoch:?}.png"),
        );
    }
}

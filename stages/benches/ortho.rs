//! Ortho-projection benchmark and peer-input writer for `benches/peers/remap.py` (`cv2.remap` with the SAME map;
//! thesis 3.4.3). Plain `fn main`, no harness.
//!
//! A 4000×2000 band-limited texture panorama (8-bit, written as PNG and re-loaded, so both sides see identical
//! pixels) is ortho-projected at 3 cm (707×707 px) and 10 cm (212×212 px) on a 30 m diagonal. Timed, per GSD,
//! with 1 thread (thread CPU time) and the default rayon pool (wall time):
//! - `ortho_project` (projection of every ortho pixel + vehicle mask + bilinear sampling: the real stage);
//! - `remap_with_map` with the precomputed map on the seam-padded panorama (bilinear sampling only — the
//!   like-for-like peer of `cv2.remap`).
//!
//! Written to `$SKYTIE_PEER_DIR/ortho/` (default `<temp>/skytie_peers/ortho/`): `panorama.png` and its decoded
//! float32 values `panorama.npy`, and per GSD
//! `map_{gsd}cm_u.npy`, `map_{gsd}cm_v.npy` (float32, campaign pixel convention: pixel centres at +0.5, NaN
//! where the vehicle hides the ground), `ortho_{gsd}cm.npy` and `remap_{gsd}cm.npy` (skytie's float32 outputs of
//! `ortho_project` and `remap_with_map`, for the agreement and accuracy checks),
//! `skytie_{gsd}cm.csv` (timings) and `geometry_{gsd}cm.json` (ground grid and panorama rotation, for a peer that
//! computes the map itself). Run: `cargo bench -p skytie-stages --bench ortho`.

#[path = "peer_support/mod.rs"]
mod peer_support;

use peer_support::{median_round_ms, median_wall_ms, peer_dir, write_npy_f32};
use std::path::Path;

use skytie_stages::campaign::Recording;
use skytie_stages::geometry::PanoramaCamera;
use skytie_stages::imaging::border::Border;
use skytie_stages::imaging::huge_pages::collect_f32;
use skytie_stages::imaging::io::{load_gray, save_gray};
use skytie_stages::imaging::resample::{remap_with_map, Interpolation, SourceMap};
use skytie_stages::imaging::GrayImage;
use skytie_stages::nadir::{ortho_project_whole, OrthoGeoref, OrthoParams};
use skytie_stages::synth::test_texture::band_limited_noise;

/// `img` with one wrapped column on each side (column −1 = the last, column w = the first), in memory advised to
/// use huge pages like the loaded panorama's.
fn pad_seam(img: &GrayImage) -> GrayImage {
    let w = img.width;
    let rows = img.data.chunks_exact(w);
    let padded = rows.flat_map(|row| {
        std::iter::once(row[w - 1])
            .chain(row.iter().copied())
            .chain(std::iter::once(row[0]))
    });
    GrayImage::from_vec(w + 2, img.height, collect_f32((w + 2) * img.height, padded))
        .expect("padded size")
}

fn recording() -> Recording {
    Recording {
        time: "2020-01-01T00:00:00Z".into(),
        yaw_deg: 0.4,
        pitch_deg: -0.3,
        roll_deg: 0.2,
        ..Recording::new(
            "bench",
            1_577_836_800.0,
            [92_345.678, 437_123.456, 3.5],
            30.0,
            2.2,
        )
    }
}

/// Median time (ms) of `reps` runs of `f` inside a rayon pool of `threads`: with 1 thread the CPU time of the
/// pool's thread (robust against other processes sharing the cores, the clock the peer script uses for
/// `cv2.remap` with 1 thread), else wall time.
fn median_ms(threads: usize, reps: usize, f: impl FnMut() + Send) -> f64 {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        if threads == 1 {
            return median_round_ms(reps, f);
        }
        median_wall_ms(reps, f)
    })
}

fn bench_gsd(panorama: &GrayImage, gsd_cm: u32, dir: &Path) {
    let rec = recording();
    let params = OrthoParams {
        gsd_m: gsd_cm as f64 / 100.0,
        ..OrthoParams::default()
    };
    let ortho = ortho_project_whole(panorama, &rec, &params);
    let (w, h) = (ortho.georef.width_px, ortho.georef.height_px);

    // The map ortho_project samples with: panorama pixel of each ortho pixel centre, NaN where masked.
    let camera =
        PanoramaCamera::from_recording(&rec, panorama.width as u32, panorama.height as u32);
    let georef = OrthoGeoref::new(ortho.georef.foot_world, &params);
    let mut map_u = vec![f32::NAN; w * h];
    let mut map_v = vec![f32::NAN; w * h];
    for row in 0..h {
        for col in 0..w {
            let i = row * w + col;
            if ortho.valid[i] == 0 {
                continue;
            }
            if let Some((u, v)) =
                georef.ortho_to_panorama_pixel(&camera, col as f64 + 0.5, row as f64 + 0.5)
            {
                map_u[i] = u as f32;
                map_v[i] = v as f32;
            }
        }
    }
    write_npy_f32(&dir.join(format!("map_{gsd_cm}cm_u.npy")), h, w, &map_u);
    write_npy_f32(&dir.join(format!("map_{gsd_cm}cm_v.npy")), h, w, &map_v);
    write_npy_f32(
        &dir.join(format!("ortho_{gsd_cm}cm.npy")),
        h,
        w,
        &ortho.image.data,
    );

    // skytie's remap with the same (f32) map, on the panorama padded with one wrapped column on each side, as
    // the peer script does for cv2.remap (the seam then needs no wrap rule; padding is not timed on either side).
    let padded = pad_seam(panorama);
    let source_map = SourceMap {
        width: w,
        height: h,
        u_px: map_u
            .iter()
            .map(|&u| u.rem_euclid(panorama.width as f32) + 1.0)
            .collect(),
        v_px: map_v.clone(),
    };
    let remap_same_map = || {
        remap_with_map(
            &padded,
            &source_map,
            Interpolation::Bilinear,
            Border::Clamp,
            0.0,
        )
    };
    let remapped = remap_same_map();
    write_npy_f32(
        &dir.join(format!("remap_{gsd_cm}cm.npy")),
        h,
        w,
        &remapped.data,
    );
    let max_diff = remapped
        .data
        .iter()
        .zip(&ortho.image.data)
        .zip(&ortho.valid)
        .filter(|(_, &ok)| ok == 1)
        .map(|((a, b), _)| (a - b).abs())
        .fold(0.0f32, f32::max);

    let threads = rayon::current_num_threads();
    let reps = if gsd_cm <= 3 { 15 } else { 60 };
    let mut csv = String::from("method,threads,ms\n");
    println!(
        "ortho {gsd_cm} cm ({w}x{h} px from a {}x{} panorama):",
        panorama.width, panorama.height
    );
    for t in [1, threads] {
        let full = median_ms(t, reps, || {
            std::hint::black_box(ortho_project_whole(panorama, &rec, &params));
        });
        let sampling = median_ms(t, reps, || {
            std::hint::black_box(remap_same_map());
        });
        println!(
            "  {t} thread(s): ortho_project {full:.3} ms, remap with the map {sampling:.3} ms"
        );
        csv.push_str(&format!(
            "skytie ortho_project_whole,{t},{full:.6}\nskytie remap (same map),{t},{sampling:.6}\n"
        ));
    }
    println!("  remap vs ortho_project_whole, max |difference| on valid pixels: {max_diff:.2e}");
    std::fs::write(dir.join(format!("skytie_{gsd_cm}cm.csv")), csv).expect("write timing CSV");

    // The geometry, so that the peer script can also compute the map itself (NumPy) before `cv2.remap`, the
    // whole job `ortho_project` does: d_world(col, row) = foot − centre + a·right + b·up with
    // a = (col + 0.5 − W/2)·gsd, b = (H/2 − row − 0.5)·gsd; d_pano = Rᵀ·d_world (R row-major, pano → world).
    let r = params.rotation_deg.to_radians();
    let foot_offset = [
        ortho.georef.foot_world[0] - camera.center_world.x,
        ortho.georef.foot_world[1] - camera.center_world.y,
        ortho.georef.foot_world[2] - camera.center_world.z,
    ];
    let rot = camera.rotation_pano_to_world;
    let rot_rows: Vec<f64> = (0..3)
        .flat_map(|i| (0..3).map(move |j| rot[(i, j)]))
        .collect();
    let json = format!(
        "{{\"width_px\": {w}, \"height_px\": {h}, \"gsd_m\": {}, \"foot_offset_m\": {:?}, \
         \"right\": [{}, {}], \"up\": [{}, {}], \"rotation_pano_to_world\": {:?}, \
         \"panorama_width_px\": {}, \"panorama_height_px\": {}}}\n",
        params.gsd_m,
        foot_offset,
        r.cos(),
        -r.sin(),
        r.sin(),
        r.cos(),
        rot_rows,
        panorama.width,
        panorama.height
    );
    std::fs::write(dir.join(format!("geometry_{gsd_cm}cm.json")), json).expect("write geometry");
}

fn main() {
    let dir = peer_dir("ortho");
    std::fs::create_dir_all(&dir).expect("create the peer directory");
    let png = dir.join("panorama.png");
    save_gray(&png, &band_limited_noise(4000, 2000, 2.0, 7)).expect("write the panorama PNG");
    let panorama = load_gray(&png).expect("re-load the panorama PNG");
    // The grey values exactly as skytie decoded them (an 8-bit → float conversion may differ from NumPy's
    // `/ 255.0` in the last bit), so that the peer samples the very same floats.
    write_npy_f32(
        &dir.join("panorama.npy"),
        panorama.height,
        panorama.width,
        &panorama.data,
    );
    for gsd_cm in [3, 10] {
        bench_gsd(&panorama, gsd_cm, &dir);
    }
    println!("inputs for benches/peers/remap.py: {}", dir.display());
}

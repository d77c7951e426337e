//! Known-answer test of the ortho-projection (thesis 3.4.3): a panorama rendered analytically from a known ground
//! pattern (bright discs at known world positions on a dark plane) is ortho-projected; each disc's centroid in the
//! ortho image must land within 0.5 ortho px of where its world position maps.

use nalgebra::Vector3;
use skytie_stages::campaign::Recording;
use skytie_stages::geometry::PanoramaCamera;
use skytie_stages::imaging::GrayImage;
use skytie_stages::nadir::{ortho_project_whole, OrthoParams, VehicleMask};

const DISC_RADIUS_M: f64 = 0.15;

fn recording(yaw: f64, pitch: f64, roll: f64, heading: f64) -> Recording {
    Recording {
        yaw_deg: yaw,
        pitch_deg: pitch,
        roll_deg: roll,
        time: "2020-01-01T00:00:00Z".into(),
        ..Recording::new(
            "r1",
            1_577_836_800.0,
            [92_345.678, 437_123.456, 3.5],
            heading,
            2.2,
        )
    }
}

fn disc_centres(rec: &Recording) -> Vec<Vector3<f64>> {
    let z = rec.z - rec.camera_height_m;
    let mut out = Vec::new();
    for &(dx, dy) in &[
        (3.1, 0.4),
        (-2.7, 4.2),
        (0.3, -5.6),
        (6.2, -3.3),
        (-7.4, -1.9),
        (1.7, 7.8),
        (-4.4, 5.9),
    ] {
        out.push(Vector3::new(rec.x + dx, rec.y + dy, z));
    }
    out
}

/// Render the ground pattern into an equirectangular panorama with 4×4 supersampling.
fn render_panorama(rec: &Recording, width: u32) -> GrayImage {
    let cam = PanoramaCamera::from_recording(rec, width, width / 2);
    let discs = disc_centres(rec);
    let ground_z = rec.z - rec.camera_height_m;
    let (w, h) = (width as usize, width as usize / 2);
    let mut img = GrayImage::filled(w, h, 0.1);
    let n = 3;
    for row in h / 2..h {
        for col in 0..w {
            let mut acc = 0.0f32;
            for sy in 0..n {
                for sx in 0..n {
                    let u = col as f64 + (sx as f64 + 0.5) / n as f64;
                    let v = row as f64 + (sy as f64 + 0.5) / n as f64;
                    let d = cam.pixel_to_ray_world(u, v);
                    if d.z >= -1e-9 {
                        acc += 0.1;
                        continue;
                    }
                    let t = (ground_z - cam.center_world.z) / d.z;
                    let p = cam.center_world + d * t;
                    let hit = discs
                        .iter()
                        .any(|c| (p.x - c.x).hypot(p.y - c.y) <= DISC_RADIUS_M);
                    acc += if hit { 0.9 } else { 0.1 };
                }
            }
            img.set(col, row, acc / (n * n) as f32);
        }
    }
    img
}

fn check(rec: Recording, rotation_deg: f64) {
    let pano = render_panorama(&rec, 3072);
    // The rendered panorama has no vehicle in it, so nothing is masked here (the mask has its own test).
    let vehicle = VehicleMask {
        enabled: false,
        ..VehicleMask::default()
    };
    let params = OrthoParams {
        gsd_m: 0.03,
        rotation_deg,
        vehicle,
        ..OrthoParams::default()
    };
    let ortho = ortho_project_whole(&pano, &rec, &params);
    assert_eq!(
        ortho.image.width,
        (30.0 / 2f64.sqrt() / 0.03f64).round() as usize
    );
    for c in disc_centres(&rec) {
        let (eu, ev) = ortho.georef.world_to_pixel(&c);
        // Centroid of (value − background) in a window around the expected position.
        let r = (DISC_RADIUS_M / 0.03 * 2.0).ceil() as isize;
        let (mut sw, mut su, mut sv) = (0.0f64, 0.0f64, 0.0f64);
        for row in (ev as isize - r)..=(ev as isize + r) {
            for col in (eu as isize - r)..=(eu as isize + r) {
                assert!(
                    row >= 0
                        && col >= 0
                        && (row as usize) < ortho.image.height
                        && (col as usize) < ortho.image.width
                );
                let i = row as usize * ortho.image.width + col as usize;
                assert_eq!(ortho.valid[i], 1, "disc pixel masked");
                let w = (ortho.image.data[i] - 0.1).max(0.0) as f64;
                sw += w;
                su += w * (col as f64 + 0.5);
                sv += w * (row as f64 + 0.5);
            }
        }
        assert!(sw > 10.0, "disc not found near ({eu:.1}, {ev:.1})");
        let (cu, cv) = (su / sw, sv / sw);
        let err = (cu - eu).hypot(cv - ev);
        assert!(
            err < 0.5,
            "disc at ({eu:.2}, {ev:.2}) found at ({cu:.2}, {cv:.2}): {err:.3} px"
        );
        // The exact inverse maps the ortho measurement back to the panorama pixel of the true point.
        let cam = PanoramaCamera::from_recording(&rec, pano.width as u32, pano.height as u32);
        let (pu, pv) = ortho.georef.ortho_to_panorama_pixel(&cam, eu, ev).unwrap();
        let (tu, tv) = cam.project_world(&c).unwrap();
        assert!((pu - tu).abs() < 1e-6 && (pv - tv).abs() < 1e-6);
    }
}

#[test]
fn discs_land_within_half_an_ortho_pixel_north_up() {
    check(recording(0.0, 0.0, 0.0, 90.0), 0.0);
}

#[test]
fn discs_land_within_half_an_ortho_pixel_rotated_and_with_residual_attitude() {
    check(recording(3.0, -1.5, 2.0, 210.0), 37.0);
}

#[test]
fn vehicle_is_masked_around_the_foot_point() {
    let rec = recording(0.0, 0.0, 0.0, 45.0);
    let pano = GrayImage::filled(512, 256, 0.5);
    let ortho = ortho_project_whole(&pano, &rec, &OrthoParams::default());
    let n = ortho.image.width;
    // The foot point (image centre) is under the car; a corner of the plane is visible.
    assert_eq!(ortho.valid[(n / 2) * n + n / 2], 0);
    assert_eq!(ortho.valid[0], 1);
    let masked = ortho.valid.iter().filter(|&&v| v == 0).count();
    let fraction = masked as f64 / (n * n) as f64;
    assert!(
        fraction > 0.01 && fraction < 0.4,
        "masked {masked} of {}",
        n * n
    );
}

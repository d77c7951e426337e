//! Panorama camera: the documented pixel ↔ direction conventions and round trips.

use crate::geometry::PanoramaCamera;
use nalgebra::Vector3;

const W: u32 = 4800;
const H: u32 = 2400;

fn rd_centre() -> Vector3<f64> {
    Vector3::new(92_012.345, 437_123.456, 3.2)
}

fn assert_vec_close(a: &Vector3<f64>, b: &Vector3<f64>, tol: f64) {
    assert!((a - b).norm() <= tol, "{a:?} != {b:?} (tol {tol})");
}

/// |u1 − u2| modulo the panorama width.
fn wrapped_du(u1: f64, u2: f64) -> f64 {
    let d = (u1 - u2).rem_euclid(f64::from(W));
    d.min(f64::from(W) - d)
}

#[test]
fn documented_directions() {
    let cam = PanoramaCamera::new(W, H, rd_centre(), 0.0, 0.0, 0.0);
    let (w, h) = (f64::from(W), f64::from(H));
    assert_vec_close(
        &cam.pixel_to_ray_world(w / 2.0, h / 2.0),
        &Vector3::new(0.0, 1.0, 0.0),
        1e-15,
    );
    assert_vec_close(
        &cam.pixel_to_ray_world(0.75 * w, h / 2.0),
        &Vector3::new(1.0, 0.0, 0.0),
        1e-15,
    );
    assert_vec_close(
        &cam.pixel_to_ray_world(0.25 * w, h / 2.0),
        &Vector3::new(-1.0, 0.0, 0.0),
        1e-15,
    );
    assert_vec_close(
        &cam.pixel_to_ray_world(0.0, h / 2.0),
        &Vector3::new(0.0, -1.0, 0.0),
        1e-15,
    );
    assert_vec_close(
        &cam.pixel_to_ray_world(1234.5, 0.0),
        &Vector3::new(0.0, 0.0, 1.0),
        1e-15,
    );
    assert_vec_close(
        &cam.pixel_to_ray_world(17.0, h),
        &Vector3::new(0.0, 0.0, -1.0),
        1e-15,
    );
    // Elevation 45° at v = H/4, azimuth 45° (north-east) at u = 5W/8.
    let d = cam.pixel_to_ray_world(0.625 * w, 0.25 * h);
    assert_vec_close(&d, &Vector3::new(0.5, 0.5, 0.5f64.sqrt()), 1e-15);
}

#[test]
fn world_points_project_to_documented_pixels() {
    let c = rd_centre();
    let cam = PanoramaCamera::new(W, H, c, 0.0, 0.0, 0.0);
    let (w, h) = (f64::from(W), f64::from(H));
    let (u, v) = cam
        .project_world(&(c + Vector3::new(0.0, 10.0, 0.0)))
        .unwrap();
    assert!(
        (u - w / 2.0).abs() < 1e-9 && (v - h / 2.0).abs() < 1e-9,
        "north: ({u},{v})"
    );
    let (u, v) = cam
        .project_world(&(c + Vector3::new(10.0, 0.0, 10.0)))
        .unwrap();
    assert!(
        (u - 0.75 * w).abs() < 1e-9 && (v - 0.25 * h).abs() < 1e-9,
        "east, 45° up: ({u},{v})"
    );
    // Just east of south: azimuth slightly below +180° maps to u slightly below W, never to W itself.
    let (u, _) = cam
        .project_world(&(c + Vector3::new(1e-3, -10.0, 0.0)))
        .unwrap();
    assert!(u < w && u > w - 1.0, "south, a bit east: {u}");
    // Just west of south: azimuth slightly above −180° maps to u slightly above 0.
    let (u, _) = cam
        .project_world(&(c + Vector3::new(-1e-3, -10.0, 0.0)))
        .unwrap();
    assert!(u > 0.0 && u < 1.0, "south, a bit west: {u}");
    let (u, _) = cam
        .project_world(&(c + Vector3::new(0.0, -10.0, 0.0)))
        .unwrap();
    assert!(
        (0.0..w).contains(&u) && wrapped_du(u, 0.0) < 1e-9,
        "south: {u}"
    );
    assert_eq!(cam.project_world(&c), None);
}

#[test]
fn positive_yaw_turns_centre_column_clockwise() {
    // "its centre column then looks at azimuth yaw"
    let cam = PanoramaCamera::new(W, H, rd_centre(), 30.0, 0.0, 0.0);
    let d = cam.pixel_to_ray_world(f64::from(W) / 2.0, f64::from(H) / 2.0);
    let a = 30f64.to_radians();
    assert_vec_close(&d, &Vector3::new(a.sin(), a.cos(), 0.0), 1e-15);
    let azimuth_deg = d.x.atan2(d.y).to_degrees();
    assert!((azimuth_deg - 30.0).abs() < 1e-12);
}

#[test]
fn positive_pitch_raises_centre_column() {
    let cam = PanoramaCamera::new(W, H, rd_centre(), 0.0, 10.0, 0.0);
    let d = cam.pixel_to_ray_world(f64::from(W) / 2.0, f64::from(H) / 2.0);
    let elevation_deg = d.z.atan2(d.x.hypot(d.y)).to_degrees();
    assert!((elevation_deg - 10.0).abs() < 1e-12, "{elevation_deg}");
    assert!(d.y > 0.0 && d.x.abs() < 1e-15);
}

#[test]
fn positive_roll_lowers_east_column() {
    let cam = PanoramaCamera::new(W, H, rd_centre(), 0.0, 0.0, 10.0);
    let d = cam.pixel_to_ray_world(0.75 * f64::from(W), f64::from(H) / 2.0);
    let elevation_deg = d.z.atan2(d.x.hypot(d.y)).to_degrees();
    assert!((elevation_deg + 10.0).abs() < 1e-12, "{elevation_deg}");
    assert!(d.x > 0.0 && d.y.abs() < 1e-15);
}

#[test]
fn pixel_ray_pixel_round_trip_dense_grid() {
    let (w, h) = (f64::from(W), f64::from(H));
    let rotations = [
        (0.0, 0.0, 0.0),
        (17.3, -2.1, 1.4),
        (-135.0, 5.0, -8.0),
        (179.9, 0.3, 0.2),
    ];
    let mut us: Vec<f64> = (0..=96)
        .map(|i| f64::from(i) * w / 96.0)
        .filter(|&u| u < w)
        .collect();
    us.extend([1e-9, 1e-6, 0.5, w - 0.5, w - 1e-6, w - 1e-9]);
    let mut vs: Vec<f64> = (1..48).map(|j| f64::from(j) * h / 48.0).collect();
    vs.extend([1e-3, 0.5, 1.0, h - 1.0, h - 0.5, h - 1e-3]);
    let mut worst = 0.0f64;
    for &(yaw, pitch, roll) in &rotations {
        let cam = PanoramaCamera::new(W, H, rd_centre(), yaw, pitch, roll);
        for &u in &us {
            for &v in &vs {
                let d = cam.pixel_to_ray_world(u, v);
                assert!((d.norm() - 1.0).abs() < 1e-14);
                let (u2, v2) = cam.ray_world_to_pixel(&d);
                assert!((0.0..w).contains(&u2), "u {u2} outside [0, W)");
                let err = wrapped_du(u, u2).max((v - v2).abs());
                worst = worst.max(err);
                assert!(
                    err < 1e-6,
                    "({u},{v}) -> ({u2},{v2}) with ypr ({yaw},{pitch},{roll})"
                );
                // Also through a world point 37 m away at RD-like coordinates. Within 2 px of a pole the
                // horizontal offset of that point is millimetres, below what f64 resolves at 4e5 m to 1e-6 px
                // in azimuth, so the pole rows are checked through directions only.
                if v.min(h - v) >= 2.0 {
                    let (u3, v3) = cam.project_world(&(cam.center_world + d * 37.0)).unwrap();
                    let err = wrapped_du(u, u3).max((v - v3).abs());
                    assert!(
                        err < 1e-6,
                        "({u},{v}) -> world -> ({u3},{v3}) with ypr ({yaw},{pitch},{roll})"
                    );
                }
            }
        }
    }
    // Away from the poles the round trip is far better than required (Hartley & Zisserman 2004, ch. 12 asks 1e-9).
    assert!(worst < 1e-6);
}

#[test]
fn round_trip_away_from_poles_is_1e9() {
    let cam = PanoramaCamera::new(W, H, rd_centre(), 3.0, -1.5, 2.0);
    let (w, h) = (f64::from(W), f64::from(H));
    for i in 0..200 {
        let u = (f64::from(i) * 0.618_033_988_75).fract() * w;
        let v = h * (0.05 + 0.9 * (f64::from(i) * 0.414_213_562_37).fract());
        let (u2, v2) = cam.ray_world_to_pixel(&cam.pixel_to_ray_world(u, v));
        assert!(
            wrapped_du(u, u2) < 1e-9 && (v - v2).abs() < 1e-9,
            "({u},{v}) -> ({u2},{v2})"
        );
    }
}

#[test]
fn poles_map_back_to_the_pole_rows() {
    for &(yaw, pitch, roll) in &[(0.0, 0.0, 0.0), (40.0, 3.0, -2.0)] {
        let cam = PanoramaCamera::new(W, H, rd_centre(), yaw, pitch, roll);
        for &u in &[0.0, 1000.0, 4799.5] {
            let (_, v) = cam.ray_world_to_pixel(&cam.pixel_to_ray_world(u, 0.0));
            assert!(v.abs() < 1e-6, "zenith -> v = {v}");
            let (_, v) = cam.ray_world_to_pixel(&cam.pixel_to_ray_world(u, f64::from(H)));
            assert!((v - f64::from(H)).abs() < 1e-6, "nadir -> v = {v}");
        }
    }
}

#[test]
fn fast_projection_matches_the_exact_one_within_1e9_px() {
    let cam = PanoramaCamera::new(W, H, rd_centre(), 0.7, -0.4, 0.3);
    let mut worst = 0.0f64;
    for i in 0..200 {
        for j in 0..100 {
            // Directions of all azimuths and elevations except the poles, at several lengths.
            let az = -std::f64::consts::PI + (i as f64 + 0.5) * std::f64::consts::TAU / 200.0;
            let el = -1.55 + (j as f64 + 0.5) * 3.1 / 100.0;
            let len = [0.01, 1.0, 3e4][(i + j) % 3];
            let d = Vector3::new(el.cos() * az.sin(), el.cos() * az.cos(), el.sin()) * len;
            let (ue, ve) = cam.ray_pano_to_pixel(&d);
            let (uf, vf) = cam.ray_pano_to_pixel_fast(&d);
            assert!((0.0..f64::from(W)).contains(&uf), "u {uf} outside [0, W)");
            worst = worst.max(wrapped_du(ue, uf).max((ve - vf).abs()));
        }
    }
    assert!(worst < 1e-9, "worst difference {worst:e} px");
}

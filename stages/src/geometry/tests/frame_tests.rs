//! Frame camera: ω-φ-κ cases computed by hand, distortion, round trips.

use crate::geometry::{BrownDistortion, FrameCamera};
use nalgebra::Vector3;

const W: u32 = 12_000;
const H: u32 = 8_000;
const F: f64 = 10_000.0;
const CX: f64 = 6_000.0;
const CY: f64 = 4_000.0;

fn centre() -> Vector3<f64> {
    Vector3::new(92_000.0, 437_000.0, 1_000.0)
}

fn camera(omega: f64, phi: f64, kappa: f64, distortion: BrownDistortion) -> FrameCamera {
    FrameCamera::from_opk(centre(), omega, phi, kappa, F, CX, CY, W, H, distortion)
}

/// The ground point (z = 0) `offset_m` = (east, north) of the camera centre projects to (u, v) within `tol` px.
fn assert_ground_px(cam: &FrameCamera, offset_m: [f64; 2], (u, v): (f64, f64), tol: f64) {
    let c = centre();
    let ground = Vector3::new(c.x + offset_m[0], c.y + offset_m[1], 0.0);
    assert_px(cam.project_world(&ground), u, v, tol);
}

/// Brown distortion with radial (k1, k2) and decentring (p1, p2) terms of typical size.
fn radial_and_decentring() -> BrownDistortion {
    BrownDistortion {
        k1: -0.12,
        k2: 0.03,
        p1: 2e-3,
        p2: -1.5e-3,
        ..BrownDistortion::NONE
    }
}

fn assert_px(got: Option<(f64, f64)>, u: f64, v: f64, tol: f64) {
    let (gu, gv) = got.expect("point should project");
    assert!(
        (gu - u).abs() <= tol && (gv - v).abs() <= tol,
        "got ({gu}, {gv}), expected ({u}, {v})"
    );
}

#[test]
fn nadir_image_top_is_north() {
    let cam = camera(0.0, 0.0, 0.0, BrownDistortion::NONE);
    let c = centre();
    // 100 m north of the nadir point at 1000 m depth: y = 0.1 → 1000 px above the principal point.
    assert_ground_px(&cam, [0.0, 100.0], (CX, CY - 1000.0), 1e-9);
    // 100 m east: x = 0.1 → 1000 px right.
    assert_ground_px(&cam, [100.0, 0.0], (CX + 1000.0, CY), 1e-9);
    assert_ground_px(&cam, [0.0, 0.0], (CX, CY), 1e-9);
    assert!((cam.viewing_direction_world() - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
    assert!((cam.gsd_at(&Vector3::new(c.x + 50.0, c.y - 20.0, 0.0)) - 0.1).abs() < 1e-12);
}

#[test]
fn points_behind_the_camera_do_not_project() {
    let cam = camera(0.0, 0.0, 0.0, BrownDistortion::NONE);
    let c = centre();
    assert_eq!(cam.project_world(&Vector3::new(c.x, c.y, c.z + 10.0)), None);
    assert_eq!(
        cam.project_world(&Vector3::new(c.x + 5.0, c.y, c.z)),
        None,
        "p.z = 0 is not in front"
    );
}

#[test]
fn oblique_45_looking_east_with_image_top_north() {
    // R·(0,0,−1) = Ry(φ)·(0,0,−1) = (−sin φ, 0, −cos φ) = (√½, 0, −√½) ⇒ φ = −45°; κ = 0 keeps the top north.
    let cam = camera(0.0, -45.0, 0.0, BrownDistortion::NONE);
    let s = 0.5f64.sqrt();
    assert!((cam.viewing_direction_world() - Vector3::new(s, 0.0, -s)).norm() < 1e-15);
    let c = centre();
    // The axis meets the ground 1000 m east of the nadir point.
    assert_ground_px(&cam, [1000.0, 0.0], (CX, CY), 1e-9);
    // 2000 m east: 63.43° from the vertical, 18.43° right of the axis: x = tan 18.43° = 1/3.
    assert_ground_px(&cam, [2000.0, 0.0], (CX + F / 3.0, CY), 1e-7);
    // North is still up in the image.
    let (_, v) = cam
        .project_world(&Vector3::new(c.x + 1000.0, c.y + 50.0, 0.0))
        .unwrap();
    assert!(v < CY);
    // Oblique GSD at the axis point: depth √2·1000 m / f.
    assert!((cam.gsd_at(&Vector3::new(c.x + 1000.0, c.y, 0.0)) - 2f64.sqrt() * 0.1).abs() < 1e-12);
}

#[test]
fn oblique_45_looking_east_with_image_top_away() {
    // κ = −90°: camera y axis = Ry(−45°)·(1,0,0) = (√½, 0, √½) (east and up), camera x axis = (0,−1,0)
    // (south, i.e. to the right when facing east).
    let cam = camera(0.0, -45.0, -90.0, BrownDistortion::NONE);
    assert_ground_px(&cam, [1000.0, 0.0], (CX, CY), 1e-9);
    // Farther east appears higher in the image (v < cy) by exactly f/3.
    assert_ground_px(&cam, [2000.0, 0.0], (CX, CY - F / 3.0), 1e-7);
    // South of the axis point appears right of the principal point: x = 100 / (√2·1000).
    let x = 100.0 / (2f64.sqrt() * 1000.0);
    assert_ground_px(&cam, [1000.0, -100.0], (CX + F * x, CY), 1e-7);
}

#[test]
fn oblique_looking_north_uses_omega() {
    // Rx(ω)·(0,0,−1) = (0, sin ω, −cos ω): ω = +45° looks north-down; image top then points north-up.
    let cam = camera(45.0, 0.0, 0.0, BrownDistortion::NONE);
    assert_ground_px(&cam, [0.0, 1000.0], (CX, CY), 1e-9);
    assert_ground_px(&cam, [0.0, 2000.0], (CX, CY - F / 3.0), 1e-7);
}

#[test]
fn brown_distortion_by_hand() {
    let k1 = BrownDistortion {
        k1: 0.1,
        ..BrownDistortion::NONE
    };
    let (xd, yd) = k1.distort(0.5, 0.0);
    assert!((xd - 0.5 * 1.025).abs() < 1e-15 && yd == 0.0);
    // Tangential p1 acts on y with y up: y_d = y + p1 (r² + 2y²).
    let p1 = BrownDistortion {
        p1: 0.01,
        ..BrownDistortion::NONE
    };
    let (xd, yd) = p1.distort(0.0, 0.5);
    assert!(xd.abs() < 1e-15 && (yd - (0.5 + 0.01 * 0.75)).abs() < 1e-15);
    // p2 acts on x: x_d = x + p2 (r² + 2x²).
    let p2 = BrownDistortion {
        p2: -0.02,
        ..BrownDistortion::NONE
    };
    let (xd, yd) = p2.distort(0.3, 0.0);
    assert!((xd - (0.3 - 0.02 * 0.27)).abs() < 1e-15 && yd.abs() < 1e-15);
    // In pixels: v = cy − f·y_d, so positive k1 pushes a point above the centre further up.
    let cam = camera(
        0.0,
        0.0,
        0.0,
        BrownDistortion {
            k1: 0.1,
            ..BrownDistortion::NONE
        },
    );
    let c = centre();
    let (_, v) = cam
        .project_world(&Vector3::new(c.x, c.y + 300.0, 0.0))
        .unwrap();
    assert!((v - (CY - F * 0.3 * (1.0 + 0.1 * 0.09))).abs() < 1e-9);
}

#[test]
fn distortion_jacobian_matches_finite_differences() {
    let d = radial_and_decentring();
    for &(x, y) in &[(0.1, 0.2), (-0.4, 0.3), (0.55, -0.35)] {
        let j = d.distort_jacobian(x, y);
        let e = 1e-6;
        let (xp, yp) = d.distort(x + e, y);
        let (xm, ym) = d.distort(x - e, y);
        assert!((j[0][0] - (xp - xm) / (2.0 * e)).abs() < 1e-8);
        assert!((j[1][0] - (yp - ym) / (2.0 * e)).abs() < 1e-8);
        let (xp, yp) = d.distort(x, y + e);
        let (xm, ym) = d.distort(x, y - e);
        assert!((j[0][1] - (xp - xm) / (2.0 * e)).abs() < 1e-8);
        assert!((j[1][1] - (yp - ym) / (2.0 * e)).abs() < 1e-8);
    }
}

#[test]
fn undistort_inverts_distort_to_1e12() {
    let d = radial_and_decentring();
    for i in -12..=12 {
        for j in -8..=8 {
            let (x, y) = (f64::from(i) * 0.05, f64::from(j) * 0.05);
            let (xd, yd) = d.distort(x, y);
            let (x2, y2) = d.try_undistort(xd, yd).expect("converges inside the image");
            assert!(
                (x2 - x).abs() < 1e-12 && (y2 - y).abs() < 1e-12,
                "({x},{y}) -> ({x2},{y2})"
            );
        }
    }
}

fn round_trip_worst_px(cam: &FrameCamera) -> f64 {
    let mut worst = 0.0f64;
    let (w, h) = (f64::from(cam.width_px), f64::from(cam.height_px));
    for i in 0..=60 {
        for j in 0..=40 {
            let u = (f64::from(i) / 60.0 * w).min(w - 1e-6);
            let v = (f64::from(j) / 40.0 * h).min(h - 1e-6);
            let d = cam.pixel_to_ray_world(u, v);
            assert!((d.norm() - 1.0).abs() < 1e-14);
            let (u2, v2) = cam.project_world(&(cam.center_world + d * 1234.5)).unwrap();
            worst = worst.max((u2 - u).abs()).max((v2 - v).abs());
        }
    }
    worst
}

#[test]
fn pixel_ray_pixel_round_trip_whole_image() {
    let distortions = [
        BrownDistortion::NONE,
        radial_and_decentring(),
        BrownDistortion {
            k1: 0.08,
            k2: -0.01,
            p1: -1e-3,
            p2: 1e-3,
            ..BrownDistortion::NONE
        },
    ];
    for d in distortions {
        for &(o, p, k) in &[
            (0.0, 0.0, 0.0),
            (0.0, -45.0, -90.0),
            (3.0, -2.0, 91.0),
            (-45.0, 10.0, 180.0),
        ] {
            let worst = round_trip_worst_px(&camera(o, p, k, d));
            assert!(worst < 1e-6, "worst {worst} px for opk ({o},{p},{k}) {d:?}");
        }
    }
}

#[test]
fn contains_is_half_open() {
    let cam = camera(0.0, 0.0, 0.0, BrownDistortion::NONE);
    assert!(cam.contains(0.0, 0.0));
    assert!(cam.contains(11_999.999, 7_999.999));
    assert!(!cam.contains(12_000.0, 10.0));
    assert!(!cam.contains(10.0, 8_000.0));
    assert!(!cam.contains(-1e-9, 10.0));
    assert!(!cam.contains(f64::NAN, 10.0));
}

#[test]
fn monotonic_limit_of_the_distortion() {
    assert_eq!(BrownDistortion::NONE.max_monotonic_r2(), f64::INFINITY);
    assert_eq!(
        BrownDistortion {
            k1: 0.1,
            ..BrownDistortion::NONE
        }
        .max_monotonic_r2(),
        f64::INFINITY
    );
    // k2 = 0: 1 + 3 k1 s = 0 ⇒ s = −1/(3 k1).
    let k1 = BrownDistortion {
        k1: -0.5,
        ..BrownDistortion::NONE
    };
    assert!((k1.max_monotonic_r2() - 2.0 / 3.0).abs() < 1e-15);
    // k1 = 0, k2 < 0: 1 + 5 k2 s² = 0 ⇒ s = sqrt(−1/(5 k2)).
    let k2 = BrownDistortion {
        k2: -0.2,
        ..BrownDistortion::NONE
    };
    assert!((k2.max_monotonic_r2() - 1.0).abs() < 1e-15);
    // General case: the derivative vanishes at the limit.
    let d = BrownDistortion {
        k1: -0.3,
        k2: 0.02,
        p1: 0.0,
        p2: 0.0,
        ..BrownDistortion::NONE
    };
    let s = d.max_monotonic_r2();
    assert!(s.is_finite() && (1.0 + 3.0 * d.k1 * s + 5.0 * d.k2 * s * s).abs() < 1e-12);
}

#[test]
fn points_beyond_the_fold_do_not_project_into_the_image() {
    // k1 = −0.5 folds at r = 0.816: a point at r = 1.5 would map to r_d = 1.5·(1 − 0.5·2.25) < 0, i.e. near
    // the principal point, although it is far outside the field of view.
    let cam = camera(
        0.0,
        0.0,
        0.0,
        BrownDistortion {
            k1: -0.5,
            ..BrownDistortion::NONE
        },
    );
    let c = centre();
    assert_eq!(
        cam.project_world(&Vector3::new(c.x + 1500.0, c.y, 0.0)),
        None
    );
    let (u, v) = cam
        .project_world(&Vector3::new(c.x + 500.0, c.y, 0.0))
        .unwrap();
    assert!((u - (CX + F * 0.5 * (1.0 - 0.5 * 0.25))).abs() < 1e-9 && (v - CY).abs() < 1e-9);
}

//! Rotations: elementary matrices, ω-φ-κ ↔ matrix, panorama residual rotation.

use crate::geometry::rotation::*;
use nalgebra::{Matrix3, Vector3};

fn assert_vec_close(a: &Vector3<f64>, b: &Vector3<f64>, tol: f64) {
    assert!((a - b).norm() <= tol, "{a:?} != {b:?} (tol {tol})");
}

#[test]
fn elementary_rotations_are_right_handed() {
    let q = 90f64.to_radians();
    // Right-handed: X→Y about Z, Y→Z about X, Z→X about Y.
    assert_vec_close(&(rot_z(q) * Vector3::x()), &Vector3::y(), 1e-15);
    assert_vec_close(&(rot_x(q) * Vector3::y()), &Vector3::z(), 1e-15);
    assert_vec_close(&(rot_y(q) * Vector3::z()), &Vector3::x(), 1e-15);
    // The matrices of the contract, element by element, for a = 30°.
    let a = 30f64.to_radians();
    let (s, c) = (0.5, 3f64.sqrt() / 2.0);
    assert!((rot_x(a) - Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)).norm() < 1e-15);
    assert!((rot_y(a) - Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)).norm() < 1e-15);
    assert!((rot_z(a) - Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)).norm() < 1e-15);
}

#[test]
fn opk_is_rx_ry_rz_product() {
    let (o, p, k) = (10.0f64, -20.0f64, 135.0f64);
    let r = opk_to_matrix(o, p, k);
    let expected = rot_x(o.to_radians()) * rot_y(p.to_radians()) * rot_z(k.to_radians());
    assert!((r - expected).norm() < 1e-15);
    // Hand expansion: R[0][2] = sin φ, R[2][2] = cos ω cos φ, R[0][0] = cos φ cos κ.
    let (o, p, k) = (o.to_radians(), p.to_radians(), k.to_radians());
    assert!((r[(0, 2)] - p.sin()).abs() < 1e-15);
    assert!((r[(2, 2)] - o.cos() * p.cos()).abs() < 1e-15);
    assert!((r[(0, 0)] - p.cos() * k.cos()).abs() < 1e-15);
    assert!((r.determinant() - 1.0).abs() < 1e-14);
    assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-14);
}

#[test]
fn zero_opk_is_identity() {
    assert_eq!(opk_to_matrix(0.0, 0.0, 0.0), Matrix3::identity());
}

#[test]
fn matrix_to_opk_round_trips() {
    let mut cases = Vec::new();
    for &o in &[-179.0, -120.0, -45.0, -3.0, 0.0, 7.5, 60.0, 179.5] {
        for &p in &[-89.0, -45.0, -1.0, 0.0, 30.0, 88.9] {
            for &k in &[-170.0, -90.0, 0.0, 12.25, 90.0, 180.0] {
                cases.push((o, p, k));
            }
        }
    }
    for (o, p, k) in cases {
        let (o2, p2, k2) = matrix_to_opk(&opk_to_matrix(o, p, k));
        let r2 = opk_to_matrix(o2, p2, k2);
        assert!(
            (r2 - opk_to_matrix(o, p, k)).norm() < 1e-12,
            "({o},{p},{k}) -> ({o2},{p2},{k2})"
        );
        assert!((p2 - p).abs() < 1e-9, "phi ({o},{p},{k}) -> {p2}");
        let wrap = |a: f64| (a + 180.0).rem_euclid(360.0) - 180.0;
        assert!(wrap(o2 - o).abs() < 1e-9, "omega ({o},{p},{k}) -> {o2}");
        assert!(wrap(k2 - k).abs() < 1e-9, "kappa ({o},{p},{k}) -> {k2}");
    }
}

#[test]
fn matrix_to_opk_at_gimbal_lock_reproduces_the_matrix() {
    for &p in &[90.0, -90.0] {
        for &(o, k) in &[(0.0, 0.0), (30.0, 0.0), (20.0, 25.0), (-60.0, 100.0)] {
            let r = opk_to_matrix(o, p, k);
            let (o2, p2, k2) = matrix_to_opk(&r);
            assert!((p2 - p).abs() < 1e-6);
            assert!(
                (opk_to_matrix(o2, p2, k2) - r).norm() < 1e-9,
                "({o},{p},{k}) -> ({o2},{p2},{k2})"
            );
        }
    }
}

#[test]
fn panorama_rotation_is_the_documented_product() {
    let (y, p, r) = (12.0f64, -3.0f64, 4.5f64);
    let expected = rot_z(-y.to_radians()) * rot_x(p.to_radians()) * rot_y(r.to_radians());
    assert!((panorama_rotation(y, p, r) - expected).norm() < 1e-15);
    assert_eq!(panorama_rotation(0.0, 0.0, 0.0), Matrix3::identity());
}

//! Closest approach of two rays: skew lines by hand, consistency with triangulation, parallel rays.

use crate::geometry::{closest_approach, triangulate_rays, Ray};
use nalgebra::Vector3;

#[test]
fn skew_lines_by_hand() {
    // Line a: the x axis at z = 0; line b: parallel to y at x = 3, z = 2. Closest points (3,0,0) and (3,0,2).
    let o = Vector3::new(92_000.0, 437_000.0, 10.0);
    let a = Ray::new(
        o + Vector3::new(-1.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
    );
    let b = Ray::new(
        o + Vector3::new(3.0, -5.0, 2.0),
        Vector3::new(0.0, 1.0, 0.0),
    );
    let ca = closest_approach(&a, &b).unwrap();
    assert!((ca.point_a_world - (o + Vector3::new(3.0, 0.0, 0.0))).norm() < 1e-9);
    assert!((ca.point_b_world - (o + Vector3::new(3.0, 0.0, 2.0))).norm() < 1e-9);
    assert!((ca.distance_m - 2.0).abs() < 1e-12);
    assert!((ca.t_a_m - 4.0).abs() < 1e-12 && (ca.t_b_m - 5.0).abs() < 1e-12);
    assert!(ca.in_front_of_both());
    assert!((ca.midpoint_world() - (o + Vector3::new(3.0, 0.0, 1.0))).norm() < 1e-9);
}

#[test]
fn behind_an_origin_is_reported() {
    let a = Ray::new(Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0));
    let b = Ray::new(Vector3::new(-2.0, -1.0, 0.0), Vector3::new(0.0, 1.0, 0.0));
    let ca = closest_approach(&a, &b).unwrap();
    assert!((ca.t_a_m + 2.0).abs() < 1e-12 && (ca.t_b_m - 1.0).abs() < 1e-12);
    assert!(!ca.in_front_of_both());
    assert!(ca.distance_m < 1e-12);
}

#[test]
fn parallel_rays_give_none() {
    let d = Vector3::new(0.3, 0.4, -0.5);
    let a = Ray::new(Vector3::zeros(), d);
    let b = Ray::new(Vector3::new(1.0, 0.0, 0.0), d);
    assert_eq!(closest_approach(&a, &b), None);
    let anti = Ray::new(Vector3::new(1.0, 0.0, 0.0), -d);
    assert_eq!(closest_approach(&a, &anti), None);
}

#[test]
fn equals_equal_weight_triangulation_in_a_symmetric_setup() {
    let o = Vector3::new(92_000.0, 437_000.0, 0.0);
    let a = Ray::new(
        o + Vector3::new(-7.0, 0.0, 1.0),
        Vector3::new(7.0, 9.0, -0.02),
    );
    let b = Ray::new(
        o + Vector3::new(7.0, 0.0, 1.0),
        Vector3::new(-7.0, 9.0, 0.02),
    );
    let ca = closest_approach(&a, &b).unwrap();
    let t = triangulate_rays(&[a, b], &[1e-3, 1e-3]).unwrap();
    assert!((t.point_world - ca.midpoint_world()).norm() < 1e-9);
    assert!((t.residuals_m[0] - ca.distance_m / 2.0).abs() < 1e-9);
}

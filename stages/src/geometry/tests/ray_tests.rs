//! Ray–plane intersection.

use crate::geometry::{intersect_ray_plane, Plane, Ray};
use nalgebra::Vector3;

#[test]
fn ray_meets_ground_plane() {
    let origin = Vector3::new(92_000.0, 437_000.0, 2.5);
    let ray = Ray::new(origin, Vector3::new(1.0, 0.0, -1.0));
    let p = intersect_ray_plane(&ray, &Plane::horizontal(0.5)).unwrap();
    assert!((p - Vector3::new(92_002.0, 437_000.0, 0.5)).norm() < 1e-9);
}

#[test]
fn tilted_plane() {
    // Plane x + z = 1 through (1, 0, 0); ray from the origin along +x hits it at (1, 0, 0).
    let plane = Plane::new(Vector3::new(1.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 1.0));
    assert!((plane.normal.norm() - 1.0).abs() < 1e-15);
    let ray = Ray::new(Vector3::zeros(), Vector3::new(1.0, 0.0, 0.0));
    let p = intersect_ray_plane(&ray, &plane).unwrap();
    assert!((p - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-15);
    assert!(plane.signed_distance(&Vector3::new(2.0, 0.0, 0.0)) > 0.0);
}

#[test]
fn parallel_or_behind_gives_none() {
    let ground = Plane::horizontal(0.0);
    let horizontal = Ray::new(Vector3::new(0.0, 0.0, 2.0), Vector3::new(1.0, 1.0, 0.0));
    assert_eq!(intersect_ray_plane(&horizontal, &ground), None);
    let upwards = Ray::new(Vector3::new(0.0, 0.0, 2.0), Vector3::new(0.0, 0.3, 1.0));
    assert_eq!(intersect_ray_plane(&upwards, &ground), None);
    // A ray starting on the plane meets it at its origin.
    let on_plane = Ray::new(Vector3::new(3.0, 4.0, 0.0), Vector3::new(0.0, 0.0, -1.0));
    assert_eq!(
        intersect_ray_plane(&on_plane, &ground),
        Some(Vector3::new(3.0, 4.0, 0.0))
    );
}

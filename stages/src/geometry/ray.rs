//! Rays and planes in the world frame, and their intersection (e.g. projecting panorama pixels onto the
//! road plane for ortho-images, thesis 3.4.4).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// A half-line `origin + t·dir`, t ≥ 0, world frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ray {
    /// Start point, world frame, metres.
    pub origin_world: Vector3<f64>,
    /// Unit direction, world frame.
    pub dir_world: Vector3<f64>,
}

impl Ray {
    /// A ray from `origin_world` along `dir_world` (normalised here; must be non-zero).
    pub fn new(origin_world: Vector3<f64>, dir_world: Vector3<f64>) -> Self {
        Self {
            origin_world,
            dir_world: dir_world.normalize(),
        }
    }

    /// The point at distance `t_m` along the ray.
    pub fn at(&self, t_m: f64) -> Vector3<f64> {
        self.origin_world + self.dir_world * t_m
    }
}

/// A plane through `point_world` with unit `normal` (world frame).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plane {
    /// Any point of the plane, world frame, metres.
    pub point_world: Vector3<f64>,
    /// Unit normal, world frame.
    pub normal: Vector3<f64>,
}

impl Plane {
    /// A plane through `point_world` with normal `normal` (normalised here; must be non-zero).
    pub fn new(point_world: Vector3<f64>, normal: Vector3<f64>) -> Self {
        Self {
            point_world,
            normal: normal.normalize(),
        }
    }

    /// The horizontal plane Z = `z_m`.
    pub fn horizontal(z_m: f64) -> Self {
        Self {
            point_world: Vector3::new(0.0, 0.0, z_m),
            normal: Vector3::z(),
        }
    }

    /// Signed distance of a point from the plane, metres (positive on the side the normal points to).
    pub fn signed_distance(&self, p_world: &Vector3<f64>) -> f64 {
        (p_world - self.point_world).dot(&self.normal)
    }
}

/// Cosine below which a ray counts as parallel to a plane.
const PARALLEL_COS: f64 = 1e-12;

/// Where the ray meets the plane; `None` if it is parallel to the plane or the plane lies behind its origin.
pub fn intersect_ray_plane(ray: &Ray, plane: &Plane) -> Option<Vector3<f64>> {
    let denom = plane.normal.dot(&ray.dir_world);
    if !(denom.abs() > PARALLEL_COS * ray.dir_world.norm()) {
        return None;
    }
    // Difference first: both points are large world coordinates.
    let t_m = (plane.point_world - ray.origin_world).dot(&plane.normal) / denom;
    if !(t_m >= 0.0 && t_m.is_finite()) {
        return None;
    }
    Some(ray.at(t_m))
}

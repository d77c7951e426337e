//! Closest approach of two lines (the two-ray triangulation in closed form, Hartley & Zisserman 2004, ch. 12): used to judge
//! correspondences by the distance at which their rays pass each other (campaign-format.md, "Truth").

use super::ray::Ray;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The closest points of the lines through two rays.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClosestApproach {
    /// Closest point on the first line, world frame, metres.
    pub point_a_world: Vector3<f64>,
    /// Closest point on the second line, world frame, metres.
    pub point_b_world: Vector3<f64>,
    /// Signed distance of `point_a_world` along the first ray (negative: behind its origin), metres.
    pub t_a_m: f64,
    /// Signed distance of `point_b_world` along the second ray, metres.
    pub t_b_m: f64,
    /// Distance between the two closest points (the miss distance), metres.
    pub distance_m: f64,
}

impl ClosestApproach {
    /// Midpoint of the two closest points (the unweighted two-ray triangulation).
    pub fn midpoint_world(&self) -> Vector3<f64> {
        self.point_b_world + (self.point_a_world - self.point_b_world) * 0.5
    }

    /// True if the closest points lie in front of both ray origins.
    pub fn in_front_of_both(&self) -> bool {
        self.t_a_m > 0.0 && self.t_b_m > 0.0
    }
}

/// Smallest accepted `1 − (d_a·d_b)²` (≈ 1e-6 rad between the rays); below it the lines count as parallel.
const MIN_SIN2: f64 = 1e-12;

/// Closest approach of the lines through `a` and `b` (unit directions); `None` if they are (nearly)
/// parallel. With `b = d_a·d_b`, `w0 = c_a − c_b`, `p = d_a·w0`, `q = d_b·w0`:
/// `t_a = (b q − p)/(1 − b²)`, `t_b = (q − b p)/(1 − b²)`.
pub fn closest_approach(a: &Ray, b: &Ray) -> Option<ClosestApproach> {
    let cos = a.dir_world.dot(&b.dir_world);
    let sin2 = 1.0 - cos * cos;
    if !(sin2 > MIN_SIN2) {
        return None;
    }
    // Origins differenced first: world coordinates are large.
    let w0 = a.origin_world - b.origin_world;
    let p = a.dir_world.dot(&w0);
    let q = b.dir_world.dot(&w0);
    let t_a_m = (cos * q - p) / sin2;
    let t_b_m = (q - cos * p) / sin2;
    // Points relative to b's origin, then shifted back, to keep the difference exact.
    let rel_a = w0 + a.dir_world * t_a_m;
    let rel_b = b.dir_world * t_b_m;
    Some(ClosestApproach {
        point_a_world: b.origin_world + rel_a,
        point_b_world: b.origin_world + rel_b,
        t_a_m,
        t_b_m,
        distance_m: (rel_a - rel_b).norm(),
    })
}

//! The horizontal position of a control point seen in one aerial nadir image.
//!
//! One ray does not fix a height, but a nadir ray is close to vertical (≈ 1° off at the edge of a frame taken
//! from 4.5 km), so at any height near the ground its horizontal position is known to the aerial matching's
//! precision: a height error δz moves it by δz · tan(tilt), a few millimetres per decimetre. The verification
//! compares the horizontal position of such a point with its MM triangulation, at the MM point's own height.

use crate::geometry::{intersect_ray_plane, Plane, Ray};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// One aerial ray, described where it crosses the ground.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AerialRayGround {
    /// The ray's point at the height it was evaluated at (world frame, m): the MM tie point's height.
    pub point_world: [f64; 3],
    /// How far the ray's point moves horizontally per metre of height (world x, y per m; tan of the tilt).
    pub xy_per_z: [f64; 2],
    /// σ of the horizontal position at a known height (the observation's σ_px × the GSD there), m.
    pub sigma_xy_m: f64,
}

impl AerialRayGround {
    /// From two distinct points of the ray at different heights (world frame, m); `None` when they are at
    /// the same height or not finite.
    pub fn through(
        at_height_world: &Vector3<f64>,
        other_world: &Vector3<f64>,
        sigma_xy_m: f64,
    ) -> Option<Self> {
        let dz = other_world.z - at_height_world.z;
        let slope = [
            (other_world.x - at_height_world.x) / dz,
            (other_world.y - at_height_world.y) / dz,
        ];
        let finite = slope.iter().all(|v| v.is_finite())
            && at_height_world.iter().all(|v| v.is_finite())
            && sigma_xy_m.is_finite();
        (finite && dz != 0.0).then(|| Self {
            point_world: [at_height_world.x, at_height_world.y, at_height_world.z],
            xy_per_z: slope,
            sigma_xy_m,
        })
    }

    /// From a ray in a Cartesian frame, evaluated at height `z_m`; `None` when the ray is (near) horizontal or
    /// points away from that height.
    pub fn from_ray(ray: &Ray, z_m: f64, sigma_xy_m: f64) -> Option<Self> {
        let at = intersect_ray_plane(ray, &Plane::horizontal(z_m))?;
        // A point one metre of height further along the ray (either way along it).
        let step = 1.0 / ray.dir_world.z;
        Self::through(&at, &(at + ray.dir_world * step), sigma_xy_m)
    }

    /// The ray's horizontal position at height `z_m` (world x, y, m).
    pub fn xy_at(&self, z_m: f64) -> [f64; 2] {
        let dz = z_m - self.point_world[2];
        [
            self.point_world[0] + self.xy_per_z[0] * dz,
            self.point_world[1] + self.xy_per_z[1] * dz,
        ]
    }

    /// Horizontal variance (per axis, m²) of [`Self::xy_at`] when the height itself has variance
    /// `z_variance_m2`.
    pub fn xy_variance_m2(&self, z_variance_m2: f64) -> [f64; 2] {
        let own = self.sigma_xy_m * self.sigma_xy_m;
        let z = z_variance_m2.max(0.0);
        [
            own + self.xy_per_z[0].powi(2) * z,
            own + self.xy_per_z[1].powi(2) * z,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tilted_ray_moves_with_height_by_its_slope() {
        // From 1000 m up, 10 m east per 1000 m down: 0.01 m per metre of height.
        let ray = Ray {
            origin_world: Vector3::new(100.0, 200.0, 1000.0),
            dir_world: Vector3::new(10.0, -5.0, -1000.0).normalize(),
        };
        let g = AerialRayGround::from_ray(&ray, 0.0, 0.05).unwrap();
        assert!((g.point_world[0] - 110.0).abs() < 1e-9);
        assert!((g.point_world[1] - 195.0).abs() < 1e-9);
        assert!((g.xy_per_z[0] + 0.01).abs() < 1e-12);
        assert!((g.xy_per_z[1] - 0.005).abs() < 1e-12);
        let [x, y] = g.xy_at(2.0);
        assert!((x - 109.98).abs() < 1e-9 && (y - 195.01).abs() < 1e-9);
        let [vx, vy] = g.xy_variance_m2(4.0);
        assert!((vx - (0.0025 + 0.0004)).abs() < 1e-12);
        assert!((vy - (0.0025 + 0.0001)).abs() < 1e-12);
    }

    #[test]
    fn a_horizontal_ray_has_no_ground_position() {
        let ray = Ray {
            origin_world: Vector3::new(0.0, 0.0, 10.0),
            dir_world: Vector3::new(1.0, 0.0, 0.0),
        };
        assert!(AerialRayGround::from_ray(&ray, 0.0, 0.05).is_none());
        let p = Vector3::new(1.0, 2.0, 3.0);
        assert!(AerialRayGround::through(&p, &p, 0.05).is_none());
    }
}

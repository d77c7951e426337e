//! The recording vehicle's body (roof, bonnet) as seen from the panorama camera — thesis 3.4.3, Figure 3.4.
//!
//! The car is modelled as a box under the camera, aligned with `heading`: its top face lies `roof_drop_m` below the
//! projection centre and spans `rear_m` behind to `front_m` ahead of it and `half_width_m` to each side. A ground
//! point is hidden when its ray to the camera pierces that top face. Real campaigns set these from the vehicle;
//! the defaults are the silhouette of the synthetic campaign's car (camera 0.4 m above the roof; bonnet and boot
//! projected onto the roof plane, plus a 5 cm margin) — set them for your vehicle.

use nalgebra::Vector3;

crate::params! {
    /// Box model of the recording vehicle in its own frame (x forward along `heading`, y to the left).
    #[derive(Copy)]
    pub struct VehicleMask {
        /// Mask the vehicle at all.
        enabled: bool = true;
        /// Find the box in the panoramas (the `vehicle` stage) and use the values below only when that fails;
        /// `false` = use the values below (an override for a known vehicle).
        detect: bool = true;
        /// Vertical distance from the projection centre down to the vehicle's top face.
        roof_drop_m: f64 = 0.4, unit "m", min 0.0, below 20.0;
        /// Extent of the body ahead of the projection centre (bonnet).
        front_m: f64 = 0.75, unit "m", min 0.0, below 20.0;
        /// Extent of the body behind the projection centre.
        rear_m: f64 = 1.25, unit "m", min 0.0, below 20.0;
        /// Half the body width.
        half_width_m: f64 = 0.75, unit "m", min 0.0, below 20.0;
    }
}

impl VehicleMask {
    /// Whether the ray from the camera (at `camera_world`, vehicle heading `heading_deg` clockwise from grid north)
    /// towards `point_world` passes through the vehicle's top face, i.e. the point is hidden by the car.
    pub fn hides(
        &self,
        camera_world: &Vector3<f64>,
        heading_deg: f64,
        point_world: &Vector3<f64>,
    ) -> bool {
        let h = heading_deg.to_radians();
        self.hides_direction(h.sin_cos(), &(point_world - camera_world))
    }

    /// [`Self::hides`] for the offset `d` (world, metres) from the camera to the point, with the heading given as
    /// (sin, cos) of its angle (for callers testing many points of one recording: no trigonometry per point).
    #[inline]
    pub fn hides_direction(&self, (sin_h, cos_h): (f64, f64), d: &Vector3<f64>) -> bool {
        // A point above the roof plane (depth ≤ roof_drop) is never hidden. Below it, where the ray meets the roof
        // plane it is scaled by roof_drop / depth (> 0): compare scaled offsets with the body's extent multiplied by
        // depth instead (no division per point). Non-short-circuit `&` keeps it branch-free (vectorisable).
        let depth_m = -d.z;
        let forward = (d.x * sin_h + d.y * cos_h) * self.roof_drop_m;
        let left = (-d.x * cos_h + d.y * sin_h) * self.roof_drop_m;
        self.enabled
            & (depth_m > self.roof_drop_m)
            & (forward <= self.front_m * depth_m)
            & (forward >= -self.rear_m * depth_m)
            & (left.abs() <= self.half_width_m * depth_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_under_the_bonnet_are_hidden_and_points_beside_are_not() {
        let m = VehicleMask::default();
        let cam = Vector3::new(100.0, 200.0, 2.2);
        // Heading east: 2 m ahead of the camera on the ground, the ray meets the roof plane at 0.36 m ahead.
        assert!(m.hides(&cam, 90.0, &Vector3::new(102.0, 200.0, 0.0)));
        // 8 m to the north (left of an east-bound car) is far outside the body's side.
        assert!(!m.hides(&cam, 90.0, &Vector3::new(100.0, 208.0, 0.0)));
        // 20 m ahead: the ray meets the roof plane at 3.6 m ahead, beyond the bonnet.
        assert!(!m.hides(&cam, 90.0, &Vector3::new(120.0, 200.0, 0.0)));
        // Same geometry heading north: now (0, +2) is ahead.
        assert!(m.hides(&cam, 0.0, &Vector3::new(100.0, 202.0, 0.0)));
        let off = VehicleMask {
            enabled: false,
            ..m
        };
        assert!(!off.hides(&cam, 0.0, &Vector3::new(100.0, 202.0, 0.0)));
    }
}

//! The street-local frame: world = origin_world + Rz(heading) · local (Z is shared, no scaling).
//! All intersection maths runs in local f64 metres so centimetres are never lost to 6-digit world values.

use nalgebra::Vector3;

/// Rigid 2-D transform between the street-local frame and the world frame (Z unchanged).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalFrame {
    pub origin_world: [f64; 2],
    cos_h: f64,
    sin_h: f64,
}

impl LocalFrame {
    /// `heading_deg`: direction of local +x, counter-clockwise from world east.
    pub fn new(origin_world: [f64; 2], heading_deg: f64) -> Self {
        let h = heading_deg.to_radians();
        Self {
            origin_world,
            cos_h: h.cos(),
            sin_h: h.sin(),
        }
    }

    /// World XY of a local XY point.
    #[inline]
    pub fn to_world_xy(&self, local: [f64; 2]) -> [f64; 2] {
        [
            self.origin_world[0] + self.cos_h * local[0] - self.sin_h * local[1],
            self.origin_world[1] + self.sin_h * local[0] + self.cos_h * local[1],
        ]
    }

    /// Local XY of a world XY point.
    #[inline]
    pub fn to_local_xy(&self, world: [f64; 2]) -> [f64; 2] {
        let dx = world[0] - self.origin_world[0];
        let dy = world[1] - self.origin_world[1];
        [
            self.cos_h * dx + self.sin_h * dy,
            -self.sin_h * dx + self.cos_h * dy,
        ]
    }

    #[inline]
    pub fn point_to_local(&self, p_world: &Vector3<f64>) -> Vector3<f64> {
        let l = self.to_local_xy([p_world.x, p_world.y]);
        Vector3::new(l[0], l[1], p_world.z)
    }

    #[inline]
    pub fn point_to_world(&self, p_local: &Vector3<f64>) -> Vector3<f64> {
        let w = self.to_world_xy([p_local.x, p_local.y]);
        Vector3::new(w[0], w[1], p_local.z)
    }

    #[inline]
    pub fn dir_to_local(&self, d_world: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(
            self.cos_h * d_world.x + self.sin_h * d_world.y,
            -self.sin_h * d_world.x + self.cos_h * d_world.y,
            d_world.z,
        )
    }

    #[inline]
    pub fn dir_to_world(&self, d_local: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(
            self.cos_h * d_local.x - self.sin_h * d_local.y,
            self.sin_h * d_local.x + self.cos_h * d_local.y,
            d_local.z,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_heading() {
        let f = LocalFrame::new([92_000.0, 437_000.0], 90.0);
        // local +x points to world north when heading is 90°
        let w = f.to_world_xy([10.0, 0.0]);
        assert!((w[0] - 92_000.0).abs() < 1e-9 && (w[1] - 437_010.0).abs() < 1e-9);
        let f = LocalFrame::new([92_000.0, 437_000.0], 23.0);
        let l = f.to_local_xy(f.to_world_xy([123.456, -78.9]));
        assert!((l[0] - 123.456).abs() < 1e-9 && (l[1] + 78.9).abs() < 1e-9);
        let d = f.dir_to_world(&f.dir_to_local(&Vector3::new(0.3, -0.4, 0.5)));
        assert!((d - Vector3::new(0.3, -0.4, 0.5)).norm() < 1e-12);
    }
}

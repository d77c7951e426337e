//! The recording vehicle's body as seen by its own panorama camera: a few boxes (roof, lower body, bonnet)
//! fixed to the camera and oriented by the heading, in dark paint, so that the bottom of every panorama shows
//! the car and masking it matters (campaign-format.md: the vehicle extent is not part of the format).
//!
//! Vehicle frame: origin at the panorama's projection centre, x to the right of the driving direction,
//! y forward (driving direction), z up; the road is at z = −camera height.

use nalgebra::Vector3;

/// Axis-aligned box in the vehicle frame, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
struct VehicleBox {
    min_m: [f64; 3],
    max_m: [f64; 3],
}

impl VehicleBox {
    /// Entry distance and axis (0, 1, 2) and side (−1/+1) of the face hit, for a ray from the origin.
    fn hit_from_origin(&self, dir: &[f64; 3]) -> Option<(f64, usize, f64)> {
        let (mut t_near, mut t_far) = (0.0_f64, f64::INFINITY);
        let mut face = (usize::MAX, 0.0);
        for axis in 0..3 {
            if dir[axis].abs() < 1e-15 {
                if 0.0 < self.min_m[axis] || 0.0 > self.max_m[axis] {
                    return None;
                }
                continue;
            }
            let t1 = self.min_m[axis] / dir[axis];
            let t2 = self.max_m[axis] / dir[axis];
            let (t_in, t_out, side) = if t1 < t2 {
                (t1, t2, -1.0)
            } else {
                (t2, t1, 1.0)
            };
            if t_in > t_near {
                t_near = t_in;
                face = (axis, side);
            }
            t_far = t_far.min(t_out);
            if t_near > t_far {
                return None;
            }
        }
        (face.0 != usize::MAX).then_some((t_near, face.0, face.1))
    }
}

/// The vehicle body for one panorama.
#[derive(Clone, Debug, PartialEq)]
pub struct VehicleBody {
    boxes: [VehicleBox; 3],
    /// World directions of the vehicle x (right) and y (forward) axes.
    right_world: [f64; 2],
    forward_world: [f64; 2],
}

/// Linear RGB of the paint on top faces (lit by the sky) and on side faces.
const PAINT_TOP: [f32; 3] = [0.10, 0.11, 0.13];
const PAINT_SIDE: [f32; 3] = [0.045, 0.05, 0.06];
const PAINT_SIDE_FRONT: [f32; 3] = [0.06, 0.065, 0.075];

impl VehicleBody {
    /// A car under a camera mounted `camera_height_m` above the road (≈ 0.4 m above the roof), driving towards
    /// `heading_deg` (clockwise from grid north).
    pub fn standard(heading_deg: f64, camera_height_m: f64) -> Self {
        let road = -camera_height_m;
        let bottom = road + 0.25;
        let boxes = [
            // Roof (narrower than the body), its top 0.4 m below the camera.
            VehicleBox {
                min_m: [-0.7, -0.9, -0.9],
                max_m: [0.7, 0.5, -0.4],
            },
            // Lower body (doors, boot).
            VehicleBox {
                min_m: [-0.9, -2.6, bottom],
                max_m: [0.9, 0.6, -0.9],
            },
            // Bonnet ahead of the windscreen.
            VehicleBox {
                min_m: [-0.85, 0.6, bottom],
                max_m: [0.85, 1.9, road + 1.05],
            },
        ];
        let (s, c) = heading_deg.to_radians().sin_cos();
        Self {
            boxes,
            right_world: [c, -s],
            forward_world: [s, c],
        }
    }

    /// Distance (m) and paint colour of the body along the world direction `dir_world` from the camera, if hit.
    pub fn hit(&self, dir_world: &Vector3<f64>) -> Option<(f64, [f32; 3])> {
        let d = [
            dir_world.x * self.right_world[0] + dir_world.y * self.right_world[1],
            dir_world.x * self.forward_world[0] + dir_world.y * self.forward_world[1],
            dir_world.z,
        ];
        let mut best: Option<(f64, [f32; 3])> = None;
        for b in &self.boxes {
            if let Some((t, axis, side)) = b.hit_from_origin(&d) {
                if best.is_none_or(|(bt, _)| t < bt) {
                    let colour = match (axis, side > 0.0) {
                        (2, true) => PAINT_TOP,
                        (1, true) => PAINT_SIDE_FRONT,
                        _ => PAINT_SIDE,
                    };
                    best = Some((t, colour));
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_down_hits_the_roof_top_0_4_m_below() {
        let v = VehicleBody::standard(37.0, 2.2);
        let (t, c) = v.hit(&Vector3::new(0.0, 0.0, -1.0)).unwrap();
        assert!((t - 0.4).abs() < 1e-12);
        assert_eq!(c, PAINT_TOP);
    }

    #[test]
    fn bonnet_is_ahead_and_the_horizon_is_free() {
        // Heading east: the bonnet lies east of the camera, below.
        let v = VehicleBody::standard(90.0, 2.2);
        let ahead_down = Vector3::new(1.5, 0.0, -1.2).normalize();
        let (t, _) = v.hit(&ahead_down).unwrap();
        assert!(t > 0.5 && t < 2.5, "bonnet at {t} m");
        let behind_same = Vector3::new(-1.5, 0.0, -1.2).normalize();
        assert!(v.hit(&behind_same).is_some(), "boot/body behind");
        for az in 0..36 {
            let a = (az as f64 * 10.0).to_radians();
            assert!(
                v.hit(&Vector3::new(a.sin(), a.cos(), -0.05)).is_none(),
                "horizon free at {az}0°"
            );
            assert!(v.hit(&Vector3::new(a.sin(), a.cos(), 0.3)).is_none());
        }
    }
}

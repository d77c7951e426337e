//! Aerial image observations in the bundle (thesis 5.4.3 names this "classical bundle adjustment
//! by locking the exterior orientation of the aerial cameras", 6.1 item 4): a tie point's pixel in a nadir or
//! oblique aerial image whose orientation is held fixed, so a point seen in a single aerial image also
//! constrains the block.
//!
//! Model (campaign-format.md "Aerial frame images", [`crate::geometry::FrameCamera::project_world`]):
//! `p = Rᵀ(X − C)` in the camera frame (x right, y up, z backwards), `x = p.x/(−p.z)`, `y = p.y/(−p.z)`,
//! Brown distortion `(x_d, y_d) = D(x, y)`, `u = cx + f·x_d`, `v = cy − f·y_d`. The residual is
//! `(u − u_obs, v − v_obs)` in pixels; the Jacobian with respect to the point X (the only unknown: the camera
//! is fixed) is `diag(f, −f) · ∂D/∂(x,y) · ∂(x,y)/∂p · Rᵀ`. Everything is in the solver's local frame.

use crate::geometry::{BrownDistortion, FrameCamera, LocalOrigin};
use nalgebra::{Matrix2x3, Matrix3, Vector2, Vector3};

/// A fixed aerial camera in the solver's local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedFrameCamera {
    /// Projection centre, local frame, metres.
    pub center_local: Vector3<f64>,
    /// Rᵀ: maps world (= local, a pure shift) vectors to the camera frame.
    pub rotation_world_to_cam: Matrix3<f64>,
    pub focal_px: f64,
    pub cx_px: f64,
    pub cy_px: f64,
    pub distortion: BrownDistortion,
    /// Largest ideal r² where the distortion is still monotonic (beyond it the projection folds back).
    pub max_r2: f64,
}

impl FixedFrameCamera {
    /// The camera `camera` (world frame) expressed in the local frame of `origin`.
    pub fn new(camera: &FrameCamera, origin: &LocalOrigin) -> Self {
        Self {
            center_local: origin.to_local(&camera.center_world),
            rotation_world_to_cam: camera.rotation_cam_to_world.transpose(),
            focal_px: camera.focal_px,
            cx_px: camera.cx_px,
            cy_px: camera.cy_px,
            distortion: camera.distortion,
            max_r2: if camera.distortion.is_zero() {
                f64::INFINITY
            } else {
                camera.distortion.max_monotonic_r2()
            },
        }
    }

    /// Residual (projected − observed, pixels) of an observation `(u_obs, v_obs)` of `point_local`, and its
    /// 2 × 3 Jacobian with respect to the point. `None` if the point is not in front of the camera or beyond
    /// the monotonic range of the distortion.
    pub fn residual(
        &self,
        observed_px: (f64, f64),
        point_local: &Vector3<f64>,
    ) -> Option<(Vector2<f64>, Matrix2x3<f64>)> {
        let p = self.rotation_world_to_cam * (point_local - self.center_local);
        // NaN-safe: a non-finite depth is rejected too.
        if p.z.partial_cmp(&0.0) != Some(std::cmp::Ordering::Less) {
            return None;
        }
        let inv_depth = 1.0 / -p.z;
        let x = p.x * inv_depth;
        let y = p.y * inv_depth;
        if (x * x + y * y).partial_cmp(&self.max_r2) != Some(std::cmp::Ordering::Less) {
            return None;
        }
        let (xd, yd) = self.distortion.distort(x, y);
        let u = self.cx_px + self.focal_px * xd;
        let v = self.cy_px - self.focal_px * yd;
        let r = Vector2::new(u - observed_px.0, v - observed_px.1);
        // ∂(x, y)/∂p: x = p.x / (−p.z) ⇒ ∂x/∂p.x = 1/(−p.z), ∂x/∂p.z = x/(−p.z); likewise for y.
        let d_xy_dp = Matrix2x3::new(inv_depth, 0.0, x * inv_depth, 0.0, inv_depth, y * inv_depth);
        let [[a, b], [c, d]] = self.distortion.distort_jacobian(x, y);
        let f = self.focal_px;
        let d_uv_dxy = nalgebra::Matrix2::new(f * a, f * b, -f * c, -f * d);
        let jacobian = d_uv_dxy * d_xy_dp * self.rotation_world_to_cam;
        Some((r, jacobian))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn oblique_camera() -> FrameCamera {
        FrameCamera::from_opk(
            Vector3::new(250_040.0, 5_600_010.0, 400.0),
            40.0,
            5.0,
            -30.0,
            9000.0,
            2010.5,
            1490.25,
            4000,
            3000,
            BrownDistortion {
                k1: -0.08,
                k2: 0.02,
                p1: 0.0007,
                p2: -0.0004,
                ..BrownDistortion::NONE
            },
        )
    }

    #[test]
    fn residual_matches_project_world_and_jacobian_matches_finite_differences() {
        let cam = oblique_camera();
        let origin = LocalOrigin::new(Vector3::new(250_000.0, 5_600_000.0, 100.0));
        let fixed = FixedFrameCamera::new(&cam, &origin);
        // A point the camera sees off-axis (distortion matters).
        let dir = cam.pixel_to_ray_world(600.0, 2700.0);
        let point_world = cam.center_world + dir * 420.0;
        let (u, v) = cam.project_world(&point_world).unwrap();
        assert!((u - 600.0).abs() < 1e-6 && (v - 2700.0).abs() < 1e-6);
        let point_local = origin.to_local(&point_world);
        let (r, _) = fixed.residual((u, v), &point_local).unwrap();
        assert!(r.norm() < 1e-6, "{r:?}");
        // Jacobian against central differences (metres → pixels, so h = 1 mm is well conditioned).
        let x1 = point_local + Vector3::new(0.7, -0.4, 0.3);
        let (_, jac) = fixed.residual((u, v), &x1).unwrap();
        let h = 1e-3;
        for k in 0..3 {
            let (mut xp, mut xm) = (x1, x1);
            xp[k] += h;
            xm[k] -= h;
            let rp = fixed.residual((u, v), &xp).unwrap().0;
            let rm = fixed.residual((u, v), &xm).unwrap().0;
            let numeric = (rp - rm) / (2.0 * h);
            for row in 0..2 {
                let scale = jac[(row, k)].abs().max(1.0);
                assert!(
                    (numeric[row] - jac[(row, k)]).abs() < 1e-6 * scale,
                    "d r{row} / d X{k}: numeric {} analytic {}",
                    numeric[row],
                    jac[(row, k)]
                );
            }
        }
        // Behind the camera: no residual.
        let behind = origin.to_local(&(cam.center_world - dir * 10.0));
        assert!(fixed.residual((u, v), &behind).is_none());
    }
}

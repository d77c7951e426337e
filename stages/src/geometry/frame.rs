//! The aerial frame (pinhole) camera of the campaign contract (campaign-format.md, "Aerial frame images"):
//! camera frame x right, y up, z backwards (the camera looks along −z); `P_world = C + R·p_cam` with
//! `R = Rx(ω)·Ry(φ)·Rz(κ)`; `x = p.x/(−p.z)`, `y = p.y/(−p.z)`, Brown distortion, `u = cx + f·x_d`,
//! `v = cy − f·y_d`.

pub use super::distortion::BrownDistortion;
use super::ray::Ray;
use super::rotation::opk_to_matrix;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// A calibrated, oriented frame camera (nadir or oblique aerial image).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameCamera {
    /// Projection centre, world frame, metres.
    pub center_world: Vector3<f64>,
    /// Maps camera-frame vectors to world-frame vectors.
    pub rotation_cam_to_world: Matrix3<f64>,
    /// Principal distance, pixels.
    pub focal_px: f64,
    /// Principal point, continuous pixel coordinates.
    pub cx_px: f64,
    pub cy_px: f64,
    pub width_px: u32,
    pub height_px: u32,
    pub distortion: BrownDistortion,
}

impl FrameCamera {
    /// A camera from its centre, ω-φ-κ attitude (degrees) and interior orientation.
    #[allow(clippy::too_many_arguments)]
    pub fn from_opk(
        center_world: Vector3<f64>,
        omega_deg: f64,
        phi_deg: f64,
        kappa_deg: f64,
        focal_px: f64,
        cx_px: f64,
        cy_px: f64,
        width_px: u32,
        height_px: u32,
        distortion: BrownDistortion,
    ) -> Self {
        Self {
            center_world,
            rotation_cam_to_world: opk_to_matrix(omega_deg, phi_deg, kappa_deg),
            focal_px,
            cx_px,
            cy_px,
            width_px,
            height_px,
            distortion,
        }
    }

    /// World point → camera frame (metres): `p = Rᵀ (P − C)`.
    pub fn world_to_cam(&self, p_world: &Vector3<f64>) -> Vector3<f64> {
        self.rotation_cam_to_world.transpose() * (p_world - self.center_world)
    }

    /// Continuous pixel of a world point (with distortion), whether or not it falls inside the image
    /// (see [`Self::contains`]); `None` if the point is not in front of the camera (p_cam.z ≥ 0), or so far
    /// off-axis that the distortion polynomial folds back ([`BrownDistortion::max_monotonic_r2`]; such a
    /// point would otherwise appear at a wrong place inside the image).
    pub fn project_world(&self, p_world: &Vector3<f64>) -> Option<(f64, f64)> {
        let p = self.world_to_cam(p_world);
        if !(p.z < 0.0) {
            return None;
        }
        let x = p.x / -p.z;
        let y = p.y / -p.z;
        if !self.distortion.is_zero() && !(x * x + y * y < self.distortion.max_monotonic_r2()) {
            return None;
        }
        let (xd, yd) = self.distortion.distort(x, y);
        Some((
            self.cx_px + self.focal_px * xd,
            self.cy_px - self.focal_px * yd,
        ))
    }

    /// Unit direction in the world frame of a continuous pixel (distortion removed).
    pub fn pixel_to_ray_world(&self, u_px: f64, v_px: f64) -> Vector3<f64> {
        let xd = (u_px - self.cx_px) / self.focal_px;
        let yd = (self.cy_px - v_px) / self.focal_px;
        let (x, y) = self.distortion.undistort(xd, yd);
        (self.rotation_cam_to_world * Vector3::new(x, y, -1.0)).normalize()
    }

    /// The ray from the projection centre through a continuous pixel (world frame, distortion removed).
    pub fn pixel_ray(&self, u_px: f64, v_px: f64) -> Ray {
        Ray {
            origin_world: self.center_world,
            dir_world: self.pixel_to_ray_world(u_px, v_px),
        }
    }

    /// Angular standard deviation (radians) of a pixel measurement with standard deviation `sigma_px` at the
    /// principal point (σ_px / f; off-axis pixels subtend slightly smaller angles, so this is conservative).
    pub fn angular_sigma_rad(&self, sigma_px: f64) -> f64 {
        sigma_px / self.focal_px
    }

    /// True if the continuous pixel lies in the image: 0 ≤ u < W and 0 ≤ v < H.
    pub fn contains(&self, u_px: f64, v_px: f64) -> bool {
        (0.0..f64::from(self.width_px)).contains(&u_px)
            && (0.0..f64::from(self.height_px)).contains(&v_px)
    }

    /// Unit viewing direction (the camera's −z axis) in the world frame.
    pub fn viewing_direction_world(&self) -> Vector3<f64> {
        -self.rotation_cam_to_world.column(2).into_owned()
    }

    /// Ground sampling distance at a world point, metres per pixel: depth along the viewing axis divided by
    /// the focal length (negative for points behind the camera).
    pub fn gsd_at(&self, p_world: &Vector3<f64>) -> f64 {
        let depth_m = (p_world - self.center_world).dot(&self.viewing_direction_world());
        depth_m / self.focal_px
    }
}

//! The equirectangular panorama camera of the campaign contract (campaign-format.md, "Panorama geometry";
//! Hartley & Zisserman 2004, ch. 12; thesis 3.4.4.5).
//!
//! For an image of W × H pixels (W = 2H) a continuous pixel (u, v) has azimuth `A = 360°·u/W − 180°`
//! (clockwise from grid north), elevation `E = 90° − 180°·v/H` and panorama-frame direction
//! `d_pano = (cos E sin A, cos E cos A, sin E)` (east, north, up); the world direction is
//! `d_world = R·d_pano` with `R = Rz(−yaw)·Rx(pitch)·Ry(roll)` ([`panorama_rotation`]).

use super::atan2_poly::atan2_poly;
use super::ray::Ray;
use super::rotation::panorama_rotation;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// An equirectangular panorama with its projection centre and orientation in the world frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PanoramaCamera {
    pub width_px: u32,
    pub height_px: u32,
    /// Projection centre, world frame, metres.
    pub center_world: Vector3<f64>,
    /// Maps panorama-frame directions to world-frame directions (identity for a levelled, north-up panorama).
    pub rotation_pano_to_world: Matrix3<f64>,
}

impl PanoramaCamera {
    /// A panorama of `width_px × height_px` at `center_world` with residual rotation yaw/pitch/roll (degrees).
    pub fn new(
        width_px: u32,
        height_px: u32,
        center_world: Vector3<f64>,
        yaw_deg: f64,
        pitch_deg: f64,
        roll_deg: f64,
    ) -> Self {
        Self {
            width_px,
            height_px,
            center_world,
            rotation_pano_to_world: panorama_rotation(yaw_deg, pitch_deg, roll_deg),
        }
    }

    /// Angular size of one pixel, radians (2π/W; equal in both directions when W = 2H).
    pub fn pixel_angle_rad(&self) -> f64 {
        TAU / f64::from(self.width_px)
    }

    /// Angular standard deviation (radians) of a pixel measurement with standard deviation `sigma_px`
    /// (Hartley & Zisserman 2004, ch. 12: σ_θ = σ_px·2π/W), e.g. for [`super::triangulate_rays`].
    pub fn angular_sigma_rad(&self, sigma_px: f64) -> f64 {
        sigma_px * self.pixel_angle_rad()
    }

    /// The ray from the projection centre through a continuous pixel (world frame).
    pub fn pixel_ray(&self, u_px: f64, v_px: f64) -> Ray {
        Ray {
            origin_world: self.center_world,
            dir_world: self.pixel_to_ray_world(u_px, v_px),
        }
    }

    /// Unit direction in the panorama frame (before the residual rotation) of a continuous pixel.
    pub fn pixel_to_ray_pano(&self, u_px: f64, v_px: f64) -> Vector3<f64> {
        let azimuth_rad = TAU * u_px / f64::from(self.width_px) - PI;
        let elevation_rad = FRAC_PI_2 - PI * v_px / f64::from(self.height_px);
        let (sin_a, cos_a) = azimuth_rad.sin_cos();
        let (sin_e, cos_e) = elevation_rad.sin_cos();
        Vector3::new(cos_e * sin_a, cos_e * cos_a, sin_e)
    }

    /// Continuous pixel of a panorama-frame direction (need not be unit, but finite and not astronomically
    /// large: its squared norm must not overflow); u wrapped into [0, W).
    ///
    /// At the poles (horizontal part zero) the azimuth is undefined and u is whatever `atan2(0, 0)` gives.
    pub fn ray_pano_to_pixel(&self, dir_pano: &Vector3<f64>) -> (f64, f64) {
        let w = f64::from(self.width_px);
        let h = f64::from(self.height_px);
        let azimuth_rad = dir_pano.x.atan2(dir_pano.y);
        let horizontal = (dir_pano.x * dir_pano.x + dir_pano.y * dir_pano.y).sqrt();
        let elevation_rad = dir_pano.z.atan2(horizontal);
        let mut u_px = (w * (azimuth_rad + PI) / TAU).rem_euclid(w);
        if u_px >= w {
            // rem_euclid of a tiny negative number can round up to exactly w.
            u_px = 0.0;
        }
        let v_px = h * (FRAC_PI_2 - elevation_rad) / PI;
        (u_px, v_px)
    }

    /// [`Self::ray_pano_to_pixel`] with [`atan2_poly`] instead of libm (≤ 1e-9 px apart for finite, non-zero
    /// directions): for dense sampling maps such as the ortho-projection's, never for measurements.
    #[inline]
    pub fn ray_pano_to_pixel_fast(&self, dir_pano: &Vector3<f64>) -> (f64, f64) {
        let w = f64::from(self.width_px);
        let h = f64::from(self.height_px);
        let azimuth_rad = atan2_poly(dir_pano.x, dir_pano.y);
        let horizontal = (dir_pano.x * dir_pano.x + dir_pano.y * dir_pano.y).sqrt();
        let elevation_rad = atan2_poly(dir_pano.z, horizontal);
        // azimuth + π ∈ [0, 2π]: only exactly 2π needs wrapping. Multiplications by the pixel scale, not divisions.
        let mut u_px = (azimuth_rad + PI) * (w / TAU);
        if u_px >= w {
            u_px -= w;
        }
        let v_px = (FRAC_PI_2 - elevation_rad) * (h / PI);
        (u_px, v_px)
    }

    /// Unit direction in the world frame of a continuous pixel.
    pub fn pixel_to_ray_world(&self, u_px: f64, v_px: f64) -> Vector3<f64> {
        self.rotation_pano_to_world * self.pixel_to_ray_pano(u_px, v_px)
    }

    /// Continuous pixel of a world-frame direction (need not be unit); u wrapped into [0, W).
    pub fn ray_world_to_pixel(&self, dir_world: &Vector3<f64>) -> (f64, f64) {
        let dir_pano = self.rotation_pano_to_world.transpose() * dir_world;
        self.ray_pano_to_pixel(&dir_pano)
    }

    /// Continuous pixel where the world point appears; `None` if it coincides with the projection centre
    /// (or is not finite).
    pub fn project_world(&self, p_world: &Vector3<f64>) -> Option<(f64, f64)> {
        let d = p_world - self.center_world;
        let norm_sq = d.norm_squared();
        if !(norm_sq > 0.0 && norm_sq.is_finite()) {
            return None;
        }
        // atan2 is scale-invariant: no normalisation needed.
        Some(self.ray_world_to_pixel(&d))
    }
}

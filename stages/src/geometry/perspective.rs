//! Artificial perspective (pinhole) views of an equirectangular panorama (thesis 4.4.1, eq. 4/1–4/4).
//!
//! A view is square, `w × w` pixels, with vertical field of view `vfov`: focal length `f = (w/2)/tan(vfov/2)`
//! (eq. 4/1), `K = [[f, 0, w/2], [0, f, w/2], [0, 0, 1]]` (eq. 4/2; principal point at the image centre in the
//! continuous-pixel convention of campaign-format.md, first pixel centre at (0.5, 0.5)).
//!
//! Camera frame (computer-vision convention, matching K): x to the right of the image, y down, z along the
//! optical axis. The world→camera rotation is
//! `R = Rx(90°)·Ry(roll)·Rx(−pitch)·Rz(yaw)` (eq. 4/3 with κ = yaw, φ = −pitch, ω = roll, the thesis' sign
//! conventions being lost in its text): `Rz(yaw)` turns the optical axis' azimuth to grid north, `Rx(−pitch)`
//! levels it, `Ry(roll)` rolls about it, and `Rx(90°)` maps the levelled (east, north, up) frame to the
//! camera frame (x, y, z) = (east, −up, north). Hence, for roll 0, the optical axis is
//! `(cos p·sin a, cos p·cos a, sin p)` in world ENU (a = yaw, clockwise from grid north; p = pitch, positive
//! above the horizon), the image x axis is horizontal and points to the right, and the image "up" (−y) has a
//! positive world Z component.
//!
//! The projection centre is the panorama's centre `t`; the projection matrix `M = K·R·[I | −t]` (eq. 4/4) is
//! only ever formed relative to a [`LocalOrigin`] (world coordinates are ≈ 10⁵ m).

use super::local_frame::LocalOrigin;
use super::panorama::PanoramaCamera;
use super::rotation::{rot_x, rot_y, rot_z};
use crate::imaging::equirect::PanoramaLevels;
use crate::imaging::{GrayImage, RgbImage};
use nalgebra::{Matrix3, Matrix3x4, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A square pinhole view centred at a panorama's projection centre.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PerspectiveView {
    /// Width = height of the view, pixels.
    pub width_px: u32,
    /// Principal distance (eq. 4/1), pixels.
    pub focal_px: f64,
    /// Azimuth of the optical axis, degrees clockwise from grid north.
    pub yaw_deg: f64,
    /// Elevation of the optical axis, degrees (positive above the horizon).
    pub pitch_deg: f64,
    /// Rotation about the optical axis, degrees (0 in the thesis).
    pub roll_deg: f64,
    /// Projection centre, world frame, metres.
    pub center_world: Vector3<f64>,
    /// World→camera rotation R (eq. 4/3): `p_cam = R·(P_world − center_world)`.
    pub rotation_world_to_cam: Matrix3<f64>,
}

impl PerspectiveView {
    /// A view of `width_px × width_px` pixels with vertical field of view `vfov_deg` (0 < vfov < 180°),
    /// optical axis at azimuth `yaw_deg` and elevation `pitch_deg`, roll `roll_deg`, centred at `center_world`.
    pub fn new(
        width_px: u32,
        vfov_deg: f64,
        yaw_deg: f64,
        pitch_deg: f64,
        roll_deg: f64,
        center_world: Vector3<f64>,
    ) -> Self {
        let half_w = f64::from(width_px) / 2.0;
        let focal_px = half_w / (vfov_deg.to_radians() / 2.0).tan();
        let rotation_world_to_cam = rot_x(90f64.to_radians())
            * rot_y(roll_deg.to_radians())
            * rot_x(-pitch_deg.to_radians())
            * rot_z(yaw_deg.to_radians());
        Self {
            width_px,
            focal_px,
            yaw_deg,
            pitch_deg,
            roll_deg,
            center_world,
            rotation_world_to_cam,
        }
    }

    /// A view from the projection centre of `pano` (roll 0, as in the thesis).
    pub fn of_panorama(
        pano: &PanoramaCamera,
        width_px: u32,
        vfov_deg: f64,
        yaw_deg: f64,
        pitch_deg: f64,
    ) -> Self {
        Self::new(
            width_px,
            vfov_deg,
            yaw_deg,
            pitch_deg,
            0.0,
            pano.center_world,
        )
    }

    /// Principal point coordinate (both axes), pixels.
    pub fn principal_px(&self) -> f64 {
        f64::from(self.width_px) / 2.0
    }

    /// Camera matrix K (eq. 4/2).
    pub fn k(&self) -> Matrix3<f64> {
        let c = self.principal_px();
        Matrix3::new(self.focal_px, 0.0, c, 0.0, self.focal_px, c, 0.0, 0.0, 1.0)
    }

    /// Unit direction (world frame) of the optical axis.
    pub fn optical_axis_world(&self) -> Vector3<f64> {
        self.rotation_world_to_cam.transpose() * Vector3::z()
    }

    /// Unit direction (world frame) of the ray through continuous pixel (u, v).
    pub fn pixel_to_ray_world(&self, u_px: f64, v_px: f64) -> Vector3<f64> {
        let c = self.principal_px();
        let d_cam = Vector3::new((u_px - c) / self.focal_px, (v_px - c) / self.focal_px, 1.0);
        (self.rotation_world_to_cam.transpose() * d_cam).normalize()
    }

    /// Continuous pixel of a world-frame direction; `None` if it does not point in front of the camera.
    /// The pixel may lie outside the view.
    pub fn ray_world_to_pixel(&self, dir_world: &Vector3<f64>) -> Option<(f64, f64)> {
        let p = self.rotation_world_to_cam * dir_world;
        if !(p.z > 0.0) {
            return None;
        }
        let c = self.principal_px();
        Some((c + self.focal_px * p.x / p.z, c + self.focal_px * p.y / p.z))
    }

    /// Continuous pixel where a world point appears; `None` if it is not in front of the camera.
    pub fn project_world(&self, p_world: &Vector3<f64>) -> Option<(f64, f64)> {
        self.ray_world_to_pixel(&(p_world - self.center_world))
    }

    /// Whether a continuous pixel lies inside the view (`[0, w] × [0, w]`).
    pub fn contains(&self, u_px: f64, v_px: f64) -> bool {
        let w = f64::from(self.width_px);
        (0.0..=w).contains(&u_px) && (0.0..=w).contains(&v_px)
    }

    /// The panorama pixel showing the same direction as view pixel (u, v) (honours the panorama's residual
    /// yaw/pitch/roll; `pano` should share this view's projection centre).
    pub fn pixel_to_panorama(&self, pano: &PanoramaCamera, u_px: f64, v_px: f64) -> (f64, f64) {
        pano.ray_world_to_pixel(&self.pixel_to_ray_world(u_px, v_px))
    }

    /// The view pixel showing the same direction as panorama pixel (u, v); `None` behind the camera.
    pub fn panorama_to_pixel(
        &self,
        pano: &PanoramaCamera,
        u_px: f64,
        v_px: f64,
    ) -> Option<(f64, f64)> {
        self.ray_world_to_pixel(&pano.pixel_to_ray_world(u_px, v_px))
    }

    /// Projection matrix `M = K·R·[I | −(t − o)]` (eq. 4/4) for points in the local frame `origin`
    /// (`x ~ M·(P_world − o, 1)`).
    pub fn projection_matrix(&self, origin: &LocalOrigin) -> Matrix3x4<f64> {
        let kr = self.k() * self.rotation_world_to_cam;
        let t_local = origin.to_local(&self.center_world);
        let mut m = Matrix3x4::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&kr);
        m.set_column(3, &(-(kr * t_local)));
        m
    }

    /// For every view pixel centre (row-major), the panorama pixel it samples: the render lookup table.
    fn panorama_lookup_row(&self, pano: &PanoramaCamera, row: usize, out: &mut [(f64, f64)]) {
        // d_pano = Rpᵀ·Rᵀ·K⁻¹·(u, v, 1): one matrix for the whole view, no allocation per pixel.
        let a = pano.rotation_pano_to_world.transpose() * self.rotation_world_to_cam.transpose();
        let c = self.principal_px();
        let y = (row as f64 + 0.5 - c) / self.focal_px;
        for (col, o) in out.iter_mut().enumerate() {
            let x = (col as f64 + 0.5 - c) / self.focal_px;
            let d = a * Vector3::new(x, y, 1.0);
            *o = pano.ray_pano_to_pixel(&d);
        }
    }

    /// Angle subtended by the view's centre pixel, radians.
    pub fn centre_pixel_angle_rad(&self) -> f64 {
        (1.0 / self.focal_px).atan()
    }

    /// The range of panorama rows (full resolution, `cam`'s pixels) the view's pixels sample.
    pub fn panorama_rows(&self, cam: &PanoramaCamera) -> (f64, f64) {
        let w = f64::from(self.width_px);
        let n = 64;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for k in 0..=n {
            let t = w * k as f64 / n as f64;
            for (u, v) in [(t, 0.0), (t, w), (0.0, t), (w, t), (w / 2.0, t)] {
                let (_, pv) = self.pixel_to_panorama(cam, u, v);
                lo = lo.min(pv);
                hi = hi.max(pv);
            }
        }
        (lo, hi)
    }

    /// Render the view: every pixel centre's panorama pixel sampled by `sample`.
    fn render_with(
        &self,
        cam: &PanoramaCamera,
        sample: impl Fn(f64, f64) -> f32 + Sync,
    ) -> GrayImage {
        let w = self.width_px as usize;
        let mut data = vec![0f32; w * w];
        data.par_chunks_mut(w.max(1)).enumerate().for_each_init(
            || vec![(0.0, 0.0); w],
            |lut, (row, out)| {
                self.panorama_lookup_row(cam, row, lut);
                for (o, &(u, v)) in out.iter_mut().zip(lut.iter()) {
                    *o = sample(u, v);
                }
            },
        );
        GrayImage {
            width: w,
            height: w,
            data,
        }
    }

    /// Render the view from a grey panorama (bilinear; columns wrap around the panorama's seam, rows clamp
    /// at the poles). `cam` is the panorama's camera (its size must be the image's).
    pub fn render(&self, pano: &GrayImage, cam: &PanoramaCamera) -> GrayImage {
        let view = ChannelView {
            width: pano.width,
            height: pano.height,
            data: &pano.data,
        };
        self.render_with(cam, |u, v| view.sample::<1>(u, v)[0])
    }

    /// Render the view from the bands of a panorama (`cam`'s size is its full resolution), sampling
    /// `level` of its pyramid.
    pub fn render_levels(
        &self,
        pano: &PanoramaLevels,
        cam: &PanoramaCamera,
        level: usize,
    ) -> GrayImage {
        self.render_with(cam, |u, v| pano.sample(level, u, v))
    }

    /// Render the view from an RGB panorama (as [`Self::render`]).
    pub fn render_rgb(&self, pano: &RgbImage, cam: &PanoramaCamera) -> RgbImage {
        let w = self.width_px as usize;
        let mut data = vec![0f32; w * w * 3];
        let view = ChannelView {
            width: pano.width,
            height: pano.height,
            data: &pano.data,
        };
        data.par_chunks_mut((3 * w).max(1))
            .enumerate()
            .for_each_init(
                || vec![(0.0, 0.0); w],
                |lut, (row, out)| {
                    self.panorama_lookup_row(cam, row, lut);
                    for (o, &(u, v)) in out.chunks_exact_mut(3).zip(lut.iter()) {
                        o.copy_from_slice(&view.sample::<3>(u, v));
                    }
                },
            );
        RgbImage {
            width: w,
            height: w,
            data,
        }
    }
}

/// An interleaved image of N channels (borrowed) for wrapped bilinear sampling.
struct ChannelView<'a> {
    width: usize,
    height: usize,
    data: &'a [f32],
}

impl ChannelView<'_> {
    /// Bilinear sample at continuous (u, v): u wraps around (panorama seam), v clamps to the first/last row.
    #[inline]
    fn sample<const N: usize>(&self, u_px: f64, v_px: f64) -> [f32; N] {
        let mut out = [0f32; N];
        if self.width == 0 || self.height == 0 || !u_px.is_finite() || !v_px.is_finite() {
            return out;
        }
        let x = u_px - 0.5;
        let y = (v_px - 0.5).clamp(0.0, (self.height - 1) as f64);
        let x0f = x.floor();
        let y0f = y.floor();
        let fx = (x - x0f) as f32;
        let fy = (y - y0f) as f32;
        let w = self.width as i64;
        let c0 = (x0f as i64).rem_euclid(w) as usize;
        let c1 = (c0 + 1) % self.width;
        let r0 = y0f as usize;
        let r1 = (r0 + 1).min(self.height - 1);
        for (ch, o) in out.iter_mut().enumerate() {
            let px = |c: usize, r: usize| self.data[(r * self.width + c) * N + ch];
            let top = px(c0, r0) * (1.0 - fx) + px(c1, r0) * fx;
            let bottom = px(c0, r1) * (1.0 - fx) + px(c1, r1) * fx;
            *o = top * (1.0 - fy) + bottom * fy;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Vector3<f64>, b: &Vector3<f64>, tol: f64) -> bool {
        (a - b).norm() < tol
    }

    #[test]
    fn optical_axis_right_and_up_follow_yaw_and_pitch() {
        for &(a, p) in &[
            (0.0, 0.0),
            (0.0, 30.0),
            (90.0, 30.0),
            (237.0, -12.0),
            (300.0, 30.0),
        ] {
            let v = PerspectiveView::new(1024, 90.0, a, p, 0.0, Vector3::new(5e5, 5.4e6, 100.0));
            let (ar, pr) = (f64::to_radians(a), f64::to_radians(p));
            let axis = Vector3::new(pr.cos() * ar.sin(), pr.cos() * ar.cos(), pr.sin());
            assert!(close(&v.optical_axis_world(), &axis, 1e-12), "{a} {p}");
            // Principal point looks along the axis.
            let c = v.principal_px();
            assert!(close(&v.pixel_to_ray_world(c, c), &axis, 1e-12));
            // Image right is horizontal, to the right of the viewing direction (clockwise seen from above).
            let right = v.pixel_to_ray_world(c + 100.0, c) - v.pixel_to_ray_world(c - 100.0, c);
            assert!(right.z.abs() < 1e-12);
            let expected_right = Vector3::new(ar.cos(), -ar.sin(), 0.0);
            assert!(right.normalize().dot(&expected_right) > 1.0 - 1e-12);
            // Image up (smaller v) is up-ish.
            let up = v.pixel_to_ray_world(c, c - 100.0) - v.pixel_to_ray_world(c, c + 100.0);
            assert!(up.z > 0.0);
        }
    }

    #[test]
    fn focal_length_follows_eq_4_1() {
        let v = PerspectiveView::new(1024, 90.0, 0.0, 0.0, 0.0, Vector3::zeros());
        assert!((v.focal_px - 512.0).abs() < 1e-9);
        // The top edge centre is 45° above the axis.
        let d = v.pixel_to_ray_world(512.0, 0.0);
        assert!((d.z.asin().to_degrees() - 45.0).abs() < 1e-9);
    }

    #[test]
    fn projection_matrix_matches_project_world() {
        let centre = Vector3::new(512_345.6, 5_401_234.5, 101.2);
        let origin = LocalOrigin::new(Vector3::new(512_300.0, 5_401_200.0, 100.0));
        let v = PerspectiveView::new(800, 75.0, 63.0, 30.0, 0.0, centre);
        let m = v.projection_matrix(&origin);
        for &off in &[
            Vector3::new(8.0, 3.0, 6.0),
            Vector3::new(12.0, -4.0, 2.0),
            Vector3::new(5.0, 5.0, 9.0),
        ] {
            let p = centre + off;
            let (u, w) = v.project_world(&p).unwrap();
            let x = m * origin.to_local(&p).push(1.0);
            assert!((x.x / x.z - u).abs() < 1e-9 && (x.y / x.z - w).abs() < 1e-9);
            // And the pixel's ray passes through the point.
            let d = v.pixel_to_ray_world(u, w);
            assert!(close(&d, &off.normalize(), 1e-12));
        }
        assert!(v
            .project_world(&(centre - Vector3::new(8.0, 3.0, 6.0) * 10.0))
            .is_none());
    }

    #[test]
    fn world_point_lands_on_the_same_panorama_pixel_via_the_view() {
        let centre = Vector3::new(512_345.6, 5_401_234.5, 101.2);
        let pano = PanoramaCamera::new(1600, 800, centre, 3.0, -1.5, 2.0);
        for &yaw in &[60.0, 90.0, 120.0, 240.0, 270.0, 300.0] {
            let v = PerspectiveView::of_panorama(&pano, 1024, 90.0, yaw, 30.0);
            for k in 0..20 {
                let (u, w) = (50.0 + 47.0 * k as f64, 980.0 - 45.0 * k as f64);
                // A world point 7–20 m along that view pixel's ray.
                let p = centre + v.pixel_to_ray_world(u, w) * (7.0 + k as f64 * 0.6);
                let (vu, vv) = v.project_world(&p).unwrap();
                let via_view = v.pixel_to_panorama(&pano, vu, vv);
                let direct = pano.project_world(&p).unwrap();
                let du = (via_view.0 - direct.0 + 800.0).rem_euclid(1600.0) - 800.0;
                assert!(du.abs() < 1e-6 && (via_view.1 - direct.1).abs() < 1e-6);
                let back = v.panorama_to_pixel(&pano, direct.0, direct.1).unwrap();
                assert!((back.0 - u).abs() < 1e-6 && (back.1 - w).abs() < 1e-6);
            }
        }
    }

    /// A panorama whose intensity is a smooth function of the world direction renders into a view whose
    /// pixels show that function of their own rays (grey and RGB, seam crossed by the yaw-0 view).
    #[test]
    fn render_shows_the_pattern_of_each_pixels_ray() {
        let centre = Vector3::new(1000.0, 2000.0, 50.0);
        let pano_cam = PanoramaCamera::new(2000, 1000, centre, 10.0, 2.0, -3.0);
        let f = |d: &Vector3<f64>| 0.5 + 0.2 * d.x - 0.15 * d.y + 0.1 * d.z;
        let mut pano = GrayImage::filled(2000, 1000, 0.0);
        let mut rgb = RgbImage::filled(2000, 1000, [0.0; 3]);
        for r in 0..1000 {
            for c in 0..2000 {
                let d = pano_cam.pixel_to_ray_world(c as f64 + 0.5, r as f64 + 0.5);
                pano.set(c, r, f(&d) as f32);
                rgb.set(c, r, [f(&d) as f32, 0.25, (1.0 - f(&d)) as f32]);
            }
        }
        // Yaw 190° puts the panorama seam (azimuth 180° + residual yaw 10°) in the middle of the view.
        for &yaw in &[190.0, 60.0, 300.0] {
            let v = PerspectiveView::of_panorama(&pano_cam, 256, 90.0, yaw, 30.0);
            let img = v.render(&pano, &pano_cam);
            let img_rgb = v.render_rgb(&rgb, &pano_cam);
            assert_eq!((img.width, img.height), (256, 256));
            let mut max_err = 0f64;
            for r in 0..256 {
                for c in 0..256 {
                    let d = v.pixel_to_ray_world(c as f64 + 0.5, r as f64 + 0.5);
                    let expect = f(&d);
                    max_err = max_err.max((f64::from(img.get(c, r)) - expect).abs());
                    let p = img_rgb.get(c, r);
                    assert!((f64::from(p[0]) - expect).abs() < 1e-4);
                    assert!((p[1] - 0.25).abs() < 1e-6);
                    assert!((f64::from(p[2]) - (1.0 - expect)).abs() < 1e-4);
                }
            }
            assert!(max_err < 1e-4, "yaw {yaw}: max error {max_err}");
        }
    }
}

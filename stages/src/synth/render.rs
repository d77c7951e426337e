//! Rendering of the synthetic scene into panoramas and aerial frames by ray casting with stratified
//! supersampling (a fixed n × n pattern per pixel, so sub-pixel matching accuracy is meaningful).
//!
//! Output is linear RGB (nominally 0..1) before any camera response ([`super::postprocess`]). Rows are
//! rendered in parallel with an ordered collect and every pixel is a fixed-order sum, so images are
//! byte-identical whatever the thread count. Pixel convention (campaign-format.md): the centre of pixel
//! (col, row) is (col + 0.5, row + 0.5); sub-sample (i, j) of an n × n pattern is at
//! (col + (i + 0.5)/n, row + (j + 0.5)/n).

use super::scene::{Epoch, Scene};
use super::vehicle::VehicleBody;
use crate::geometry::{FrameCamera, PanoramaCamera};
use crate::imaging::RgbImage;
use nalgebra::Vector3;
use rayon::prelude::*;

/// Render `width × height` pixels with `spp_axis × spp_axis` stratified samples each; `radiance(u, v)` gives
/// the linear RGB seen through the continuous pixel position (u, v).
fn render_rows<F>(width: usize, height: usize, spp_axis: u32, radiance: F) -> RgbImage
where
    F: Fn(f64, f64) -> [f32; 3] + Sync,
{
    let n = spp_axis.max(1) as usize;
    let offsets: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
    let inv = 1.0 / (n * n) as f32;
    let rows: Vec<Vec<f32>> = (0..height)
        .into_par_iter()
        .map(|row| {
            let mut line = vec![0.0f32; width * 3];
            for col in 0..width {
                let mut acc = [0.0f32; 3];
                for dv in &offsets {
                    for du in &offsets {
                        let c = radiance(col as f64 + du, row as f64 + dv);
                        acc[0] += c[0];
                        acc[1] += c[1];
                        acc[2] += c[2];
                    }
                }
                line[col * 3] = acc[0] * inv;
                line[col * 3 + 1] = acc[1] * inv;
                line[col * 3 + 2] = acc[2] * inv;
            }
            line
        })
        .collect();
    RgbImage {
        width,
        height,
        data: rows.concat(),
    }
}

/// Number of primary (camera) rays traced for an image of `width × height` with `spp_axis²` samples per pixel.
pub fn primary_rays(width: u32, height: u32, spp_axis: u32) -> u64 {
    u64::from(width) * u64::from(height) * u64::from(spp_axis.max(1)).pow(2)
}

/// Render an equirectangular panorama of the scene as seen from `camera` (no vehicle body).
pub fn render_panorama(
    scene: &Scene,
    camera: &PanoramaCamera,
    epoch: Epoch,
    spp_axis: u32,
) -> RgbImage {
    render_panorama_with_vehicle(scene, camera, None, epoch, spp_axis)
}

/// Render a panorama; where a ray hits `vehicle` (the recording car fixed to the camera) it shows its paint.
pub fn render_panorama_with_vehicle(
    scene: &Scene,
    camera: &PanoramaCamera,
    vehicle: Option<&VehicleBody>,
    epoch: Epoch,
    spp_axis: u32,
) -> RgbImage {
    let origin: Vector3<f64> = camera.center_world;
    render_rows(
        camera.width_px as usize,
        camera.height_px as usize,
        spp_axis,
        |u, v| {
            let dir = camera.pixel_to_ray_world(u, v);
            if let Some((_, paint)) = vehicle.and_then(|b| b.hit(&dir)) {
                return paint;
            }
            scene.radiance(&origin, &dir, epoch)
        },
    )
}

/// Render a frame (pinhole + Brown distortion) image of the scene as seen from `camera`.
pub fn render_frame(scene: &Scene, camera: &FrameCamera, epoch: Epoch, spp_axis: u32) -> RgbImage {
    let origin: Vector3<f64> = camera.center_world;
    render_rows(
        camera.width_px as usize,
        camera.height_px as usize,
        spp_axis,
        |u, v| scene.radiance(&origin, &camera.pixel_to_ray_world(u, v), epoch),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stratified_samples_average_a_linear_ramp_exactly_at_pixel_centres() {
        // radiance = u, so the mean over the stratified pattern is the pixel centre's u.
        let img = render_rows(5, 2, 3, |u, v| [u as f32, v as f32, 1.0]);
        for row in 0..2 {
            for col in 0..5 {
                let c = img.get(col, row);
                assert!(
                    (c[0] - (col as f32 + 0.5)).abs() < 1e-5
                        && (c[1] - (row as f32 + 0.5)).abs() < 1e-5
                );
                assert!((c[2] - 1.0).abs() < 1e-6);
            }
        }
        assert_eq!(primary_rays(5, 2, 3), 90);
    }
}

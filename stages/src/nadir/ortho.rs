//! Ortho-projection (inverse perspective mapping) of a panorama onto a horizontal ground plane — thesis 3.4.3.
//!
//! A horizontal plane `camera_height` below the projection centre, centred at the perpendicular foot of the
//! camera, `diagonal_m` across (30 m in the thesis), is discretised into a square pixel grid of spacing `gsd_m`
//! (3 cm for MM↔MM matching, 10 cm or the aerial GSD for MM↔aerial), rotated so that the image's "up" points at
//! azimuth `rotation_deg` (0 = grid north; the aerial image's κ direction to align with it). Every ortho pixel is
//! filled by back-projection: its ground point is projected into the panorama and the grey value interpolated
//! bilinearly — so there are no gaps. Ground points hidden by the recording vehicle are masked (`valid = 0`).
//!
//! Ortho images are for matching only: [`OrthoGeoref::ortho_to_panorama_pixel`] is the exact inverse that turns an
//! ortho-image measurement back into the panorama's spherical geometry, where all measuring happens (3.4.3, last
//! paragraph).

use super::vehicle_mask::VehicleMask;
use crate::campaign::Recording;
use crate::geometry::PanoramaCamera;
use crate::imaging::bilinear_many::sample_bilinear_many;
use crate::imaging::border::Border;
use crate::imaging::sample::{floor_fast, sample_bilinear};
use crate::imaging::GrayImage;
use crate::params::StageId;
use nalgebra::Vector3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId {
    name: "ortho",
    version: "3",
};

crate::params! {
    /// Parameters of one ortho-projection.
    pub struct OrthoParams {
        /// Pixel spacing on the ground.
        gsd_m: f64 = 0.03, unit "m", min 0.001, max 1.0;
        /// Diagonal of the square ground plane (thesis: 30 m).
        diagonal_m: f64 = 30.0, unit "m", min 1.0, max 200.0;
        /// Azimuth (clockwise from grid north) that the image's "up" direction points at.
        rotation_deg: f64 = 0.0, unit "deg", min -360.0, max 360.0;
        /// The recording vehicle's body, masked out.
        vehicle: VehicleMask = VehicleMask::default(), section;
    }
    check(p, v) {
        if p.diagonal_m / p.gsd_m > 20_000.0 {
            v.push(crate::params::Violation::new(
                "gsd_m",
                "diagonal_m / gsd_m exceeds 20000 px: the ortho image would be too large",
            ));
        }
    }
}

/// Where an ortho image lies in the world: the plane's centre (foot point), spacing, rotation and size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrthoGeoref {
    /// Centre of the plane: the perpendicular foot of the projection centre (x, y, z − camera_height), world.
    pub foot_world: [f64; 3],
    pub gsd_m: f64,
    /// Azimuth of the image's "up" direction, degrees clockwise from grid north.
    pub rotation_deg: f64,
    pub width_px: usize,
    pub height_px: usize,
}

impl OrthoGeoref {
    /// The square grid for `params` centred at `foot_world`.
    pub fn new(foot_world: [f64; 3], params: &OrthoParams) -> Self {
        let side_m = params.diagonal_m / std::f64::consts::SQRT_2;
        let n = (side_m / params.gsd_m).round().max(1.0) as usize;
        Self {
            foot_world,
            gsd_m: params.gsd_m,
            rotation_deg: params.rotation_deg,
            width_px: n,
            height_px: n,
        }
    }

    /// Unit vectors (east, north) of the image's right and up directions.
    fn axes(&self) -> ([f64; 2], [f64; 2]) {
        let r = self.rotation_deg.to_radians();
        let up = [r.sin(), r.cos()];
        let right = [r.cos(), -r.sin()];
        (right, up)
    }

    /// World point on the plane at continuous ortho pixel (u, v).
    pub fn pixel_to_world(&self, u_px: f64, v_px: f64) -> Vector3<f64> {
        let (right, up) = self.axes();
        let a = (u_px - self.width_px as f64 / 2.0) * self.gsd_m;
        let b = (self.height_px as f64 / 2.0 - v_px) * self.gsd_m;
        Vector3::new(
            self.foot_world[0] + a * right[0] + b * up[0],
            self.foot_world[1] + a * right[1] + b * up[1],
            self.foot_world[2],
        )
    }

    /// Continuous ortho pixel of the vertical projection of `p_world` onto the plane (its z is ignored).
    pub fn world_to_pixel(&self, p_world: &Vector3<f64>) -> (f64, f64) {
        let (right, up) = self.axes();
        let dx = p_world.x - self.foot_world[0];
        let dy = p_world.y - self.foot_world[1];
        let a = dx * right[0] + dy * right[1];
        let b = dx * up[0] + dy * up[1];
        (
            a / self.gsd_m + self.width_px as f64 / 2.0,
            self.height_px as f64 / 2.0 - b / self.gsd_m,
        )
    }

    /// The exact inverse of the ortho-projection: the panorama pixel an ortho pixel was sampled from.
    pub fn ortho_to_panorama_pixel(
        &self,
        camera: &PanoramaCamera,
        u_px: f64,
        v_px: f64,
    ) -> Option<(f64, f64)> {
        camera.project_world(&self.pixel_to_world(u_px, v_px))
    }
}

/// An ortho-projected panorama: grey values, validity mask (1 = filled, 0 = hidden by the vehicle) and georeference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrthoImage {
    pub image: GrayImage,
    /// Row-major, one byte per pixel: 1 where the pixel holds ground seen by the panorama, 0 where masked.
    pub valid: Vec<u8>,
    pub georef: OrthoGeoref,
}

/// Bilinear sample of an equirectangular panorama, continuous across the seam at azimuth ±180° (u = 0 / W):
/// columns wrap around, rows clamp at the poles. Reads the panorama in place (no padded copy per call: the
/// 3 cm ortho of a 4000 × 2000 panorama would otherwise copy 32 MB to fill 0.5 M pixels). The ortho-projection
/// calls it only where [`sample_bilinear_many`] finds a neighbour outside the image.
#[cold]
#[inline(never)]
fn sample_panorama(pano: &GrayImage, u_px: f64, v_px: f64) -> f32 {
    let (w, h) = (pano.width, pano.height);
    let x = u_px - 0.5;
    let x0f = floor_fast(x);
    let x0 = x0f as isize;
    if x0 >= 0 && (x0 as usize) + 1 < w {
        return sample_bilinear(pano, u_px, v_px, Border::Clamp);
    }
    if w == 0 || h == 0 || !u_px.is_finite() || !v_px.is_finite() {
        return 0.0;
    }
    let wrap = |c: isize| c.rem_euclid(w as isize) as usize;
    let (c0, c1) = (wrap(x0), wrap(x0 + 1));
    let y = (v_px - 0.5).clamp(0.0, (h - 1) as f64);
    let y0 = (floor_fast(y) as usize).min(h - 1);
    let y1 = (y0 + 1).min(h - 1);
    let (fx, fy) = ((x - x0f) as f32, (y - y0 as f64) as f32);
    let at = |c: usize, r: usize| pano.data[r * w + c];
    let top = at(c0, y0) + (at(c1, y0) - at(c0, y0)) * fx;
    let bottom = at(c0, y1) + (at(c1, y1) - at(c0, y1)) * fx;
    top + (bottom - top) * fy
}

/// The ortho pixel → panorama pixel sampling map along one ortho row. The world direction from the projection
/// centre to column `col`'s ground point is `d(col) = d0 + d_step·col` (the plane is flat), formed from the
/// camera-to-foot offset so that no national-grid coordinate enters (no cancellation near the nadir); rotated into
/// the panorama frame once per row. Each pixel then costs two polynomial `atan2`
/// ([`PanoramaCamera::ray_pano_to_pixel_fast`]) and no libm call; ≤ 1e-6 px from the exact inverse
/// [`OrthoGeoref::ortho_to_panorama_pixel`] (test).
struct RowMap {
    /// World direction from the projection centre to column 0's ground point, and its per-column step.
    d0_world: Vector3<f64>,
    d_step_world: Vector3<f64>,
    /// The same in the panorama frame.
    d0_pano: Vector3<f64>,
    d_step_pano: Vector3<f64>,
}

impl RowMap {
    fn new(georef: &OrthoGeoref, camera: &PanoramaCamera, row: usize) -> Self {
        let (right, up) = georef.axes();
        let foot_offset = Vector3::from(georef.foot_world) - camera.center_world;
        let a0_m = (0.5 - georef.width_px as f64 / 2.0) * georef.gsd_m;
        let b_m = (georef.height_px as f64 / 2.0 - (row as f64 + 0.5)) * georef.gsd_m;
        let right = Vector3::new(right[0], right[1], 0.0);
        let up = Vector3::new(up[0], up[1], 0.0);
        let d0_world = foot_offset + right * a0_m + up * b_m;
        let d_step_world = right * georef.gsd_m;
        let world_to_pano = camera.rotation_pano_to_world.transpose();
        Self {
            d0_world,
            d_step_world,
            d0_pano: world_to_pano * d0_world,
            d_step_pano: world_to_pano * d_step_world,
        }
    }

    /// World direction from the projection centre to column `col`'s ground point.
    #[inline]
    fn direction_world(&self, col: usize) -> Vector3<f64> {
        self.d0_world + self.d_step_world * col as f64
    }

    /// The panorama pixel (`us`, `vs`) of every column's ground point and `valid` = 1, or NaN and 0 where the
    /// vehicle hides the point (or it is the projection centre itself). Branch-free, so it vectorises (with AVX2
    /// where the CPU has it; no FMA, so the values are the same either way).
    fn fill(
        &self,
        camera: &PanoramaCamera,
        vehicle: &VehicleMask,
        heading: (f64, f64),
        us: &mut [f64],
        vs: &mut [f64],
        valid: &mut [u8],
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { self.fill_avx2(camera, vehicle, heading, us, vs, valid) };
        }
        self.fill_impl(camera, vehicle, heading, us, vs, valid)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn fill_avx2(
        &self,
        camera: &PanoramaCamera,
        vehicle: &VehicleMask,
        heading: (f64, f64),
        us: &mut [f64],
        vs: &mut [f64],
        valid: &mut [u8],
    ) {
        self.fill_impl(camera, vehicle, heading, us, vs, valid)
    }

    #[inline(always)]
    fn fill_impl(
        &self,
        camera: &PanoramaCamera,
        vehicle: &VehicleMask,
        heading: (f64, f64),
        us: &mut [f64],
        vs: &mut [f64],
        valid: &mut [u8],
    ) {
        let cols = us.iter_mut().zip(vs.iter_mut()).zip(valid.iter_mut());
        for (col, ((u, v), valid)) in cols.enumerate() {
            let hidden = vehicle.hides_direction(heading, &self.direction_world(col));
            let d = self.d0_pano + self.d_step_pano * col as f64;
            let norm_sq = d.norm_squared();
            let ok = (norm_sq > 0.0) & norm_sq.is_finite() & !hidden;
            let (pu, pv) = camera.ray_pano_to_pixel_fast(&d);
            *u = if ok { pu } else { f64::NAN };
            *v = if ok { pv } else { f64::NAN };
            *valid = u8::from(ok);
        }
    }

    /// Panorama pixel of column `col`'s ground point; `None` where the point is the projection centre itself.
    #[cfg(test)]
    #[inline]
    fn panorama_pixel(&self, camera: &PanoramaCamera, col: usize) -> Option<(f64, f64)> {
        let d = self.d0_pano + self.d_step_pano * col as f64;
        let norm_sq = d.norm_squared();
        (norm_sq > 0.0 && norm_sq.is_finite()).then(|| camera.ray_pano_to_pixel_fast(&d))
    }
}

/// Ortho-project `panorama` (grey, W = 2H) of `recording` with `params`. Thesis 3.4.3.
pub fn ortho_project(
    panorama: &GrayImage,
    recording: &Recording,
    params: &OrthoParams,
) -> OrthoImage {
    let camera =
        PanoramaCamera::from_recording(recording, panorama.width as u32, panorama.height as u32);
    let foot = [
        recording.x,
        recording.y,
        recording.z - recording.camera_height_m,
    ];
    let georef = OrthoGeoref::new(foot, params);
    let heading = recording.heading_deg.to_radians().sin_cos();
    let (w, h) = (georef.width_px, georef.height_px);
    let mut image = GrayImage::filled(w, h, 0.0);
    let mut valid = vec![0u8; w * h];
    image
        .data
        .par_chunks_mut(w)
        .zip(valid.par_chunks_mut(w))
        .enumerate()
        .for_each_init(
            || (vec![0.0; w], vec![0.0; w]),
            |(us, vs), (row, (out, ok))| {
                // Pass 1: the panorama pixel of every ortho pixel (NaN where the vehicle hides the ground).
                RowMap::new(&georef, &camera, row).fill(
                    &camera,
                    &params.vehicle,
                    heading,
                    us,
                    vs,
                    ok,
                );
                // Pass 2: bilinear sampling; the seam columns and pole rows wrap/clamp.
                sample_bilinear_many(panorama, us, vs, out, 0.0, |_, u, v| {
                    sample_panorama(panorama, u, v)
                });
            },
        );
    debug_assert_eq!(h * w, image.data.len());
    OrthoImage {
        image,
        valid,
        georef,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A recording in national-grid coordinates (4000 × 2000 panorama, small residual rotation) and its ortho
    /// grid for the given GSD, image rotation and heading.
    fn setup(
        gsd_m: f64,
        rotation_deg: f64,
        heading_deg: f64,
    ) -> (Recording, PanoramaCamera, OrthoParams, OrthoGeoref) {
        let rec = Recording {
            image_id: "r".into(),
            file: "r.jpg".into(),
            time: "2020-01-01T00:00:00Z".into(),
            time_s: 0.0,
            x: 92_007.83,
            y: 437_001.05,
            z: 3.43,
            heading_deg,
            camera_height_m: 2.2,
            sigma_xy_m: None,
            sigma_z_m: None,
            yaw_deg: 0.24,
            pitch_deg: -0.49,
            roll_deg: -0.19,
        };
        let camera = PanoramaCamera::from_recording(&rec, 4000, 2000);
        let params = OrthoParams {
            gsd_m,
            rotation_deg,
            ..OrthoParams::default()
        };
        let georef = OrthoGeoref::new([rec.x, rec.y, rec.z - rec.camera_height_m], &params);
        (rec, camera, params, georef)
    }

    #[test]
    fn panorama_sampling_wraps_across_the_seam() {
        // 4 × 2 panorama; columns 0 and 3 are the seam neighbours.
        let pano = GrayImage::from_vec(4, 2, vec![1.0, 2.0, 3.0, 5.0, 1.0, 2.0, 3.0, 5.0]).unwrap();
        // u = 0 lies halfway between the centres of column 3 (u = 3.5, wrapped to −0.5) and column 0 (0.5).
        assert!((sample_panorama(&pano, 0.0, 1.0) - 3.0).abs() < 1e-6);
        assert!((sample_panorama(&pano, 4.0, 1.0) - 3.0).abs() < 1e-6);
        // Interior samples are plain bilinear; pixel centres return the pixel.
        assert!((sample_panorama(&pano, 1.5, 0.5) - 2.0).abs() < 1e-6);
        assert!((sample_panorama(&pano, 2.0, 1.5) - 2.5).abs() < 1e-6);
        // Rows clamp at the poles.
        assert!((sample_panorama(&pano, 3.5, 0.0) - 5.0).abs() < 1e-6);
    }

    #[test]
    fn the_row_map_matches_the_exact_inverse_within_1e6_px() {
        for (gsd_m, rotation_deg, heading_deg) in
            [(0.03, 0.0, 67.0), (0.1, 123.0, 200.0), (0.05, 0.0, 0.0)]
        {
            let (_, camera, _, georef) = setup(gsd_m, rotation_deg, heading_deg);
            let mut worst = 0.0f64;
            for row in 0..georef.height_px {
                let map = RowMap::new(&georef, &camera, row);
                for col in 0..georef.width_px {
                    let exact =
                        georef.ortho_to_panorama_pixel(&camera, col as f64 + 0.5, row as f64 + 0.5);
                    match (exact, map.panorama_pixel(&camera, col)) {
                        (Some(a), Some(b)) => {
                            let du = (a.0 - b.0).abs();
                            let du = du.min(4000.0 - du); // the same direction across the seam
                            worst = worst.max(du.hypot(a.1 - b.1));
                        }
                        (None, None) => {}
                        _ => panic!("projection differs in existence at ({col}, {row})"),
                    }
                    let ground = camera.center_world + map.direction_world(col);
                    let truth = georef.pixel_to_world(col as f64 + 0.5, row as f64 + 0.5);
                    assert!(
                        (ground - truth).norm() < 1e-9,
                        "ground point of ({col}, {row})"
                    );
                }
            }
            assert!(worst < 1e-6, "gsd {gsd_m}: worst map error {worst:e} px");
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx2_row_map_is_bit_identical_to_the_scalar_one() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        let (rec, camera, params, georef) = setup(0.05, 33.0, 141.0);
        let heading = rec.heading_deg.to_radians().sin_cos();
        let n = georef.width_px;
        let mut hidden = 0;
        for row in 0..georef.height_px {
            let map = RowMap::new(&georef, &camera, row);
            let mut a = (vec![0.0; n], vec![0.0; n], vec![0u8; n]);
            let mut b = a.clone();
            map.fill_impl(
                &camera,
                &params.vehicle,
                heading,
                &mut a.0,
                &mut a.1,
                &mut a.2,
            );
            // SAFETY: AVX2 was detected above.
            unsafe {
                map.fill_avx2(
                    &camera,
                    &params.vehicle,
                    heading,
                    &mut b.0,
                    &mut b.1,
                    &mut b.2,
                )
            };
            assert_eq!(a.2, b.2, "row {row}: validity");
            for col in 0..n {
                assert_eq!(
                    a.0[col].to_bits(),
                    b.0[col].to_bits(),
                    "u of ({col}, {row})"
                );
                assert_eq!(
                    a.1[col].to_bits(),
                    b.1[col].to_bits(),
                    "v of ({col}, {row})"
                );
            }
            hidden += a.2.iter().filter(|&&ok| ok == 0).count();
        }
        assert!(hidden > 100, "the vehicle mask hid only {hidden} pixels");
    }
}

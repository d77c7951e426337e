//! Ortho-projection (inverse perspective mapping) of a panorama onto a horizontal ground plane — thesis 3.4.3.
//!
//! A horizontal plane `camera_height` below the projection centre, centred at the perpendicular foot of the
//! camera, `diagonal_m` across (30 m in the thesis), is discretised into a square pixel grid of spacing `gsd_m`
//! (3 cm for MM↔MM matching, 10 cm or the aerial GSD for MM↔aerial), rotated so that the image's "up" points at
//! azimuth `rotation_deg` (0 = grid north; the aerial image's κ direction to align with it). Every ortho pixel is
//! filled by back-projection: its ground point is projected into the panorama and the grey value interpolated
//! bilinearly — so there are no gaps. Ground points hidden by the recording vehicle are masked (`valid = 0`).
//! Where the panorama resolves the ground more finely than the ortho's pixel (near the vehicle), the sample
//! comes from the panorama's pyramid level that matches the pixel's footprint ([`pixel_level`]), so the ortho
//! averages the panorama there instead of aliasing it; the result depends on the ground, not on how many
//! pixels the panorama has.
//!
//! Ortho images are for matching only: [`OrthoGeoref::ortho_to_panorama_pixel`] is the exact inverse that turns an
//! ortho-image measurement back into the panorama's spherical geometry, where all measuring happens (3.4.3, last
//! paragraph).

use super::vehicle_mask::VehicleMask;
use crate::campaign::Recording;
use crate::geometry::PanoramaCamera;
use crate::imaging::equirect::PanoramaLevels;
use crate::imaging::GrayImage;
use crate::params::StageId;
use nalgebra::Vector3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("ortho", "4");

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
        /// `ortho_aerial` only: the coarsest GSD the MM↔aerial registration works at. An aerial image finer than
        /// this is registered at the coarsest level of its pyramid whose GSD does not exceed it (a 2.5 cm frame
        /// at 10 cm), and the ortho is made at that GSD; coarser images at their own GSD (thesis 3.4.5.2 works at
        /// the aerial images' 10 cm); an image enlarged by pixel repetition never finer than the level it was
        /// enlarged from (its detail level). Default 0.12 m: 10 cm frames and their GSD's variation across the
        /// frame stay at full resolution.
        registration_gsd_m: f64 = 0.12, unit "m", min 0.001, max 10.0;
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
    fn fill(&self, view: &RowView, out: RowPixels) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { self.fill_avx2(view, out) };
        }
        self.fill_impl(view, out)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn fill_avx2(&self, view: &RowView, out: RowPixels) {
        self.fill_impl(view, out)
    }

    #[inline(always)]
    fn fill_impl(&self, view: &RowView, out: RowPixels) {
        let cols = out
            .us
            .iter_mut()
            .zip(out.vs.iter_mut())
            .zip(out.valid.iter_mut());
        for (col, ((u, v), valid)) in cols.enumerate() {
            let hidden = view
                .vehicle
                .hides_direction(view.heading, &self.direction_world(col));
            let d = self.d0_pano + self.d_step_pano * col as f64;
            let norm_sq = d.norm_squared();
            let ok = (norm_sq > 0.0) & norm_sq.is_finite() & !hidden;
            let (pu, pv) = view.camera.ray_pano_to_pixel_fast(&d);
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

/// What one panorama sees of the ground: its camera, the recording vehicle's mask and the vehicle's heading
/// (sin, cos).
struct RowView<'a> {
    camera: &'a PanoramaCamera,
    vehicle: &'a VehicleMask,
    heading: (f64, f64),
}

/// [`RowMap::fill`]'s output along one ortho row: the panorama pixel (`us`, `vs`) of each column and its
/// validity.
struct RowPixels<'a> {
    us: &'a mut [f64],
    vs: &'a mut [f64],
    valid: &'a mut [u8],
}

/// The pyramid level for an ortho pixel of `gsd_m` whose ground point lies at `dir_world` from the projection
/// centre, in a panorama of `pixel_angle_rad` per pixel: the finest level whose pixel covers at least the ortho
/// pixel's area on the ground. A panorama pixel at horizontal distance d and height h spans `Δ·(d² + h²)/h`
/// radially and `Δ·d` across, so the level is `⌊½·log2(g²·h / (Δ²·d·(d² + h²)))⌋`, clamped to
/// `[0, max_level]`.
#[inline]
pub fn pixel_level(
    dir_world: &Vector3<f64>,
    gsd_m: f64,
    pixel_angle_rad: f64,
    max_level: usize,
) -> usize {
    let h = -dir_world.z;
    let d2 = dir_world.x * dir_world.x + dir_world.y * dir_world.y;
    let area = pixel_angle_rad * pixel_angle_rad * d2.sqrt() * (d2 + h * h) / h.abs().max(1e-9);
    let ratio = gsd_m * gsd_m / area;
    if !(ratio >= 4.0) {
        return 0;
    }
    ((0.5 * ratio.log2()).floor() as usize).min(max_level)
}

/// Which rows of which pyramid levels [`ortho_project`] reads for `recording` with `params` from a panorama of
/// `width × height` px with levels `0..=max_level`: (level, (v0, v1)) in full-resolution panorama rows, each
/// level only over the ground distances where [`pixel_level`] picks it (with a margin for the recorded
/// attitude).
pub fn panorama_bands(
    recording: &Recording,
    params: &OrthoParams,
    (width, height): (usize, usize),
    max_level: usize,
) -> Vec<(usize, (f64, f64))> {
    let delta = std::f64::consts::TAU / width.max(1) as f64;
    let h = recording.camera_height_m.max(0.05);
    let g = params.gsd_m;
    // Ground distances where level l applies: t(d) = g²h/(Δ²d(d² + h²)) in [4^l, 4^(l+1)), t falling in d.
    let distance_where = |t: f64| {
        // Solve d(d² + h²) = g²h/(Δ²t) by bisection on [0, 1e4].
        let target = g * g * h / (delta * delta * t);
        let (mut lo, mut hi) = (0.0f64, 1e4f64);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if mid * (mid * mid + h * h) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    };
    let d_max = params.diagonal_m / 2.0 + 1.0;
    let tilt = recording.pitch_deg.abs() + recording.roll_deg.abs() + 1.0;
    let row_of = |d: f64, sign: f64| {
        let elevation_deg = -(h / d.max(1e-3)).atan().to_degrees() + sign * tilt;
        ((90.0 - elevation_deg) / 180.0 * height as f64).clamp(0.0, height as f64)
    };
    (0..=max_level)
        .filter_map(|l| {
            let d_far = if l == 0 {
                d_max
            } else {
                distance_where(4f64.powi(l as i32)).min(d_max)
            };
            let d_near = if l == max_level {
                0.0
            } else {
                distance_where(4f64.powi(l as i32 + 1))
            };
            (d_near < d_far).then(|| (l, (row_of(d_far, 1.0), row_of(d_near, -1.0))))
        })
        .collect()
}

/// [`ortho_project`] of a whole in-memory panorama (tools, tests): its coarser levels are computed here.
pub fn ortho_project_whole(
    panorama: &GrayImage,
    recording: &Recording,
    params: &OrthoParams,
) -> OrthoImage {
    let size = (panorama.width, panorama.height);
    let max_level = panorama_bands(recording, params, size, 12)
        .iter()
        .map(|(l, _)| *l)
        .max()
        .unwrap_or(0);
    ortho_project(
        &PanoramaLevels::from_image(panorama, max_level),
        recording,
        params,
    )
}

/// Ortho-project `panorama` (grey, W = 2H; the bands of [`panorama_bands`]) of `recording` with `params`.
/// Thesis 3.4.3.
pub fn ortho_project(
    panorama: &PanoramaLevels,
    recording: &Recording,
    params: &OrthoParams,
) -> OrthoImage {
    let camera = PanoramaCamera::from_recording(
        recording,
        panorama.width_px as u32,
        panorama.height_px as u32,
    );
    let foot = [
        recording.x,
        recording.y,
        recording.z - recording.camera_height_m,
    ];
    let georef = OrthoGeoref::new(foot, params);
    let view = RowView {
        camera: &camera,
        vehicle: &params.vehicle,
        heading: recording.heading_deg.to_radians().sin_cos(),
    };
    let delta = camera.pixel_angle_rad();
    let max_level = panorama.max_level();
    let (w, h) = (georef.width_px, georef.height_px);
    let mut image = GrayImage::filled(w, h, 0.0);
    let mut valid = vec![0u8; w * h];
    image
        .data
        .par_chunks_mut(w)
        .zip(valid.par_chunks_mut(w))
        .enumerate()
        .for_each_init(
            || (vec![0.0; w], vec![0.0; w], (Vec::new(), Vec::new())),
            |(us, vs, scratch), (row, (out, ok))| {
                // Pass 1: the panorama pixel of every ortho pixel (NaN where the vehicle hides the ground).
                let map = RowMap::new(&georef, &camera, row);
                let pixels = RowPixels { us, vs, valid: ok };
                map.fill(&view, pixels);
                // Pass 2: bilinear sampling, run by run of columns sharing a pyramid level; the seam columns and
                // pole rows wrap/clamp.
                let level_at = |col: usize| {
                    pixel_level(&map.direction_world(col), georef.gsd_m, delta, max_level)
                };
                let mut start = 0;
                while start < w {
                    let level = level_at(start);
                    let mut end = start + 1;
                    while end < w && level_at(end) == level {
                        end += 1;
                    }
                    panorama.sample_many(
                        level,
                        &us[start..end],
                        &vs[start..end],
                        &mut out[start..end],
                        0.0,
                        scratch,
                    );
                    start = end;
                }
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
            yaw_deg: 0.24,
            pitch_deg: -0.49,
            roll_deg: -0.19,
            time: "2020-01-01T00:00:00Z".into(),
            ..Recording::new("r", 0.0, [92_007.83, 437_001.05, 3.43], heading_deg, 2.2)
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
        let img = GrayImage::from_vec(4, 2, vec![1.0, 2.0, 3.0, 5.0, 1.0, 2.0, 3.0, 5.0]).unwrap();
        let pano = PanoramaLevels::from_image(&img, 0);
        // u = 0 lies halfway between the centres of column 3 (u = 3.5, wrapped to −0.5) and column 0 (0.5).
        assert!((pano.sample(0, 0.0, 1.0) - 3.0).abs() < 1e-6);
        assert!((pano.sample(0, 4.0, 1.0) - 3.0).abs() < 1e-6);
        // Interior samples are plain bilinear; pixel centres return the pixel.
        assert!((pano.sample(0, 1.5, 0.5) - 2.0).abs() < 1e-6);
        assert!((pano.sample(0, 2.0, 1.5) - 2.5).abs() < 1e-6);
        // Rows clamp at the poles.
        assert!((pano.sample(0, 3.5, 0.0) - 5.0).abs() < 1e-6);
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

    #[test]
    fn levels_follow_the_ground_footprint_and_the_bands_cover_them() {
        let (rec, camera, _, georef) = setup(0.10, 0.0, 30.0);
        let delta = camera.pixel_angle_rad();
        // 4000-px panorama (Δ = 1.57 mrad), camera 2.2 m up, 10 cm pixels: t = g²h/(Δ²d(d² + h²)).
        let at = |d: f64| pixel_level(&Vector3::new(d, 0.0, -2.2), 0.10, delta, 6);
        assert_eq!(at(20.0), 0);
        let t = |d: f64| 0.01 * 2.2 / (delta * delta * d * (d * d + 4.84));
        for d in [0.5, 1.0, 3.0, 6.0, 10.0] {
            assert_eq!(
                at(d),
                ((0.5 * t(d).log2()).floor().max(0.0) as usize).min(6),
                "d = {d}"
            );
        }
        assert!(at(3.0) >= 2 && at(10.0) >= 1);
        // A panorama 4× as wide picks levels two higher at the same place.
        let fine = |d: f64| pixel_level(&Vector3::new(d, 0.0, -2.2), 0.10, delta / 4.0, 9);
        for d in [1.0, 3.0, 6.0, 10.0, 20.0] {
            assert_eq!(fine(d), at(d) + 2, "d = {d}");
        }
        // Every pixel's level has a band that holds the panorama row of its ground point.
        let params = OrthoParams {
            gsd_m: 0.10,
            ..OrthoParams::default()
        };
        let bands = panorama_bands(&rec, &params, (4000, 2000), 6);
        for row in (0..georef.height_px).step_by(7) {
            let map = RowMap::new(&georef, &camera, row);
            for col in (0..georef.width_px).step_by(5) {
                let Some((_, v)) = map.panorama_pixel(&camera, col) else {
                    continue;
                };
                let level = pixel_level(&map.direction_world(col), 0.10, delta, 6);
                let (_, (v0, v1)) = bands
                    .iter()
                    .find(|(l, _)| *l == level)
                    .expect("band of the level");
                assert!(
                    *v0 <= v && v <= *v1,
                    "({col}, {row}) level {level}: row {v} not in [{v0}, {v1}]"
                );
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx2_row_map_is_bit_identical_to_the_scalar_one() {
        if !crate::imaging::avx2_to_compare() {
            return;
        }
        let (rec, camera, params, georef) = setup(0.05, 33.0, 141.0);
        let view = RowView {
            camera: &camera,
            vehicle: &params.vehicle,
            heading: rec.heading_deg.to_radians().sin_cos(),
        };
        let n = georef.width_px;
        let mut hidden = 0;
        for row in 0..georef.height_px {
            let map = RowMap::new(&georef, &camera, row);
            let mut a = (vec![0.0; n], vec![0.0; n], vec![0u8; n]);
            let mut b = a.clone();
            let (us, vs, valid) = (&mut a.0, &mut a.1, &mut a.2);
            map.fill_impl(&view, RowPixels { us, vs, valid });
            let (us, vs, valid) = (&mut b.0, &mut b.1, &mut b.2);
            // SAFETY: AVX2 was detected above.
            unsafe { map.fill_avx2(&view, RowPixels { us, vs, valid }) };
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

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
use crate::imaging::border::Border;
use crate::imaging::sample::{floor_fast, sample_bilinear};
use crate::imaging::GrayImage;
use nalgebra::Vector3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Parameters of one ortho-projection.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OrthoParams {
    /// Pixel spacing on the ground, m.
    pub gsd_m: f64,
    /// Diagonal of the square ground plane, m (thesis: 30 m).
    pub diagonal_m: f64,
    /// Azimuth (degrees clockwise from grid north) that the image's "up" direction points at.
    pub rotation_deg: f64,
    /// The recording vehicle's body, masked out.
    pub vehicle: VehicleMask,
}

impl Default for OrthoParams {
    fn default() -> Self {
        Self {
            gsd_m: 0.03,
            diagonal_m: 30.0,
            rotation_deg: 0.0,
            vehicle: VehicleMask::default(),
        }
    }
}

impl OrthoParams {
    /// Check ranges; each error is (field, message with the allowed range).
    pub fn validate(&self) -> Result<(), Vec<(String, String)>> {
        let mut errs = Vec::new();
        if !(self.gsd_m.is_finite() && self.gsd_m >= 0.001 && self.gsd_m <= 1.0) {
            errs.push((
                "gsd_m".into(),
                format!("must be in [0.001, 1] m, got {}", self.gsd_m),
            ));
        }
        if !(self.diagonal_m.is_finite() && self.diagonal_m >= 1.0 && self.diagonal_m <= 200.0) {
            errs.push((
                "diagonal_m".into(),
                format!("must be in [1, 200] m, got {}", self.diagonal_m),
            ));
        }
        if !self.rotation_deg.is_finite() {
            errs.push((
                "rotation_deg".into(),
                "must be a finite angle in degrees".into(),
            ));
        }
        if self.gsd_m.is_finite()
            && self.diagonal_m.is_finite()
            && self.diagonal_m / self.gsd_m > 20_000.0
        {
            errs.push((
                "gsd_m".into(),
                "diagonal_m / gsd_m exceeds 20000 px: the ortho image would be too large".into(),
            ));
        }
        if let Err(v) = self.vehicle.validate() {
            errs.extend(v.into_iter().map(|(f, m)| (format!("vehicle.{f}"), m)));
        }
        if errs.is_empty() {
            Ok(())
        } else {
            Err(errs)
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
/// 3 cm ortho of a 4000 × 2000 panorama would otherwise copy 32 MB to fill 0.5 M pixels).
#[inline]
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

/// Node spacing of the interpolated ortho → panorama map, ortho pixels.
pub const MAP_CELL_PX: usize = 8;

/// Largest admitted error of the interpolated map, panorama pixels: a cell whose interpolated centre is further
/// than this from the exact projection is projected exactly, pixel by pixel.
pub const MAP_TOLERANCE_PX: f64 = 0.01;

/// The ortho pixel → panorama pixel map of one ortho image, computed exactly at nodes every [`MAP_CELL_PX`]
/// pixels and interpolated bilinearly inside cells where that is accurate to [`MAP_TOLERANCE_PX`] (checked at
/// each cell's centre); cells at the panorama seam, near the nadir (where the map bends fast) or with a node
/// that does not project are computed exactly per pixel. The map is smooth elsewhere, so this replaces ~64
/// trigonometric projections by one.
struct PanoramaMap<'a> {
    georef: &'a OrthoGeoref,
    camera: &'a PanoramaCamera,
    /// Node columns/rows (pixel indices), first 0, last `width − 1`/`height − 1`.
    node_cols: Vec<usize>,
    node_rows: Vec<usize>,
    /// Exact map at the nodes, row-major over (node_rows × node_cols).
    nodes: Vec<Option<(f64, f64)>>,
    /// Per cell (row-major over (node_rows − 1) × (node_cols − 1)): interpolation is accurate.
    smooth: Vec<bool>,
}

fn node_positions(n: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (0..n).step_by(MAP_CELL_PX).collect();
    if *v.last().unwrap_or(&0) != n.saturating_sub(1) {
        v.push(n - 1);
    }
    if v.len() == 1 {
        v.push(v[0]);
    }
    v
}

impl<'a> PanoramaMap<'a> {
    fn new(georef: &'a OrthoGeoref, camera: &'a PanoramaCamera) -> Self {
        let node_cols = node_positions(georef.width_px);
        let node_rows = node_positions(georef.height_px);
        let exact = |col: usize, row: usize| {
            georef.ortho_to_panorama_pixel(camera, col as f64 + 0.5, row as f64 + 0.5)
        };
        let nodes: Vec<Option<(f64, f64)>> = node_rows
            .par_iter()
            .flat_map_iter(|&r| node_cols.iter().map(move |&c| exact(c, r)))
            .collect();
        let (nc, nr) = (node_cols.len(), node_rows.len());
        let half_width = f64::from(camera.width_px) / 2.0;
        let smooth: Vec<bool> = (0..(nr - 1) * (nc - 1))
            .into_par_iter()
            .map(|cell| {
                let (i, j) = (cell / (nc - 1), cell % (nc - 1));
                let corners = [
                    nodes[i * nc + j],
                    nodes[i * nc + j + 1],
                    nodes[(i + 1) * nc + j],
                    nodes[(i + 1) * nc + j + 1],
                ];
                let Some(c) = corners.iter().copied().collect::<Option<Vec<_>>>() else {
                    return false;
                };
                let (umin, umax) = c
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
                if umax - umin > half_width {
                    return false; // the cell straddles the seam
                }
                let (c0, c1) = (node_cols[j], node_cols[j + 1]);
                let (r0, r1) = (node_rows[i], node_rows[i + 1]);
                let (cm, rm) = ((c0 + c1) / 2, (r0 + r1) / 2);
                // The centre and the four edge midpoints must interpolate within the tolerance (the map bends
                // fast near the nadir, where the azimuth turns quickly: a single probe can pass by symmetry).
                [(cm, rm), (cm, r0), (cm, r1), (c0, rm), (c1, rm)]
                    .iter()
                    .all(|&(pc, pr)| {
                        exact(pc, pr).is_some_and(|truth| {
                            let interp = bilerp(&c, frac(pc, c0, c1), frac(pr, r0, r1));
                            (interp.0 - truth.0).hypot(interp.1 - truth.1) <= MAP_TOLERANCE_PX
                        })
                    })
            })
            .collect();
        Self {
            georef,
            camera,
            node_cols,
            node_rows,
            nodes,
            smooth,
        }
    }

    /// The panorama pixel of ortho pixel (col, row) (its centre), `None` if it does not project.
    #[inline]
    fn at(&self, col: usize, row: usize, cell_i: usize, cell_j: usize) -> Option<(f64, f64)> {
        let nc = self.node_cols.len();
        if self.smooth[cell_i * (nc - 1) + cell_j] {
            let (c0, c1) = (self.node_cols[cell_j], self.node_cols[cell_j + 1]);
            let (r0, r1) = (self.node_rows[cell_i], self.node_rows[cell_i + 1]);
            let corner = |a: usize, b: usize| self.nodes[a * nc + b].unwrap_or((0.0, 0.0));
            let c = [
                corner(cell_i, cell_j),
                corner(cell_i, cell_j + 1),
                corner(cell_i + 1, cell_j),
                corner(cell_i + 1, cell_j + 1),
            ];
            Some(bilerp(&c, frac(col, c0, c1), frac(row, r0, r1)))
        } else {
            self.georef
                .ortho_to_panorama_pixel(self.camera, col as f64 + 0.5, row as f64 + 0.5)
        }
    }
}

#[inline]
fn frac(x: usize, a: usize, b: usize) -> f64 {
    if b > a {
        (x - a) as f64 / (b - a) as f64
    } else {
        0.0
    }
}

/// Bilinear interpolation of corner values [top-left, top-right, bottom-left, bottom-right].
#[inline]
fn bilerp(c: &[(f64, f64)], tx: f64, ty: f64) -> (f64, f64) {
    let top = (
        c[0].0 + (c[1].0 - c[0].0) * tx,
        c[0].1 + (c[1].1 - c[0].1) * tx,
    );
    let bottom = (
        c[2].0 + (c[3].0 - c[2].0) * tx,
        c[2].1 + (c[3].1 - c[2].1) * tx,
    );
    (
        top.0 + (bottom.0 - top.0) * ty,
        top.1 + (bottom.1 - top.1) * ty,
    )
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
    let map = PanoramaMap::new(&georef, &camera);
    let heading = recording.heading_deg.to_radians().sin_cos();
    let (w, h) = (georef.width_px, georef.height_px);
    let mut image = GrayImage::filled(w, h, 0.0);
    let mut valid = vec![0u8; w * h];
    image
        .data
        .par_chunks_mut(w)
        .zip(valid.par_chunks_mut(w))
        .enumerate()
        .for_each(|(row, (out, ok))| {
            let cell_i = (row / MAP_CELL_PX).min(map.node_rows.len() - 2);
            // Ground points of this row: p(col) = first + col · step (no trigonometry per pixel).
            let first = georef.pixel_to_world(0.5, row as f64 + 0.5);
            let step = georef.pixel_to_world(1.5, row as f64 + 0.5) - first;
            for col in 0..w {
                let p = first + step * col as f64;
                if params
                    .vehicle
                    .hides_with_heading(&camera.center_world, heading, &p)
                {
                    continue;
                }
                let cell_j = (col / MAP_CELL_PX).min(map.node_cols.len() - 2);
                if let Some((u, v)) = map.at(col, row, cell_i, cell_j) {
                    out[col] = sample_panorama(panorama, u, v);
                    ok[col] = 1;
                }
            }
        });
    OrthoImage {
        image,
        valid,
        georef,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn the_interpolated_map_matches_the_exact_projection() {
        for (gsd_m, rotation_deg, heading_deg) in
            [(0.03, 0.0, 67.0), (0.1, 123.0, 200.0), (0.05, 0.0, 0.0)]
        {
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
            let map = PanoramaMap::new(&georef, &camera);
            let mut worst = 0.0f64;
            for row in 0..georef.height_px {
                for col in 0..georef.width_px {
                    let ci = (row / MAP_CELL_PX).min(map.node_rows.len() - 2);
                    let cj = (col / MAP_CELL_PX).min(map.node_cols.len() - 2);
                    let exact =
                        georef.ortho_to_panorama_pixel(&camera, col as f64 + 0.5, row as f64 + 0.5);
                    let got = map.at(col, row, ci, cj);
                    match (exact, got) {
                        (Some(a), Some(b)) => {
                            let du = (a.0 - b.0).abs();
                            let du = du.min(4000.0 - du); // the same direction across the seam
                            let e = du.hypot(a.1 - b.1);
                            worst = worst.max(e);
                        }
                        (None, None) => {}
                        _ => panic!("projection differs in existence at ({col}, {row})"),
                    }
                }
            }
            // The tolerance is checked at cell centres; elsewhere in a smooth cell the error is of the same order.
            assert!(worst < 0.03, "gsd {gsd_m}: worst map error {worst} px");
        }
    }
}

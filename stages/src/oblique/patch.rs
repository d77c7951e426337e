//! Image-to-plane patches (thesis 4.4.5, Figure 4.8): a square grid in a façade plane around a sparse object
//! point, filled from the panorama and from an oblique image by back-projection (bilinear, gray), and the
//! oblique patch's real-resolution ratio.
//!
//! Pixel convention of a patch of `n × n` pixels with spacing `s` metres (same as images, campaign-format.md):
//! patch pixel (col, row) covers the continuous square `[col, col + 1) × [row, row + 1)`, its centre
//! (col + 0.5, row + 0.5) is the world point `centre + (x − n/2)·s·axis_u − (y − n/2)·s·axis_v` for the
//! continuous patch coordinate (x, y). So the grid centre (n/2, n/2) is the object point, columns run along
//! `axis_u` (along the façade) and rows run *down* (against `axis_v`, which points up), as in an image of the
//! façade. A patch translation `(dx, dy)` px therefore is the plane shift `(dx·s, −dy·s)` m along
//! (`axis_u`, `axis_v`) ([`PatchGrid::shift_px_to_plane_m`]), the sign used by `PatchMatch::shift_plane_m`.
//!
//! Patch pixels without data (the back-projection leaves the image, or the point is behind the camera) are NaN:
//! the registration treats them as masked.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::geometry::frame::FrameCamera;
use crate::geometry::panorama::PanoramaCamera;
use crate::imaging::equirect::PanoramaLevels;
use crate::imaging::pyramid::ScaledWindow;
use crate::imaging::GrayImage;
use crate::ratio::ratio_or_zero;
use nalgebra::Vector3;

/// A square grid of `size_px × size_px` pixels, `spacing_m` apart, in the plane spanned by `axis_u`, `axis_v`,
/// centred on `centre_world`.
#[derive(Clone, Debug, PartialEq)]
pub struct PatchGrid {
    pub centre_world: Vector3<f64>,
    pub axis_u_world: Vector3<f64>,
    pub axis_v_world: Vector3<f64>,
    pub spacing_m: f64,
    pub size_px: usize,
}

impl PatchGrid {
    /// The grid of extent `extent_m` (rounded to whole pixels, at least 3) at `spacing_m` around `centre_world`
    /// in the plane (`axis_u`, `axis_v`); `None` for a non-finite or non-positive extent or spacing.
    pub fn new(
        centre_world: [f64; 3],
        axis_u_world: [f64; 3],
        axis_v_world: [f64; 3],
        extent_m: f64,
        spacing_m: f64,
    ) -> Option<Self> {
        if !(extent_m > 0.0 && spacing_m > 0.0 && extent_m.is_finite() && spacing_m.is_finite()) {
            return None;
        }
        let size = (extent_m / spacing_m).round();
        if !(size < 1e5) {
            return None;
        }
        Some(Self {
            centre_world: Vector3::from(centre_world),
            axis_u_world: Vector3::from(axis_u_world),
            axis_v_world: Vector3::from(axis_v_world),
            spacing_m,
            size_px: (size as usize).max(3),
        })
    }

    /// The same grid moved in its plane by `shift_plane_m` (metres along `axis_u`, `axis_v`).
    pub fn shifted(&self, shift_plane_m: [f64; 2]) -> Self {
        let mut g = self.clone();
        g.centre_world +=
            self.axis_u_world * shift_plane_m[0] + self.axis_v_world * shift_plane_m[1];
        g
    }

    /// The world point at continuous patch coordinates (x, y) px.
    pub fn world_at(&self, x_px: f64, y_px: f64) -> Vector3<f64> {
        let half = self.size_px as f64 / 2.0;
        self.centre_world + self.axis_u_world * ((x_px - half) * self.spacing_m)
            - self.axis_v_world * ((y_px - half) * self.spacing_m)
    }

    /// A patch translation (dx, dy) px as a plane shift (along `axis_u`, `axis_v`), metres.
    pub fn shift_px_to_plane_m(&self, d_px: [f64; 2]) -> [f64; 2] {
        [d_px[0] * self.spacing_m, -d_px[1] * self.spacing_m]
    }

    /// A plane shift (metres along `axis_u`, `axis_v`) as a patch translation, px.
    pub fn plane_m_to_shift_px(&self, shift_m: [f64; 2]) -> [f64; 2] {
        [shift_m[0] / self.spacing_m, -shift_m[1] / self.spacing_m]
    }

    /// Calls `f(index, world)` for every pixel centre in row-major order.
    fn for_each_pixel(&self, mut f: impl FnMut(usize, Vector3<f64>)) {
        let n = self.size_px;
        for row in 0..n {
            for col in 0..n {
                f(
                    row * n + col,
                    self.world_at(col as f64 + 0.5, row as f64 + 0.5),
                );
            }
        }
    }
}

/// Bilinear sample inside `[0, W) × [0, H)` (edge pixels replicated within the outer half pixel); `None`
/// outside.
fn sample_inside(img: &GrayImage, u_px: f64, v_px: f64) -> Option<f32> {
    let (w, h) = (img.width, img.height);
    if w == 0 || h == 0 || !(0.0..w as f64).contains(&u_px) || !(0.0..h as f64).contains(&v_px) {
        return None;
    }
    let x = (u_px - 0.5).clamp(0.0, (w - 1) as f64);
    let y = (v_px - 0.5).clamp(0.0, (h - 1) as f64);
    let x0 = (x.floor() as usize).min(w - 1);
    let y0 = (y.floor() as usize).min(h - 1);
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let p = |c: usize, r: usize| f64::from(img.data[r * w + c]);
    let v = (1.0 - fy) * ((1.0 - fx) * p(x0, y0) + fx * p(x1, y0))
        + fy * ((1.0 - fx) * p(x0, y1) + fx * p(x1, y1));
    Some(v as f32)
}

/// Most sub-samples per patch pixel and axis when a patch pixel covers several panorama pixels.
pub const MAX_SUPERSAMPLING: usize = 4;

/// The panorama level and sub-samples per axis that make one patch pixel of `spacing_m` at `range_m` from the
/// panorama centre average over the panorama pixels it covers (one pixel of level l spans
/// `range · 2π · 2^l / W` metres at right angles): the finest level, at most `max_level`, where at most
/// [`MAX_SUPERSAMPLING`] sub-samples per axis do (a panorama several times finer than the patch is read from
/// a coarser level instead of sampled more densely). Levels finer than `detail_level` (the panorama's,
/// [`PanoramaLevels::detail_level`]) only repeat its pixels and are not considered.
pub fn panorama_sampling(
    spacing_m: f64,
    range_m: f64,
    pano_width_px: u32,
    (detail_level, max_level): (usize, usize),
) -> (usize, usize) {
    let detail_level = detail_level.min(max_level);
    let footprint_m = range_m * std::f64::consts::TAU / f64::from(pano_width_px.max(1));
    if !(footprint_m > 0.0) {
        return (detail_level, 1);
    }
    for level in detail_level..=max_level {
        let k = (spacing_m / (footprint_m * (1u64 << level) as f64))
            .ceil()
            .max(1.0);
        if k <= MAX_SUPERSAMPLING as f64 {
            return (level, k as usize);
        }
    }
    (max_level, MAX_SUPERSAMPLING)
}

/// The panorama patch: every grid pixel projected into the panorama (`cam`, whose `width_px` × `height_px`
/// may differ from the panorama's full size: coordinates are scaled) and sampled bilinearly; NaN where there
/// is no data. The MM panorama resolves a façade 10 m away at ≈ 4 cm, finer than the oblique-resolution grid,
/// so each patch pixel averages k × k bilinear samples spread over its cell, from the level and with the k of
/// [`panorama_sampling`] at the patch centre, instead of point-sampling — which would alias the façade texture
/// and blur the MI optimum. A pixel whose sub-samples are partly missing averages the rest.
pub fn fill_from_panorama(
    grid: &PatchGrid,
    cam: &PanoramaCamera,
    pano: &PanoramaLevels,
) -> GrayImage {
    let n = grid.size_px;
    let mut out = GrayImage::filled(n, n, f32::NAN);
    let sx = pano.width_px as f64 / f64::from(cam.width_px);
    let sy = pano.height_px as f64 / f64::from(cam.height_px);
    let range_m = (grid.centre_world - cam.center_world).norm();
    let levels = (pano.detail_level(), pano.max_level());
    let (level, k) = panorama_sampling(grid.spacing_m, range_m, cam.width_px, levels);
    let offsets: Vec<f64> = (0..k).map(|j| (j as f64 + 0.5) / k as f64).collect();
    for row in 0..n {
        for col in 0..n {
            let (mut sum, mut count) = (0.0f64, 0usize);
            for &oy in &offsets {
                for &ox in &offsets {
                    let p = grid.world_at(col as f64 + ox, row as f64 + oy);
                    if let Some(g) = cam
                        .project_world(&p)
                        .and_then(|(u, v)| pano.sample_checked(level, u * sx, v * sy))
                    {
                        sum += f64::from(g);
                        count += 1;
                    }
                }
            }
            if count > 0 {
                out.data[row * n + col] = (sum / count as f64) as f32;
            }
        }
    }
    out
}

/// An oblique patch with the count its real-resolution ratio needs.
#[derive(Clone, Debug, PartialEq)]
pub struct FramePatch {
    /// Gray values, NaN where the grid point is outside the image or behind the camera.
    pub image: GrayImage,
    /// Grid pixels with data.
    pub valid_pixels: usize,
    /// Distinct image pixels (integer cells of the image) the valid grid pixels fell into.
    pub distinct_image_pixels: usize,
}

impl FramePatch {
    /// Real-resolution ratio (thesis 4.4.5): distinct image pixels assigned / grid pixels with data; 1 when the
    /// grid resolves every image pixel once, smaller when several grid pixels read the same image pixel (the
    /// grid is finer on the façade than the image). 0 without data.
    pub fn real_resolution_ratio(&self) -> f64 {
        ratio_or_zero(self.distinct_image_pixels, self.valid_pixels)
    }

    /// Fraction of the grid with data.
    pub fn valid_fraction(&self) -> f64 {
        self.valid_pixels as f64 / self.image.data.len().max(1) as f64
    }
}

/// Projects every grid pixel centre into a frame image read as `window` (a level of its pyramid): `(index, u,
/// v)` in window pixels for the points inside the image and the window, in row-major order. The camera's
/// pixels are the full-resolution image's.
fn frame_projections(
    grid: &PatchGrid,
    cam: &FrameCamera,
    window: &ScaledWindow,
    mut f: impl FnMut(usize, f64, f64),
) {
    let (fw, fh) = (window.full_size.0 as f64, window.full_size.1 as f64);
    let (ww, wh) = (window.image.width as f64, window.image.height as f64);
    grid.for_each_pixel(|i, p| {
        if let Some((u, v)) = cam.project_world(&p) {
            if !((0.0..fw).contains(&u) && (0.0..fh).contains(&v)) {
                return;
            }
            let (u, v) = window.from_full(u, v);
            if (0.0..ww).contains(&u) && (0.0..wh).contains(&v) {
                f(i, u, v);
            }
        }
    });
}

/// Number of distinct cells among row-major cell indices (sorts `cells`).
fn count_distinct(cells: &mut [u64]) -> usize {
    cells.sort_unstable();
    let mut distinct = 0;
    for (k, c) in cells.iter().enumerate() {
        if k == 0 || cells[k - 1] != *c {
            distinct += 1;
        }
    }
    distinct
}

/// The oblique patch: every grid pixel centre projected with `cam` into `window` (the image at the level the
/// patches are made at) and sampled bilinearly, with the counts of the real-resolution ratio (distinct pixels
/// of that level).
pub fn fill_from_frame(grid: &PatchGrid, cam: &FrameCamera, window: &ScaledWindow) -> FramePatch {
    let n = grid.size_px;
    let img = &window.image;
    let mut out = GrayImage::filled(n, n, f32::NAN);
    let mut cells: Vec<u64> = Vec::with_capacity(n * n);
    frame_projections(grid, cam, window, |i, u, v| {
        if let Some(g) = sample_inside(img, u, v) {
            out.data[i] = g;
            cells.push((v.floor() as u64) * img.width as u64 + u.floor() as u64);
        }
    });
    let valid_pixels = cells.len();
    FramePatch {
        image: out,
        valid_pixels,
        distinct_image_pixels: count_distinct(&mut cells),
    }
}

/// Real-resolution ratio of a grid in a frame image read as `window`, without sampling
/// ([`FramePatch::real_resolution_ratio`]), and the fraction of the grid inside the image.
pub fn real_resolution_ratio(
    grid: &PatchGrid,
    cam: &FrameCamera,
    window: &ScaledWindow,
) -> (f64, f64) {
    let mut cells: Vec<u64> = Vec::with_capacity(grid.size_px * grid.size_px);
    let width = window.image.width as u64;
    frame_projections(grid, cam, window, |_, u, v| {
        cells.push((v.floor() as u64) * width + u.floor() as u64);
    });
    let valid = cells.len();
    let fraction = valid as f64 / (grid.size_px * grid.size_px) as f64;
    if valid == 0 {
        return (0.0, fraction);
    }
    (count_distinct(&mut cells) as f64 / valid as f64, fraction)
}

#[cfg(test)]
mod supersampling_tests {
    use super::panorama_sampling;

    #[test]
    fn sub_samples_and_levels_follow_the_panorama_footprint() {
        // 1600-px panorama: a pixel spans 2π·10/1600 ≈ 3.9 cm at 10 m.
        assert_eq!(panorama_sampling(0.10, 10.0, 1600, (0, 5)), (0, 3));
        assert_eq!(panorama_sampling(0.03, 10.0, 1600, (0, 5)), (0, 1));
        // 0.20 m needs 6 sub-samples at level 0: level 1 with 3.
        assert_eq!(panorama_sampling(0.20, 10.0, 1600, (0, 5)), (1, 3));
        assert_eq!(panorama_sampling(0.20, 10.0, 1600, (0, 0)), (0, 4)); // capped
        assert_eq!(panorama_sampling(0.10, 0.0, 1600, (0, 5)), (0, 1));
        // The same panorama 4× as wide: two levels up, the same sub-samples.
        assert_eq!(panorama_sampling(0.10, 10.0, 6400, (0, 5)), (2, 3));
    }
}

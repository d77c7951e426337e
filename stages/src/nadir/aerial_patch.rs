//! The aerial side of MM↔aerial registration (thesis 3.4.5.1–3.4.5.2): ortho parameters that make a recording's
//! ortho image resemble an aerial nadir image (same ground sampling distance, same orientation), and the aerial
//! image patch that covers the recording's ortho footprint enlarged by the expected maximum localisation error.
//!
//! Both are derived from the aerial camera's geometry at the foot point, not from the sign convention of κ: the
//! local Jacobian of the projection (world E, N on the horizontal plane through the foot point → aerial pixels)
//! gives the GSD (`1/√|det J|`, metres per pixel) and the rotation of the nearest similarity gives the azimuth of
//! the aerial image's "up" direction, which becomes the ortho image's `rotation_deg` (see `ortho.rs`: the ortho's
//! "up" points at azimuth `rotation_deg`). Ortho pixels then map to aerial pixels by (nearly) a pure translation.
//!
//! Working resolution: an aerial image finer than `OrthoParams::registration_gsd_m` is registered at a level of
//! its pyramid — the coarsest whose GSD does not exceed that ([`working_level`]) — and the ortho is made at that
//! level's GSD, so a 2.5 cm frame is matched exactly like the same frame taken at 10 cm. The level is never finer
//! than the frame's detail level (`PyramidLayout::detail_level`, [`ortho_params_for_aerial_image`]): a frame
//! enlarged by pixel repetition is registered at the level it was enlarged from, even where that is coarser than
//! `registration_gsd_m`, exactly like the original. The aerial side is read as a window of that level
//! ([`extract_patch`], [`AerialWindow`]); measurements are returned in full-resolution aerial pixels.

use super::ortho::{OrthoGeoref, OrthoParams};
use crate::geometry::{FrameCamera, Similarity2};
use crate::imaging::pyramid::{footprint_level, PyramidError, ScaledWindow, TileSource};
use crate::imaging::GrayImage;
use crate::params::StageId;
use nalgebra::{Vector2, Vector3};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("ortho_aerial", "5");

/// Step of the finite differences of the projection Jacobian, metres on the ground.
const JACOBIAN_STEP_M: f64 = 1.0;

/// Patches narrower or lower than this (pixels, after clipping to the image) are not returned.
pub const MIN_PATCH_SIDE_PX: usize = 16;

/// Local similarity between the horizontal ground plane at a world point and the aerial image: the GSD (metres per
/// pixel) and the azimuth (degrees clockwise from grid north, in [0, 360)) of the image's "up" direction. `None` if
/// the point (or its neighbourhood) does not project in front of the camera or the projection is degenerate.
pub fn aerial_ground_similarity(cam: &FrameCamera, point_world: [f64; 3]) -> Option<(f64, f64)> {
    let h = JACOBIAN_STEP_M;
    let at = |dx: f64, dy: f64| {
        cam.project_world(&Vector3::new(
            point_world[0] + dx,
            point_world[1] + dy,
            point_world[2],
        ))
    };
    let (e_plus, e_minus) = (at(h, 0.0)?, at(-h, 0.0)?);
    let (n_plus, n_minus) = (at(0.0, h)?, at(0.0, -h)?);
    // J = ∂(u, v)/∂(E, N), then flip v so that the image frame is y-up like the map: M = diag(1, −1)·J.
    let du_de = (e_plus.0 - e_minus.0) / (2.0 * h);
    let dv_de = (e_plus.1 - e_minus.1) / (2.0 * h);
    let du_dn = (n_plus.0 - n_minus.0) / (2.0 * h);
    let dv_dn = (n_plus.1 - n_minus.1) / (2.0 * h);
    let (m00, m01, m10, m11) = (du_de, du_dn, -dv_de, -dv_dn);
    let det = m00 * m11 - m01 * m10;
    if !(det.is_finite() && det > 0.0) {
        // det ≤ 0 would be a mirrored view of the ground (from below): not a nadir image of it.
        return None;
    }
    let gsd_m = 1.0 / det.sqrt();
    // Nearest similarity [a −b; b a] to M; θ = atan2(b, a) rotates map axes (E, N) into image axes (x, y-up)
    // counter-clockwise, so the image's up axis (0, 1) is the map direction (sin θ, cos θ): azimuth θ.
    let a = 0.5 * (m00 + m11);
    let b = 0.5 * (m10 - m01);
    let azimuth_deg = b.atan2(a).to_degrees().rem_euclid(360.0);
    (gsd_m.is_finite() && gsd_m > 0.0).then_some((gsd_m, azimuth_deg))
}

/// Levels the pyramid of a `width × height` image has.
fn level_count(width: u32, height: u32) -> usize {
    crate::imaging::pyramid::PyramidLayout::new(
        width.max(1) as usize,
        height.max(1) as usize,
        crate::imaging::pyramid::SampleDepth::U8,
        crate::imaging::pyramid::DEFAULT_TILE_SIDE,
    )
    .map_or(1, |l| l.levels())
}

/// The pyramid level of an aerial image of `aerial_gsd_m` (size `width × height`) that the registration works
/// at: the coarsest whose GSD `aerial_gsd_m · 2^l` does not exceed `registration_gsd_m` (level 0 for images
/// at or coarser than it).
pub fn working_level(
    aerial_gsd_m: f64,
    registration_gsd_m: f64,
    (width, height): (u32, u32),
) -> usize {
    footprint_level(aerial_gsd_m, registration_gsd_m, level_count(width, height))
}

/// The pyramid level at which an ortho made by [`ortho_params_for_aerial`] meets the aerial image, from the
/// scale of a transform ortho px → full aerial px (≈ 2^level).
pub fn level_of_scale(ortho_to_aerial_scale: f64) -> usize {
    if !(ortho_to_aerial_scale.is_finite() && ortho_to_aerial_scale > 1.0) {
        return 0;
    }
    ortho_to_aerial_scale.log2().round().max(0.0) as usize
}

/// [`ortho_params_for_aerial_image`] for a frame whose every level holds detail of its own (detail level 0,
/// any photograph).
pub fn ortho_params_for_aerial(
    cam: &FrameCamera,
    foot_world: [f64; 3],
    base: &OrthoParams,
) -> OrthoParams {
    ortho_params_for_aerial_image(cam, foot_world, base, 0)
}

/// `base` with the GSD set to the aerial GSD at `foot_world` (at the working level, [`working_level`], but not
/// finer than the frame's `detail_level`) and the rotation set so that the ortho image's axes are aligned with
/// the aerial image's axes (thesis 3.4.5.2: "the resolution of the projected MM images is set to match the
/// aerial images' resolution"). If the foot point does not project into the camera, `base` is returned
/// unchanged (such an image does not overlap the recording; see `aerial_overlap`).
pub fn ortho_params_for_aerial_image(
    cam: &FrameCamera,
    foot_world: [f64; 3],
    base: &OrthoParams,
    detail_level: usize,
) -> OrthoParams {
    match aerial_ground_similarity(cam, foot_world) {
        Some((gsd_m, rotation_deg)) => {
            let size = (cam.width_px, cam.height_px);
            let levels = level_count(size.0, size.1);
            let level = working_level(gsd_m, base.registration_gsd_m, size)
                .max(detail_level.min(levels - 1));
            OrthoParams {
                gsd_m: gsd_m * (1u64 << level) as f64,
                rotation_deg,
                ..base.clone()
            }
        }
        None => base.clone(),
    }
}

/// A rectangular crop of an aerial image at one pyramid level.
#[derive(Clone, Debug, PartialEq)]
pub struct AerialPatch {
    pub image: GrayImage,
    /// Full-image continuous pixel coordinates of the patch's (0, 0) corner: a patch pixel (u, v) is the
    /// full-image pixel (u·scale + origin_u_px, v·scale + origin_v_px).
    pub origin_u_px: f64,
    pub origin_v_px: f64,
    /// Full-image pixels per patch pixel (2^level).
    pub scale: f64,
}

impl AerialPatch {
    /// Full-image pixel of a patch pixel.
    pub fn to_full(&self, u_px: f64, v_px: f64) -> (f64, f64) {
        (
            u_px * self.scale + self.origin_u_px,
            v_px * self.scale + self.origin_v_px,
        )
    }

    /// Patch pixel of a full-image pixel.
    pub fn to_patch(&self, u_px: f64, v_px: f64) -> (f64, f64) {
        (
            (u_px - self.origin_u_px) / self.scale,
            (v_px - self.origin_v_px) / self.scale,
        )
    }
}

/// The region of `aerial` (camera `cam`) covering the ortho footprint of `georef` enlarged by `margin_m` on every
/// side (thesis 3.4.5.1: the patch "overlaps the MM image to the extent of the expected localisation error"),
/// clipped to the image, read at pyramid `level`. The footprint's corners and edge midpoints are projected
/// through the camera and their bounding box taken (whole pixels). `Ok(None)` if a footprint point lies behind
/// the camera or the clipped patch is smaller than [`MIN_PATCH_SIDE_PX`] on a side.
pub fn extract_patch(
    aerial: &dyn TileSource,
    cam: &FrameCamera,
    georef: &OrthoGeoref,
    margin_m: f64,
    level: usize,
) -> Result<Option<AerialPatch>, PyramidError> {
    if !(margin_m.is_finite() && georef.gsd_m > 0.0) {
        return Ok(None);
    }
    let grow_px = margin_m.max(0.0) / georef.gsd_m;
    let (w, h) = (georef.width_px as f64, georef.height_px as f64);
    let xs = [-grow_px, 0.5 * w, w + grow_px];
    let ys = [-grow_px, 0.5 * h, h + grow_px];
    let (mut u_min, mut v_min) = (f64::INFINITY, f64::INFINITY);
    let (mut u_max, mut v_max) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for (i, &x) in xs.iter().enumerate() {
        for (j, &y) in ys.iter().enumerate() {
            if i == 1 && j == 1 {
                continue;
            }
            let Some((u, v)) = cam.project_world(&georef.pixel_to_world(x, y)) else {
                return Ok(None);
            };
            u_min = u_min.min(u);
            u_max = u_max.max(u);
            v_min = v_min.min(v);
            v_max = v_max.max(v);
        }
    }
    if !(u_min.is_finite() && u_max.is_finite() && v_min.is_finite() && v_max.is_finite()) {
        return Ok(None);
    }
    let Some(win) = ScaledWindow::read(aerial, level, [u_min, v_min, u_max, v_max])? else {
        return Ok(None);
    };
    if !(win.image.width >= MIN_PATCH_SIDE_PX && win.image.height >= MIN_PATCH_SIDE_PX) {
        return Ok(None);
    }
    let (origin_u_px, origin_v_px) = win.to_full(0.0, 0.0);
    Ok(Some(AerialPatch {
        scale: win.scale(),
        image: win.image,
        origin_u_px,
        origin_v_px,
    }))
}

/// The aerial image around an ortho image's footprint, read at the level where the ortho meets it, and the
/// transform ortho px → full aerial px re-expressed into the window's pixels.
pub struct AerialWindow {
    pub window: ScaledWindow,
    /// Ortho px → window px.
    pub ortho_to_window: Similarity2,
}

impl AerialWindow {
    /// The window of `aerial` covering the ortho (`width × height` px) mapped by `ortho_to_aerial`, grown by
    /// `margin_ortho_px` ortho pixels on every side, clipped to the image, at level
    /// [`level_of_scale`]`(ortho_to_aerial.scale)`. `Ok(None)` when it misses the image.
    pub fn read(
        aerial: &dyn TileSource,
        (width, height): (usize, usize),
        ortho_to_aerial: &Similarity2,
        margin_ortho_px: f64,
    ) -> Result<Option<Self>, PyramidError> {
        let m = margin_ortho_px;
        let (w, h) = (width as f64, height as f64);
        let corners = [(-m, -m), (w + m, -m), (-m, h + m), (w + m, h + m)]
            .map(|(x, y)| ortho_to_aerial.apply(&Vector2::new(x, y)));
        let lo = |f: fn(&Vector2<f64>) -> f64| corners.iter().map(f).fold(f64::INFINITY, f64::min);
        let hi =
            |f: fn(&Vector2<f64>) -> f64| corners.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
        let level = level_of_scale(ortho_to_aerial.scale);
        let Some(window) = ScaledWindow::read(
            aerial,
            level,
            [lo(|c| c.x), lo(|c| c.y), hi(|c| c.x), hi(|c| c.y)],
        )?
        else {
            return Ok(None);
        };
        let s = window.scale();
        let t = ortho_to_aerial;
        let ortho_to_window = Similarity2 {
            scale: t.scale / s,
            rotation_rad: t.rotation_rad,
            tx: t.tx / s - window.rect.x0 as f64,
            ty: t.ty / s - window.rect.y0 as f64,
        };
        Ok(Some(Self {
            window,
            ortho_to_window,
        }))
    }

    /// Whether the full-resolution aerial pixel (u, v) lies inside the whole image.
    pub fn image_contains(&self, u_px: f64, v_px: f64) -> bool {
        let (w, h) = self.window.full_size;
        u_px >= 0.0 && v_px >= 0.0 && u_px < w as f64 && v_px < h as f64
    }

    /// The ortho pixel (u, v) of `ground_world` in `georef` and its full-resolution aerial location predicted by
    /// `ortho_to_aerial`; `None` when that location lies outside the whole image.
    pub fn predict(
        &self,
        georef: &OrthoGeoref,
        ortho_to_aerial: &Similarity2,
        ground_world: [f64; 3],
    ) -> Option<((f64, f64), Vector2<f64>)> {
        let g = ground_world;
        let (u_o, v_o) = georef.world_to_pixel(&Vector3::new(g[0], g[1], g[2]));
        let predicted = ortho_to_aerial.apply(&Vector2::new(u_o, v_o));
        self.image_contains(predicted.x, predicted.y)
            .then_some(((u_o, v_o), predicted))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::BrownDistortion;

    fn camera(kappa_deg: f64) -> FrameCamera {
        FrameCamera::from_opk(
            Vector3::new(1000.0, 2000.0, 4472.2),
            0.0,
            0.0,
            kappa_deg,
            44_700.0,
            256.0,
            192.0,
            512,
            384,
            BrownDistortion::default(),
        )
    }

    #[test]
    fn pure_kappa_gives_minus_kappa_azimuth_and_focal_gsd() {
        for kappa in [0.0, 30.0, -90.0, 180.0, -269.7] {
            let (gsd, az) =
                aerial_ground_similarity(&camera(kappa), [1003.0, 1995.0, 2.2]).unwrap();
            assert!((gsd - 4470.0 / 44_700.0).abs() < 1e-9, "gsd {gsd}");
            let expected = (-kappa).rem_euclid(360.0);
            let diff = (az - expected + 540.0).rem_euclid(360.0) - 180.0;
            assert!(
                diff.abs() < 1e-9,
                "κ {kappa}: azimuth {az}, expected {expected}"
            );
        }
    }

    #[test]
    fn patch_covers_the_grown_footprint_and_is_clipped() {
        let cam = camera(30.0);
        let foot = [1000.0, 2000.0, 2.2];
        let base = OrthoParams::default();
        let params = ortho_params_for_aerial(&cam, foot, &base);
        let georef = OrthoGeoref::new(foot, &params);
        let img = GrayImage::from_vec(
            512,
            384,
            (0..512 * 384).map(|i| (i % 512) as f32 / 512.0).collect(),
        )
        .unwrap();
        let pyramid = crate::imaging::pyramid::MemoryPyramid::from_gray(&img);
        let patch = extract_patch(&pyramid, &cam, &georef, 1.5, 0)
            .unwrap()
            .unwrap();
        // 212 px footprint + 2 × 15 px margin, centred on the principal point.
        let expected = georef.width_px as f64 + 30.0;
        assert!((patch.image.width as f64 - expected).abs() <= 2.0);
        assert!((patch.image.height as f64 - expected).abs() <= 2.0);
        assert!((patch.origin_u_px + patch.image.width as f64 / 2.0 - 256.0).abs() <= 1.0);
        let expected = img.get(
            3 + patch.origin_u_px as usize,
            5 + patch.origin_v_px as usize,
        );
        assert!((patch.image.get(3, 5) - expected).abs() < 1e-5);
        // At level 1 the patch covers the same region with half the pixels.
        let half = extract_patch(&pyramid, &cam, &georef, 1.5, 1)
            .unwrap()
            .unwrap();
        assert_eq!(half.scale, 2.0);
        assert!((half.image.width as f64 - patch.image.width as f64 / 2.0).abs() <= 1.0);
        let (u, v) = half.to_full(1.5, 2.5);
        assert_eq!(half.to_patch(u, v), (1.5, 2.5));
        // Near the image edge the patch is clipped to the image.
        let edge_foot = [1000.0, 2000.0 + 16.0, 2.2];
        let georef = OrthoGeoref::new(edge_foot, &params);
        let clipped = extract_patch(&pyramid, &cam, &georef, 1.5, 0)
            .unwrap()
            .unwrap();
        assert!(clipped.origin_u_px >= 0.0 && clipped.origin_v_px >= 0.0);
        assert!(clipped.origin_u_px as usize + clipped.image.width <= 512);
        assert!(clipped.origin_v_px as usize + clipped.image.height <= 384);
        // Far outside: no patch.
        let georef = OrthoGeoref::new([1000.0, 2100.0, 2.2], &params);
        assert!(extract_patch(&pyramid, &cam, &georef, 1.5, 0)
            .unwrap()
            .is_none());
    }

    #[test]
    fn working_levels_keep_the_gsd_at_or_below_the_registration_gsd() {
        assert_eq!(working_level(0.10, 0.12, (1600, 1200)), 0);
        assert_eq!(working_level(0.025, 0.12, (6400, 4800)), 2);
        assert_eq!(working_level(0.00605, 0.12, (26460, 17004)), 4);
        assert_eq!(working_level(0.06, 0.12, (1000, 1000)), 1);
        assert_eq!(working_level(0.001, 0.12, (64, 64)), 1);
        assert_eq!(level_of_scale(4.0003), 2);
        assert_eq!(level_of_scale(0.98), 0);
        // A frame 4× finer gives an ortho at the same GSD.
        let coarse = camera(0.0);
        let fine = FrameCamera::from_opk(
            Vector3::new(1000.0, 2000.0, 4472.2),
            0.0,
            0.0,
            0.0,
            4.0 * 44_700.0,
            4.0 * 256.0,
            4.0 * 192.0,
            4 * 512,
            4 * 384,
            BrownDistortion::default(),
        );
        let base = OrthoParams {
            registration_gsd_m: 0.12,
            ..OrthoParams::default()
        };
        let foot = [1003.0, 1995.0, 2.2];
        let a = ortho_params_for_aerial(&coarse, foot, &base);
        let b = ortho_params_for_aerial(&fine, foot, &base);
        assert_eq!(a.gsd_m, b.gsd_m);
    }
}

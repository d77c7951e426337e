//! The aerial side of MM↔aerial registration (thesis 3.4.5.1–3.4.5.2): ortho parameters that make a recording's
//! ortho image resemble an aerial nadir image (same ground sampling distance, same orientation), and the aerial
//! image patch that covers the recording's ortho footprint enlarged by the expected maximum localisation error.
//!
//! Both are derived from the aerial camera's geometry at the foot point, not from the sign convention of κ: the
//! local Jacobian of the projection (world E, N on the horizontal plane through the foot point → aerial pixels)
//! gives the GSD (`1/√|det J|`, metres per pixel) and the rotation of the nearest similarity gives the azimuth of
//! the aerial image's "up" direction, which becomes the ortho image's `rotation_deg` (see `ortho.rs`: the ortho's
//! "up" points at azimuth `rotation_deg`). Ortho pixels then map to aerial pixels by (nearly) a pure translation.

use super::ortho::{OrthoGeoref, OrthoParams};
use crate::geometry::FrameCamera;
use crate::imaging::GrayImage;
use crate::params::StageId;
use nalgebra::Vector3;

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId {
    name: "ortho_aerial",
    version: "3",
};

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

/// `base` with the GSD set to the aerial GSD at `foot_world` and the rotation set so that the ortho image's axes
/// are aligned with the aerial image's axes (thesis 3.4.5.2: "the resolution of the projected MM images is set to
/// match the aerial images' resolution"). If the foot point does not project into the camera, `base` is returned
/// unchanged (such an image does not overlap the recording; see `aerial_overlap`).
pub fn ortho_params_for_aerial(
    cam: &FrameCamera,
    foot_world: [f64; 3],
    base: &OrthoParams,
) -> OrthoParams {
    match aerial_ground_similarity(cam, foot_world) {
        Some((gsd_m, rotation_deg)) => OrthoParams {
            gsd_m,
            rotation_deg,
            ..base.clone()
        },
        None => base.clone(),
    }
}

/// A rectangular crop of an aerial image.
#[derive(Clone, Debug, PartialEq)]
pub struct AerialPatch {
    pub image: GrayImage,
    /// Full-image continuous pixel coordinates of the patch's (0, 0) corner (integers): a patch pixel (u, v)
    /// is the full-image pixel (u + origin_u_px, v + origin_v_px).
    pub origin_u_px: f64,
    pub origin_v_px: f64,
}

impl AerialPatch {
    /// Full-image pixel of a patch pixel.
    pub fn to_full(&self, u_px: f64, v_px: f64) -> (f64, f64) {
        (u_px + self.origin_u_px, v_px + self.origin_v_px)
    }

    /// Patch pixel of a full-image pixel.
    pub fn to_patch(&self, u_px: f64, v_px: f64) -> (f64, f64) {
        (u_px - self.origin_u_px, v_px - self.origin_v_px)
    }
}

/// The region of `aerial` (camera `cam`) covering the ortho footprint of `georef` enlarged by `margin_m` on every
/// side (thesis 3.4.5.1: the patch "overlaps the MM image to the extent of the expected localisation error"),
/// clipped to the image. The footprint's corners and edge midpoints are projected through the camera and their
/// bounding box taken (whole pixels). `None` if a footprint point lies behind the camera or the clipped patch is
/// smaller than [`MIN_PATCH_SIDE_PX`] on a side.
pub fn extract_patch(
    aerial: &GrayImage,
    cam: &FrameCamera,
    georef: &OrthoGeoref,
    margin_m: f64,
) -> Option<AerialPatch> {
    if !(margin_m.is_finite() && georef.gsd_m > 0.0) {
        return None;
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
            let (u, v) = cam.project_world(&georef.pixel_to_world(x, y))?;
            u_min = u_min.min(u);
            u_max = u_max.max(u);
            v_min = v_min.min(v);
            v_max = v_max.max(v);
        }
    }
    if !(u_min.is_finite() && u_max.is_finite() && v_min.is_finite() && v_max.is_finite()) {
        return None;
    }
    let col0 = u_min.floor().max(0.0);
    let row0 = v_min.floor().max(0.0);
    let col1 = u_max.ceil().min(aerial.width as f64);
    let row1 = v_max.ceil().min(aerial.height as f64);
    if !(col1 - col0 >= MIN_PATCH_SIDE_PX as f64 && row1 - row0 >= MIN_PATCH_SIDE_PX as f64) {
        return None;
    }
    let (c0, r0, c1, r1) = (col0 as usize, row0 as usize, col1 as usize, row1 as usize);
    let mut data = Vec::with_capacity((c1 - c0) * (r1 - r0));
    for row in r0..r1 {
        data.extend_from_slice(&aerial.row(row)[c0..c1]);
    }
    Some(AerialPatch {
        image: GrayImage::from_vec(c1 - c0, r1 - r0, data)?,
        origin_u_px: col0,
        origin_v_px: row0,
    })
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
        let patch = extract_patch(&img, &cam, &georef, 1.5).unwrap();
        // 212 px footprint + 2 × 15 px margin, centred on the principal point.
        let expected = georef.width_px as f64 + 30.0;
        assert!((patch.image.width as f64 - expected).abs() <= 2.0);
        assert!((patch.image.height as f64 - expected).abs() <= 2.0);
        assert!((patch.origin_u_px + patch.image.width as f64 / 2.0 - 256.0).abs() <= 1.0);
        assert_eq!(
            patch.image.get(3, 5),
            img.get(
                3 + patch.origin_u_px as usize,
                5 + patch.origin_v_px as usize
            )
        );
        // Near the image edge the patch is clipped to the image.
        let edge_foot = [1000.0, 2000.0 + 16.0, 2.2];
        let georef = OrthoGeoref::new(edge_foot, &params);
        let clipped = extract_patch(&img, &cam, &georef, 1.5).unwrap();
        assert!(clipped.origin_u_px >= 0.0 && clipped.origin_v_px >= 0.0);
        assert!(clipped.origin_u_px as usize + clipped.image.width <= 512);
        assert!(clipped.origin_v_px as usize + clipped.image.height <= 384);
        // Far outside: no patch.
        let georef = OrthoGeoref::new([1000.0, 2100.0, 2.2], &params);
        assert!(extract_patch(&img, &cam, &georef, 1.5).is_none());
    }
}

//! The chapter-2 baseline for MM↔aerial registration (thesis 2.2.3): isolated Förstner keypoints in the aerial
//! image and normalised cross-correlation template matching — the "Förstner/CC" column of thesis Table 2-10,
//! run as a workflow variant against the full method (3.4.5.3). It produces the same [`AerialRefinement`] as
//! [`super::refine::refine_in_aerial`], so control points and grading are shared.
//!
//! Steps (thesis 2.2.3.1–2.2.3.2):
//! 1. Förstner keypoints (Köthe's 2× tensor) only in the aerial image, inside the region the MM ortho image
//!    covers (through the initial transform);
//! 2. a kd-tree over them; a keypoint is **isolated** when at most `max_neighbours` others lie in the
//!    `isolation_box_m` × `isolation_box_m` box around it (repetitive markings produce crowded corners);
//! 3. the MM ortho image is blurred by a Gaussian to resemble the aerial image (2.2.3.1);
//! 4. per MM tie point: a `template_px` MM template around its corner is cross-correlated (NCC,
//!    `TM_CCOEFF_NORMED`) inside a `search_px` aerial window (resampled onto the ortho grid through the
//!    transform, as in `refine`), sub-pixel peak by a quadratic fit; the peak must reach `min_ncc`;
//! 5. as in the thesis, the measurement in the aerial image is the keypoint itself ("the location of the peak
//!    is assumed to correspond to the extracted keypoint"): the nearest isolated keypoint within `snap_px` of
//!    the peak becomes the observation; without one the tie point is not located.
//!
//! The thesis matched aerial templates inside MM windows and named the reverse ("using parts of the MM image as
//! a template") as future work; we run the reverse so that each observation belongs to an MM tie point.

mod kdtree;

pub use kdtree::KdTree2;

use rayon::prelude::*;

use super::aerial_patch::AerialWindow;
use super::ortho::OrthoImage;
use super::refine::{cut_ortho_template, grey_std, sample_aerial_on_ortho_grid};
use super::registration::{AerialMatch, AerialRefinement, InitialTransform, MmWindowMatch};
use crate::campaign::{AerialImage, AerialKind};
use crate::correspondence::AerialObservation;
use crate::features::forstner::{forstner_corners, ForstnerParams};
use crate::geometry::FrameCamera;
use crate::imaging::gaussian::gaussian_blur;
use crate::imaging::pyramid::{PyramidError, TileSource};
use crate::imaging::GrayImage;
use crate::matching::ncc::match_template;
use crate::params::{Params, StageId};
use nalgebra::{Vector2, Vector3};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("baseline", "8");

crate::params! {
    /// Parameters of [`baseline_matches`]; thesis 2.2.3 values as defaults.
    pub struct BaselineParams {
        /// Förstner σ of the derivative-of-Gaussian gradient, in aerial pixels.
        forstner_sigma_gradient_px: f32 = 0.7, unit "px", above 0.0, max 20.0;
        /// Förstner σ of the tensor's integration window, in aerial pixels.
        forstner_sigma_integration_px: f32 = 2.0, unit "px", above 0.0, max 20.0;
        /// Förstner minimum roundness q.
        forstner_min_roundness: f32 = 0.5, min 0.0, max 1.0;
        /// Förstner minimum weight relative to the patch's mean weight.
        forstner_min_weight_rel: f32 = 1.0, min 0.0;
        /// Side of the square neighbourhood of the isolation test (thesis: 6 × 6 m).
        isolation_box_m: f64 = 6.0, unit "m", above 0.0, max 100.0;
        /// A keypoint is isolated with at most this many other keypoints in the box (thesis: 7).
        max_neighbours: usize = 7;
        /// σ of the Gaussian blur of the MM ortho image; 0 = none.
        mm_blur_sigma_px: f32 = 1.0, unit "px", min 0.0, max 10.0;
        /// Template side (thesis: 16).
        template_px: usize = 16, unit "px", min 4, max 128;
        /// Search window side (thesis: 40); larger than `template_px`.
        search_px: usize = 40, unit "px", max 512;
        /// Smallest accepted NCC peak.
        min_ncc: f64 = 0.7, min -1.0, max 1.0;
        /// Largest distance from the NCC peak to the isolated aerial keypoint that becomes the observation.
        snap_px: f64 = 1.5, unit "px", above 0.0, max 20.0;
        /// Smallest grey-value standard deviation of a template (0..1 scale).
        min_template_std: f64 = 0.01, min 0.0;
    }
    check(p, v) {
        if p.search_px <= p.template_px {
            v.push(crate::params::Violation::new(
                "search_px",
                format!(
                    "must be larger than template_px ({}), got {}",
                    p.template_px, p.search_px
                ),
            ));
        }
    }
}

impl BaselineParams {
    fn forstner(&self) -> ForstnerParams {
        ForstnerParams {
            sigma_gradient_px: self.forstner_sigma_gradient_px,
            sigma_integration_px: self.forstner_sigma_integration_px,
            min_roundness: self.forstner_min_roundness,
            min_weight_rel: self.forstner_min_weight_rel,
            ..ForstnerParams::default()
        }
    }
}

/// Isolated Förstner keypoints (full aerial pixels) in `aerial`, the window of the aerial image around the
/// part `mm_ortho` covers (grown by half the isolation box so that keypoints near its edge see all their
/// neighbours, [`AerialWindow`]); `gsd_m` is the aerial GSD on the ground at full resolution, m/px (thesis
/// 2.2.3.2). The detector runs on the window's level.
pub fn isolated_aerial_keypoints(
    aerial: &AerialWindow,
    gsd_m: f64,
    p: &BaselineParams,
) -> Vec<[f64; 2]> {
    let half_box_px = p.isolation_box_m / 2.0 / gsd_m;
    let patch = &aerial.window.image;
    if !(patch.width >= 8 && patch.height >= 8) {
        return Vec::new();
    }
    let points: Vec<[f64; 2]> = forstner_corners(patch, &p.forstner())
        .into_iter()
        .map(|c| {
            let (u, v) = aerial.window.to_full(c.u_px, c.v_px);
            [u, v]
        })
        .collect();
    let tree = KdTree2::build(&points);
    points
        .iter()
        .copied()
        .filter(|&c| tree.count_in_box(c, [half_box_px, half_box_px]) - 1 <= p.max_neighbours)
        .collect()
}

/// Locate the tie points of `window` in one aerial nadir image with the chapter-2 method (thesis 2.2.3);
/// inputs as for [`super::refine::refine_in_aerial`]. Matches keep the tie-point order; the score is the NCC
/// peak. Invalid parameters or transform yield an empty refinement.
pub fn baseline_matches(
    mm_ortho: &OrthoImage,
    aerial: &dyn TileSource,
    aerial_row: &AerialImage,
    t: &InitialTransform,
    window: &MmWindowMatch,
    p: &BaselineParams,
) -> Result<AerialRefinement, PyramidError> {
    let mut result = AerialRefinement::empty(&t.recording_id, &aerial_row.image_id);
    let tf = t.ortho_to_aerial;
    if !tf.is_usable() || p.validate().is_err() {
        return Ok(result);
    }
    let foot = Vector3::from(mm_ortho.georef.foot_world);
    let gsd_m = FrameCamera::from_aerial(aerial_row).gsd_at(&foot);
    if !(gsd_m.is_finite() && gsd_m > 0.0) {
        return Ok(result);
    }
    // The window must hold the isolation boxes of keypoints at the footprint's edge and every search window.
    let margin_ortho_px = (p.isolation_box_m / 2.0 / gsd_m) / tf.scale + p.search_px as f64 + 4.0;
    let size = (mm_ortho.image.width, mm_ortho.image.height);
    let Some(aerial_window) = AerialWindow::read(aerial, size, &tf, margin_ortho_px)? else {
        return Ok(result);
    };
    let keypoints = isolated_aerial_keypoints(&aerial_window, gsd_m, p);
    let tf_window = aerial_window.ortho_to_window;
    // Snapping distance in full-resolution pixels (the parameter is in working pixels).
    let snap_px = p.snap_px * aerial_window.window.scale();
    let keypoint_tree = KdTree2::build(&keypoints);
    let blurred = OrthoImage {
        image: if p.mm_blur_sigma_px > 0.0 {
            gaussian_blur(&mm_ortho.image, p.mm_blur_sigma_px)
        } else {
            mm_ortho.image.clone()
        },
        valid: mm_ortho.valid.clone(),
        georef: mm_ortho.georef.clone(),
    };
    let n = window.tie_points.len().min(window.ground_world.len());
    let outcomes: Vec<(bool, Option<AerialMatch>)> = (0..n)
        .into_par_iter()
        .map_init(
            || (GrayImage::filled(0, 0, 0.0), GrayImage::filled(0, 0, 0.0)),
            |(template, search), i| {
                let g = window.ground_world[i];
                let Some(((u_o, v_o), predicted)) = aerial_window.predict(&blurred.georef, &tf, g)
                else {
                    return (false, None);
                };
                // No isolated keypoint anywhere near: nothing to measure (saves the NCC).
                let reach = p.search_px as f64 / 2.0 * tf.scale + snap_px;
                if keypoint_tree.count_in_box([predicted.x, predicted.y], [reach, reach]) == 0 {
                    return (true, None);
                }
                let half = p.template_px as f64 / 2.0;
                let (x0, y0) = ((u_o - half).round(), (v_o - half).round());
                if !cut_ortho_template(&blurred, x0 as isize, y0 as isize, p.template_px, template)
                    || grey_std(template) < p.min_template_std
                {
                    return (true, None);
                }
                let margin = ((p.search_px - p.template_px) / 2) as f64;
                let side = p.template_px + 2 * ((p.search_px - p.template_px) / 2);
                if !sample_aerial_on_ortho_grid(
                    &aerial_window.window.image,
                    &tf_window,
                    x0 - margin,
                    y0 - margin,
                    side,
                    side,
                    search,
                ) {
                    return (true, None);
                }
                let Ok(m) = match_template(search, template) else {
                    return (true, None);
                };
                if !(m.score as f64 >= p.min_ncc) {
                    return (true, None);
                }
                let dx = (x0 - margin + m.u_px) - (x0 + half);
                let dy = (y0 - margin + m.v_px) - (y0 + half);
                let peak = tf.apply(&Vector2::new(u_o + dx, v_o + dy));
                // Snap to the nearest isolated keypoint (ties: the first in keypoint order).
                let mut best: Option<([f64; 2], f64)> = None;
                for &k in &keypoints {
                    let d = (k[0] - peak.x).hypot(k[1] - peak.y);
                    if d <= snap_px && best.is_none_or(|(_, bd)| d < bd) {
                        best = Some((k, d));
                    }
                }
                let Some((k, _)) = best else {
                    return (true, None);
                };
                let observation = AerialObservation {
                    image_id: aerial_row.image_id.clone(),
                    kind: AerialKind::Nadir,
                    u_px: k[0],
                    v_px: k[1],
                    score: m.score as f64,
                    sigma_px: None,
                };
                (
                    true,
                    Some(AerialMatch {
                        tie_point_id: window.tie_points[i].id.clone(),
                        observation,
                        predicted_u_px: predicted.x,
                        predicted_v_px: predicted.y,
                        level: aerial_window.window.level,
                        view_disagreement_px: None,
                    }),
                )
            },
        )
        .collect();
    for (tried, m) in outcomes {
        result.tried += usize::from(tried);
        result.matches.extend(m);
    }
    Ok(result)
}

//! Corner features of the detecting ortho image and their transfer into a neighbour (thesis 3.4.4.4):
//! Förstner corners at sub-pixel precision (Köthe's 2× tensor) away from masked pixels, carried into the
//! neighbour by the pair transform, located there by NCC template matching in a small search window (and
//! matched back: the neighbour's template at that location must lead back to the corner), and verified again: the located position must agree with the transferred one (after removing the pair's
//! median offset, which is the relative pose error when the transform came from the poses) within a
//! tolerance.

use super::pair_transform::PairTransform;
use super::params::MmMatchParams;
use super::prepared::PreparedOrtho;
use super::template::{match_corner, TemplateScratch};
use super::OrthoView;
use crate::estimators::median_consensus::median_in_place;
use crate::features::forstner::{forstner_corners, Corner, ForstnerParams};
use rayon::prelude::*;

/// Förstner settings from the matching parameters (sub-pixel, Köthe 2×).
pub fn forstner_params(p: &MmMatchParams) -> ForstnerParams {
    ForstnerParams {
        sigma_gradient_px: p.forstner_sigma_gradient_px,
        sigma_integration_px: p.forstner_sigma_integration_px,
        min_roundness: p.forstner_min_roundness,
        min_weight_rel: p.forstner_min_weight_rel,
        nms_radius_px: p.forstner_nms_radius_px,
        upsample_2x: true,
        max_corners: None,
        ..ForstnerParams::default()
    }
}

/// The detecting image's corners (thesis 3.4.4.4): strongest first, each with a fully valid template and
/// within `max_corner_distance_m` of the camera's foot point, at most `max_corners`.
pub fn detect_corners(view: &OrthoView, prep: &PreparedOrtho, p: &MmMatchParams) -> Vec<Corner> {
    let g = &view.ortho.georef;
    let (cu, cv) = (g.width_px as f64 / 2.0, g.height_px as f64 / 2.0);
    let max_px = p.max_corner_distance_m / g.gsd_m;
    let half = p.template_half_px as i64;
    let mut corners = forstner_corners(&prep.filled, &forstner_params(p));
    corners.retain(|c| {
        (c.u_px - cu).hypot(c.v_px - cv) <= max_px
            && prep
                .valid
                .square_valid(c.u_px.floor() as i64, c.v_px.floor() as i64, half)
    });
    corners.truncate(p.max_corners);
    corners
}

/// A corner located in the neighbour image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocatedCorner {
    /// Neighbour ortho pixel, continuous.
    pub u_px: f64,
    pub v_px: f64,
    /// NCC peak value.
    pub score: f64,
}

/// Template match of one corner: the position in the neighbour and the displacement from the transferred
/// position (neighbour px).
fn locate(
    det: &PreparedOrtho,
    nb: &PreparedOrtho,
    corner: &Corner,
    predicted: (f64, f64),
    radius: usize,
    p: &MmMatchParams,
    scratch: &mut TemplateScratch,
) -> Option<(LocatedCorner, (f64, f64))> {
    let half = p.template_half_px;
    let (sc, sr) = (corner.u_px.floor() as i64, corner.v_px.floor() as i64);
    let (dc, dr) = (predicted.0.floor() as i64, predicted.1.floor() as i64);
    if !(predicted.0.is_finite()
        && predicted.1.is_finite()
        && nb.valid.square_valid(dc, dr, half as i64 + radius as i64))
    {
        return None;
    }
    let peak = match_corner(
        &det.filled,
        sc,
        sr,
        &nb.filled,
        dc,
        dr,
        half,
        radius,
        scratch,
    )?;
    if peak.score < p.min_ncc as f64 {
        return None;
    }
    // The template's centre pixel (sc, sr) landed at (dc, dr) + offset; the corner keeps its sub-pixel
    // position relative to that pixel's centre.
    let u = dc as f64 + 0.5 + peak.offset_u_px + (corner.u_px - (sc as f64 + 0.5));
    let v = dr as f64 + 0.5 + peak.offset_v_px + (corner.v_px - (sr as f64 + 0.5));
    // Back-matching: the neighbour's template at the located position must lead back to the corner.
    let (bc, br) = (u.floor() as i64, v.floor() as i64);
    let back_radius = p.max_backmatch_px.ceil() as usize + 1;
    let back = match_corner(
        &nb.filled,
        bc,
        br,
        &det.filled,
        sc,
        sr,
        half,
        back_radius,
        scratch,
    )?;
    let back_u = sc as f64 + 0.5 + back.offset_u_px + (u - (bc as f64 + 0.5));
    let back_v = sr as f64 + 0.5 + back.offset_v_px + (v - (br as f64 + 0.5));
    if back.score < p.min_ncc as f64
        || (back_u - corner.u_px).hypot(back_v - corner.v_px) > p.max_backmatch_px
    {
        return None;
    }
    Some((
        LocatedCorner {
            u_px: u,
            v_px: v,
            score: peak.score,
        },
        (u - predicted.0, v - predicted.1),
    ))
}

/// Locate every corner in the neighbour (thesis 3.4.4.4). One entry per corner: `Some` when the template
/// match succeeded and passed the verification. Deterministic for any thread count (per-corner results,
/// ordered collect, median of the sorted offsets).
pub fn match_corners(
    det_view: &OrthoView,
    det: &PreparedOrtho,
    nb_view: &OrthoView,
    nb: &PreparedOrtho,
    corners: &[Corner],
    transform: &PairTransform,
    p: &MmMatchParams,
) -> Vec<Option<LocatedCorner>> {
    let radius = match transform {
        PairTransform::Homography(_) => p.search_radius_px,
        PairTransform::Poses => p.fallback_search_radius_px,
    };
    let (ga, gb) = (&det_view.ortho.georef, &nb_view.ortho.georef);
    let located: Vec<Option<(LocatedCorner, (f64, f64))>> = corners
        .par_iter()
        .map_init(TemplateScratch::default, |scratch, c| {
            let predicted = transform.transfer(ga, gb, c.u_px, c.v_px)?;
            locate(det, nb, c, predicted, radius, p, scratch)
        })
        .collect();
    let mut du: Vec<f64> = located.iter().flatten().map(|(_, d)| d.0).collect();
    let mut dv: Vec<f64> = located.iter().flatten().map(|(_, d)| d.1).collect();
    let (mu, mv) = (
        median_in_place(&mut du).unwrap_or(0.0),
        median_in_place(&mut dv).unwrap_or(0.0),
    );
    located
        .into_iter()
        .map(|l| {
            let (c, d) = l?;
            ((d.0 - mu).hypot(d.1 - mv) <= p.corner_tolerance_px).then_some(c)
        })
        .collect()
}

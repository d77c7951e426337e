//! What one patch-registration node reads of its two images: the oblique image as one window, at the level
//! of its pyramid the patches are made at, covering every candidate's patches and search range; the panorama
//! as bands of rows at the levels its patches sample ([`crate::oblique::patch::panorama_sampling`]).

use super::PatchParams;
use crate::geometry::frame::FrameCamera;
use crate::geometry::panorama::PanoramaCamera;
use crate::imaging::equirect::PanoramaLevels;
use crate::imaging::pyramid::{
    footprint_level, PyramidError, PyramidLayout, ScaledWindow, TileSource,
};
use crate::oblique::patch::panorama_sampling;
use crate::oblique::types::{FacadePlane, ObliqueView, SparsePoint};
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// One façade point to register, as the inputs see it.
pub struct PointInPlane<'a> {
    pub plane: &'a FacadePlane,
    pub view: &'a ObliqueView,
    pub point: &'a SparsePoint,
}

/// Half the side of the square (in the plane, metres) around a point that any of its patches, shifted by
/// any searched shift, can cover.
fn reach_m(p: &PatchParams) -> f64 {
    let extent = p
        .coarse_extent_m
        .max(p.fine_extent_m)
        .max(p.single_extent_m);
    std::f64::consts::SQRT_2 * extent / 2.0 + p.search_radius_m + p.fine_window_m
}

/// The pyramid level of the oblique image the patches are made at: the coarsest whose resolution at the
/// finest candidate does not exceed `registration_resolution_m`, and not finer than the image's detail level
/// (`layout.detail_level`: levels below it only repeat its pixels, so an image enlarged by pixel repetition
/// is registered like the image it was enlarged from, even when that is coarser than
/// `registration_resolution_m`).
pub fn oblique_level(points: &[PointInPlane], p: &PatchParams, layout: &PyramidLayout) -> usize {
    let detail_level = layout.detail_level.min(layout.levels() - 1);
    let finest = points
        .iter()
        .map(|c| c.view.resolution_m)
        .filter(|r| r.is_finite() && *r > 0.0)
        .fold(f64::INFINITY, f64::min);
    if !finest.is_finite() {
        return detail_level;
    }
    footprint_level(finest, p.registration_resolution_m, layout.levels()).max(detail_level)
}

/// The window of the oblique image at `level` covering the patches of every point (`Ok(None)` when they all
/// miss the image).
pub fn oblique_window(
    source: &dyn TileSource,
    cam: &FrameCamera,
    points: &[PointInPlane],
    p: &PatchParams,
    level: usize,
) -> Result<Option<ScaledWindow>, PyramidError> {
    let r = reach_m(p);
    let mut bbox = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for c in points {
        let centre = Vector3::from(c.point.tie.point_world);
        let (u, v) = (
            Vector3::from(c.plane.axis_u_world),
            Vector3::from(c.plane.axis_v_world),
        );
        for (a, b) in [
            (-1.0, -1.0),
            (1.0, -1.0),
            (-1.0, 1.0),
            (1.0, 1.0),
            (0.0, 0.0),
        ] {
            if let Some((x, y)) = cam.project_world(&(centre + u * (a * r) + v * (b * r))) {
                bbox = [
                    bbox[0].min(x),
                    bbox[1].min(y),
                    bbox[2].max(x),
                    bbox[3].max(y),
                ];
            }
        }
    }
    if !bbox.iter().all(|v| v.is_finite()) {
        return Ok(None);
    }
    let s = (1u64 << level) as f64;
    let margin = 2.0 * s;
    ScaledWindow::read(
        source,
        level,
        [
            bbox[0] - margin,
            bbox[1] - margin,
            bbox[2] + margin,
            bbox[3] + margin,
        ],
    )
}

/// The panorama bands the patches of every point sample: per level of [`panorama_sampling`] (for the coarse
/// and the fine spacing at `oblique_scale` × the theoretical resolution), the rows their patches reach.
pub fn panorama_bands(
    source: &dyn TileSource,
    cam: &PanoramaCamera,
    points: &[PointInPlane],
    p: &PatchParams,
    oblique_scale: f64,
) -> Result<PanoramaLevels, PyramidError> {
    let levels = (source.layout().detail_level, source.layout().levels() - 1);
    let rows_per_rad = f64::from(cam.height_px) / std::f64::consts::PI;
    let r = reach_m(p);
    let mut rows: BTreeMap<usize, (f64, f64)> = BTreeMap::new();
    for c in points {
        let centre = Vector3::from(c.point.tie.point_world);
        let range = (centre - cam.center_world).norm();
        let Some((_, v)) = cam.project_world(&centre) else {
            continue;
        };
        let half_rows = (r / range.max(0.5)).min(std::f64::consts::PI) * rows_per_rad + 2.0;
        // The spacings `Context::spacing` gives the coarse, fine and single levels' grids.
        let spacing = c.view.resolution_m * oblique_scale;
        let grid_spacing = |extent: f64, sp: f64| sp.max(extent / p.max_patch_px as f64);
        for sp in [
            grid_spacing(p.coarse_extent_m, spacing * p.coarse_spacing_factor),
            grid_spacing(p.fine_extent_m, spacing),
            grid_spacing(p.single_extent_m, spacing),
        ] {
            let (level, _) = panorama_sampling(sp, range, cam.width_px, levels);
            let e = rows
                .entry(level)
                .or_insert((f64::INFINITY, f64::NEG_INFINITY));
            *e = (e.0.min(v - half_rows), e.1.max(v + half_rows));
        }
    }
    if rows.is_empty() {
        rows.insert(0, (0.0, 1.0));
    }
    let wanted: Vec<(usize, (f64, f64))> = rows.into_iter().collect();
    PanoramaLevels::read_bands(source, &wanted)
}

//! The initial transform of a panorama's ground ortho into the orthophoto (the orthophoto's counterpart of
//! thesis 3.4.5.2). An orthophoto is north-up with a known pixel size, so the ortho is made north-up at the
//! orthophoto's resolution and the two differ by a translation only — the recording's position error. It is
//! found by phase correlation of the ortho's centre — the road around the vehicle, `road_template_m` wide,
//! without the façades that the ortho-projection smears across the ground (the vehicle's masked pixels set to
//! the mean) — against the orthophoto sampled on the ortho grid, grown on every side by the largest offset
//! searched; both Wallis-filtered first. A peak below
//! `min_peak` or an offset beyond `max_offset_m` rejects the recording, with the reason.

use super::OrthophotoParams;
use crate::geometry::Similarity2;
use crate::imaging::georef::GeoTransform;
use crate::imaging::pyramid::{PyramidError, TileSource};
use crate::imaging::wallis::{wallis_filter, WallisParams};
use crate::imaging::GrayImage;
use crate::matching::phase_correlation::{locate_template, PhaseCorrelationParams};
use crate::nadir::aerial_patch::AerialWindow;
use crate::nadir::refine::sample_aerial_on_ortho_grid;
use crate::nadir::{InitialTransform, OrthoGeoref, OrthoImage, TransformOutcome};

/// Ortho pixel → full orthophoto pixel for the ortho's recorded placement.
pub fn nominal_transform(georef: &OrthoGeoref, photo: &GeoTransform) -> Similarity2 {
    let p0 = georef.pixel_to_world(0.0, 0.0);
    let p1 = georef.pixel_to_world(1.0, 0.0);
    let (u0, v0) = photo.world_to_pixel(p0.x, p0.y);
    let (u1, v1) = photo.world_to_pixel(p1.x, p1.y);
    Similarity2::from_ab(u1 - u0, v1 - v0, u0, v0)
}

/// The central `side × side` pixels of the ortho (the road around the vehicle), masked pixels set to the mean
/// of the valid ones, Wallis-filtered like the search window; and the crop's top-left ortho pixel.
fn road_template(ortho: &OrthoImage, side: usize) -> (GrayImage, (usize, usize)) {
    let filled = filled_template(ortho);
    let (w, h) = (filled.width, filled.height);
    let (cw, ch) = (side.min(w), side.min(h));
    let (x0, y0) = ((w - cw) / 2, (h - ch) / 2);
    let mut crop = GrayImage::filled(cw, ch, 0.0);
    for r in 0..ch {
        let start = (y0 + r) * w + x0;
        crop.data[r * cw..(r + 1) * cw].copy_from_slice(&filled.data[start..start + cw]);
    }
    (wallis_or_same(crop), (x0, y0))
}

/// The image Wallis-filtered (thesis 3.4.5.2 equalises MM and aerial contrast so), or unchanged if it cannot be.
fn wallis_or_same(img: GrayImage) -> GrayImage {
    wallis_filter(&img, &WallisParams::default()).unwrap_or(img)
}

/// The ortho's grey values with masked pixels set to the mean of the valid ones.
fn filled_template(ortho: &OrthoImage) -> GrayImage {
    let valid: Vec<f32> = ortho
        .image
        .data
        .iter()
        .zip(&ortho.valid)
        .filter(|(_, &ok)| ok != 0)
        .map(|(&g, _)| g)
        .collect();
    let mean = valid.iter().map(|&g| f64::from(g)).sum::<f64>() / valid.len().max(1) as f64;
    let mut img = ortho.image.clone();
    for (g, &ok) in img.data.iter_mut().zip(&ortho.valid) {
        if ok == 0 {
            *g = mean as f32;
        }
    }
    img
}

/// Register `ortho` (recording `recording_id`) in the orthophoto tile `photo` (id `photo_id`, placed by
/// `photo_transform`); see the module documentation. `Err` only when the orthophoto cannot be read.
pub fn register_translation(
    ortho: &OrthoImage,
    recording_id: &str,
    photo: &dyn TileSource,
    photo_id: &str,
    photo_transform: &GeoTransform,
    p: &OrthophotoParams,
) -> Result<TransformOutcome, PyramidError> {
    let reject = |reason: String| TransformOutcome::Rejected {
        recording_id: recording_id.to_string(),
        aerial_id: photo_id.to_string(),
        reason,
        matches: 0,
        inliers: 0,
    };
    let nominal = nominal_transform(&ortho.georef, photo_transform);
    let gsd_m = ortho.georef.gsd_m;
    let m = (p.max_offset_m / gsd_m).ceil() as usize;
    let (w, h) = (ortho.image.width, ortho.image.height);
    let Some(win) = AerialWindow::read(photo, (w, h), &nominal, m as f64 + 4.0)? else {
        return Ok(reject("the orthophoto does not cover the recording".into()));
    };
    let mut search = GrayImage::filled(0, 0, 0.0);
    let (mf, wf, hf) = (m as f64, w as f64, h as f64);
    if !sample_aerial_on_ortho_grid(
        &win.window.image,
        &win.ortho_to_window,
        -mf,
        -mf,
        w + 2 * m,
        h + 2 * m,
        &mut search,
    ) {
        return Ok(reject(format!(
            "the orthophoto ends within {} m of the recording's ground ortho",
            p.max_offset_m
        )));
    }
    let side = (p.road_template_m / gsd_m).round().max(8.0) as usize;
    let (template, (x0, y0)) = road_template(ortho, side);
    let search = wallis_or_same(search);
    let Ok(loc) = locate_template(&template, &search, &PhaseCorrelationParams::default()) else {
        return Ok(reject("phase correlation failed".into()));
    };
    // The template's centre is at ortho pixel (x0 + tw/2, y0 + th/2), i.e. search pixel m + that.
    let (tw, th) = (template.width as f64, template.height as f64);
    let dx = loc.u_px - (mf + x0 as f64 + tw / 2.0);
    let dy = loc.v_px - (mf + y0 as f64 + th / 2.0);
    let offset_m = dx.hypot(dy) * gsd_m;
    if !(offset_m <= p.max_offset_m) {
        return Ok(reject(format!(
            "offset {offset_m:.2} m > max_offset_m {} m",
            p.max_offset_m
        )));
    }
    if !(loc.peak >= p.min_peak) {
        return Ok(reject(format!(
            "correlation peak {:.3} < min_peak {}",
            loc.peak, p.min_peak
        )));
    }
    let (a, b) = nominal.ab();
    let tf = Similarity2::from_ab(
        a,
        b,
        nominal.tx + a * dx - b * dy,
        nominal.ty + b * dx + a * dy,
    );
    let c0 = ortho.georef.pixel_to_world(wf / 2.0, hf / 2.0);
    let c1 = ortho.georef.pixel_to_world(wf / 2.0 + dx, hf / 2.0 + dy);
    Ok(TransformOutcome::Accepted(InitialTransform {
        recording_id: recording_id.to_string(),
        aerial_id: photo_id.to_string(),
        ortho_to_aerial: tf,
        matches: 0,
        inliers: 0,
        centre_offset_m: offset_m,
        centre_offset_world_m: [c1.x - c0.x, c1.y - c0.y],
        reused_from: None,
    }))
}

//! The nadir registration view (thesis Figs 3.6, 3.11, 3.12): the recording's north-up MM ortho image beside
//! the aerial nadir image resampled onto the same ground grid, each correspondence a line between its two
//! observations.

use super::{best_aerial, canvas, save, truth, Context, ControlPoint, ViewCounts};
use crate::report::image_cache::ImageCache;
use canvas::{crop_scaled, line, resample_on_ground, ring, side_by_side, Black};
use nalgebra::Vector3;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::geometry::{FrameCamera, PanoramaCamera};
use skytie_stages::imaging::equirect::PanoramaLevels;
use skytie_stages::imaging::partial::{PartialPyramid, Region};
use skytie_stages::imaging::pyramid::layout::MAX_LEVELS;
use skytie_stages::imaging::pyramid::{footprint_level, PyramidLayout, ScaledWindow, TileSource};
use skytie_stages::nadir::ortho::panorama_bands;
use skytie_stages::nadir::{ortho_project, OrthoGeoref, OrthoImage, OrthoParams};
use std::path::Path;
use std::sync::Arc;
use truth::verdict;

/// Ortho image | aerial nadir crop of the same ground.
pub(super) fn nadir_view(
    ctx: &Context<'_>,
    rec: &Recording,
    points: &[&ControlPoint],
    out: &Path,
) -> Result<(String, ViewCounts), String> {
    let aerial_id = best_aerial(points, "nadir").ok_or("no nadir observation")?;
    let aerial = ctx
        .aerial("nadir", &aerial_id)
        .ok_or_else(|| format!("nadir image {aerial_id} is not in the campaign"))?;
    let (ortho, pano_size) =
        ortho_of_panorama(&ctx.campaign.root.join("mm/panoramas").join(&rec.file), rec)?;
    let g = &ortho.georef;
    let left = crop_scaled(
        &ortho.image,
        0.0,
        0.0,
        g.width_px as f64,
        g.height_px as f64,
        1.0,
    );
    let cam = FrameCamera::from_aerial(aerial);
    cam.project_world(&Vector3::from(g.foot_world))
        .ok_or("the recording is not in front of the aerial camera")?;
    // The aerial side on the same north-up ground grid as the ortho image (each pixel's ground point projected
    // into the aerial image), so both halves share orientation and scale and the lines run side to side.
    let project = |c: f64, r: f64| cam.project_world(&g.pixel_to_world(c, r));
    let aerial_path = ctx.aerial_path("nadir", aerial);
    let right = match ground_window(ctx.images, &aerial_path, aerial, g, &project)? {
        Some(window) => resample_on_ground(window.as_ref(), g.width_px, g.height_px, project),
        None => resample_on_ground(&Black, g.width_px, g.height_px, project),
    };
    let gap = 12;
    let mut img = side_by_side(&left, &right, gap);
    let x_off = (left.width + gap) as f64;
    let pano_cam = PanoramaCamera::from_recording(rec, pano_size.0 as u32, pano_size.1 as u32);
    let ground_z = rec.z - rec.camera_height_m;
    let mut counts = ViewCounts::default();
    for p in points {
        let Some(mo) = p.pano.iter().find(|o| o.image_id == rec.image_id) else {
            continue;
        };
        let Some(ao) = p
            .aerial
            .iter()
            .find(|o| o.kind == "nadir" && o.image_id == aerial_id)
        else {
            continue;
        };
        let Some(ground) =
            truth::ground_intersection(&pano_cam.pixel_ray(mo.u_px, mo.v_px), ground_z)
        else {
            continue;
        };
        let a = g.world_to_pixel(&ground);
        // The aerial observation on the same ground grid: its ray meets the ortho plane.
        let Some(aerial_ground) =
            truth::ground_intersection(&cam.pixel_ray(ao.u_px, ao.v_px), g.foot_world[2])
        else {
            continue;
        };
        let (bu, bv) = g.world_to_pixel(&aerial_ground);
        let bpt = (x_off + bu, bv);
        let x = ctx.true_point(p);
        let colour = counts.add(verdict(x.as_ref(), aerial, ao.u_px, ao.v_px));
        line(&mut img, a, bpt, colour, 1);
        ring(&mut img, a, 7.0, colour);
        ring(&mut img, bpt, 7.0, colour);
    }
    save(out, &img)?;
    Ok((aerial_id, counts))
}

/// The recording's north-up ortho image at the default ortho parameters, from the bands of the panorama at
/// `path` that the projection samples (the panorama is decoded once; only those bands are kept), and the
/// panorama's size in pixels.
pub(super) fn ortho_of_panorama(
    path: &Path,
    rec: &Recording,
) -> Result<(OrthoImage, (usize, usize)), String> {
    let params = OrthoParams::default();
    let bands_of = |layout: &PyramidLayout| {
        panorama_bands(
            rec,
            &params,
            (layout.width, layout.height),
            layout.levels() - 1,
        )
    };
    let pyramid = PartialPyramid::decode(path, |layout| {
        bands_of(layout)
            .into_iter()
            .map(|(level, (v0, v1))| Region::window(level, [0.0, v0, layout.width as f64, v1]))
            .collect()
    })
    .map_err(|e| e.to_string())?;
    let layout = pyramid.layout();
    let panorama = PanoramaLevels::read_bands(&pyramid, &bands_of(layout))
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let size = (layout.width, layout.height);
    drop(pyramid);
    Ok((ortho_project(&panorama, rec, &params), size))
}

/// The window of the aerial image at `path` that the ground grid `g` projects into (`project`: ortho pixel
/// centre → full-resolution aerial pixel), at the pyramid level matching an ortho pixel's footprint in the
/// aerial image; `None` when the grid misses the image.
pub(super) fn ground_window(
    images: &ImageCache,
    path: &Path,
    aerial: &AerialImage,
    g: &OrthoGeoref,
    project: &dyn Fn(f64, f64) -> Option<(f64, f64)>,
) -> Result<Option<Arc<ScaledWindow>>, String> {
    let (cx, cy) = (g.width_px as f64 / 2.0, g.height_px as f64 / 2.0);
    let footprint_px = match (project(cx, cy), project(cx + 1.0, cy)) {
        (Some(a), Some(b)) => (b.0 - a.0).hypot(b.1 - a.1),
        _ => 1.0,
    };
    let level = footprint_level(1.0, footprint_px, MAX_LEVELS);
    let margin = 2.0 * (1u64 << level) as f64;
    let (w, h) = (aerial.width_px as f64, aerial.height_px as f64);
    let mut b: Option<[f64; 4]> = None;
    for r in 0..g.height_px {
        for c in 0..g.width_px {
            let Some((u, v)) = project(c as f64 + 0.5, r as f64 + 0.5) else {
                continue;
            };
            if u < -margin || v < -margin || u > w + margin || v > h + margin {
                continue;
            }
            let x = b.get_or_insert([u, v, u, v]);
            *x = [x[0].min(u), x[1].min(v), x[2].max(u), x[3].max(v)];
        }
    }
    let Some([u0, v0, u1, v1]) = b else {
        return Ok(None);
    };
    images.window(
        path,
        level,
        [u0 - margin, v0 - margin, u1 + margin, v1 + margin],
    )
}

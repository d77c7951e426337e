//! The interactive map's background: the campaign's aerial nadir images resampled onto a north-up grid of the
//! area (a rectified mosaic on a horizontal ground plane at the recordings' median road height). Each grid
//! pixel takes the nadir image that sees it closest to that image's principal point (the most vertical view).
//! A flat ground is enough for a background; the measurements never use it.

use super::image_cache::ImageCache;
use nalgebra::Vector3;
use skytie_stages::campaign::Campaign;
use skytie_stages::geometry::FrameCamera;
use skytie_stages::imaging::image::GrayImage;
use skytie_stages::imaging::io::save_gray;
use std::path::Path;

/// Largest side of a background image, pixels.
const MAX_SIDE_PX: f64 = 2048.0;
/// Finest background resolution, metres per pixel.
const MIN_GSD_M: f64 = 0.05;

/// A written background: its world bounds (x0, y0, x1, y1), metres.
pub struct Background {
    pub bounds_world: [f64; 4],
}

/// One nadir image that may cover the area: camera, footprint box on the ground plane, image file.
struct Candidate {
    camera: FrameCamera,
    footprint: [f64; 4],
    principal: (f64, f64),
    path: std::path::PathBuf,
    size: (f64, f64),
}

fn footprint(camera: &FrameCamera, w: f64, h: f64, ground_z: f64) -> Option<[f64; 4]> {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for (u, v) in [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)] {
        let ray = camera.pixel_ray(u, v);
        let dz = ray.dir_world[2];
        if dz >= -1e-9 {
            return None;
        }
        let t = (ground_z - ray.origin_world[2]) / dz;
        let p = ray.origin_world + ray.dir_world * t;
        b = [
            b[0].min(p[0]),
            b[1].min(p[1]),
            b[2].max(p[0]),
            b[3].max(p[1]),
        ];
    }
    Some(b)
}

/// Writes the background of the area `bounds_world` (x0, y0, x1, y1) to `out` (PNG). Ok(None) when no nadir
/// image covers the area.
pub fn nadir_background(
    campaign: &Campaign,
    images: &ImageCache,
    bounds_world: [f64; 4],
    ground_z: f64,
    out: &Path,
) -> Result<Option<Background>, String> {
    let [x0, y0, x1, y1] = bounds_world;
    let candidates: Vec<Candidate> = campaign
        .nadir
        .iter()
        .filter_map(|a| {
            let camera = FrameCamera::from_aerial(a);
            let (w, h) = (a.width_px as f64, a.height_px as f64);
            let f = footprint(&camera, w, h, ground_z)?;
            let overlaps = f[0] < x1 && f[2] > x0 && f[1] < y1 && f[3] > y0;
            overlaps.then(|| Candidate {
                camera,
                footprint: f,
                principal: (a.cx_px, a.cy_px),
                path: campaign.root.join("aerial/nadir").join(&a.file),
                size: (w, h),
            })
        })
        .collect();
    if candidates.is_empty() {
        return Ok(None);
    }
    let gsd = ((x1 - x0).max(y1 - y0) / MAX_SIDE_PX).max(MIN_GSD_M);
    let (w, h) = (
        ((x1 - x0) / gsd).ceil().max(1.0) as usize,
        ((y1 - y0) / gsd).ceil().max(1.0) as usize,
    );
    let decoded: Vec<std::sync::Arc<GrayImage>> = candidates
        .iter()
        .map(|c| images.gray(&c.path))
        .collect::<Result<_, _>>()?;
    let mut img = GrayImage::filled(w, h, 0.0);
    for row in 0..h {
        let y = y1 - (row as f64 + 0.5) * gsd;
        for col in 0..w {
            let x = x0 + (col as f64 + 0.5) * gsd;
            let mut best: Option<(f64, usize, f64, f64)> = None;
            for (k, c) in candidates.iter().enumerate() {
                let f = &c.footprint;
                if x < f[0] || x > f[2] || y < f[1] || y > f[3] {
                    continue;
                }
                let Some((u, v)) = c.camera.project_world(&Vector3::new(x, y, ground_z)) else {
                    continue;
                };
                if !(u >= 0.0 && v >= 0.0 && u < c.size.0 && v < c.size.1) {
                    continue;
                }
                let d = (u - c.principal.0).hypot(v - c.principal.1);
                if best.is_none_or(|b| d < b.0) {
                    best = Some((d, k, u, v));
                }
            }
            if let Some((_, k, u, v)) = best {
                let value = skytie_stages::imaging::sample::sample_bilinear(
                    &decoded[k],
                    u,
                    v,
                    skytie_stages::imaging::Border::Clamp,
                );
                img.set(col, row, value);
            }
        }
    }
    save_gray(out, &img).map_err(|e| e.to_string())?;
    Ok(Some(Background {
        bounds_world: [x0, y1 - h as f64 * gsd, x0 + w as f64 * gsd, y1],
    }))
}

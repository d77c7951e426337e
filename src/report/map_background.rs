//! The interactive map's background: the campaign's aerial nadir images resampled onto a north-up grid of the
//! area (a rectified mosaic on a horizontal ground plane at the recordings' median road height). Each grid
//! pixel takes the nadir image that sees it closest to that image's principal point (the most vertical view).
//! A flat ground is enough for a background; the measurements never use it. Each image is read at the
//! pyramid level matching the background's resolution, over the part of it the background shows, one image
//! at a time.

use super::image_cache::ImageCache;
use nalgebra::Vector3;
use skytie_stages::campaign::Campaign;
use skytie_stages::geometry::FrameCamera;
use skytie_stages::imaging::image::GrayImage;
use skytie_stages::imaging::io::save_gray;
use skytie_stages::imaging::pyramid::footprint_level;
use skytie_stages::imaging::pyramid::layout::MAX_LEVELS;
use skytie_stages::imaging::sample::sample_bilinear;
use skytie_stages::imaging::Border;
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

/// No image for a background pixel.
const NONE: u32 = u32::MAX;

/// For every background pixel (`w × h`, ground point `ground(col, row)`), the candidate that sees it closest
/// to its principal point ([`NONE`] when none sees it), and for every candidate the box of full-resolution
/// image positions it is sampled at (None when it fills no pixel).
#[allow(clippy::type_complexity)]
fn choose_images(
    candidates: &[Candidate],
    w: usize,
    h: usize,
    ground: &dyn Fn(usize, usize) -> Vector3<f64>,
) -> (Vec<u32>, Vec<Option<[f64; 4]>>) {
    let mut choice = vec![NONE; w * h];
    let mut boxes: Vec<Option<[f64; 4]>> = vec![None; candidates.len()];
    for row in 0..h {
        for col in 0..w {
            let p = ground(col, row);
            let mut best: Option<(f64, usize, f64, f64)> = None;
            for (k, c) in candidates.iter().enumerate() {
                let f = &c.footprint;
                if p.x < f[0] || p.x > f[2] || p.y < f[1] || p.y > f[3] {
                    continue;
                }
                let Some((u, v)) = c.camera.project_world(&p) else {
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
                choice[row * w + col] = k as u32;
                let b = boxes[k].get_or_insert([u, v, u, v]);
                *b = [b[0].min(u), b[1].min(v), b[2].max(u), b[3].max(v)];
            }
        }
    }
    (choice, boxes)
}

/// Ground sampling distance of a candidate at its principal point on the plane `ground_z`, metres per pixel.
fn native_gsd_m(c: &Candidate, ground_z: f64) -> Option<f64> {
    let on_ground = |u: f64, v: f64| {
        let ray = c.camera.pixel_ray(u, v);
        let dz = ray.dir_world[2];
        (dz < -1e-9)
            .then(|| ray.origin_world + ray.dir_world * ((ground_z - ray.origin_world[2]) / dz))
    };
    let (u, v) = c.principal;
    let a = on_ground(u, v)?;
    let b = on_ground(u + 1.0, v)?;
    let d = (b - a).norm();
    (d.is_finite() && d > 0.0).then_some(d)
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
    let ground = |col: usize, row: usize| {
        Vector3::new(
            x0 + (col as f64 + 0.5) * gsd,
            y1 - (row as f64 + 0.5) * gsd,
            ground_z,
        )
    };
    let (choice, boxes) = choose_images(&candidates, w, h, &ground);
    let mut img = GrayImage::filled(w, h, 0.0);
    // One image at a time, read at the level matching the background's resolution over the part it fills.
    for (k, c) in candidates.iter().enumerate() {
        let Some([u0, v0, u1, v1]) = boxes[k] else {
            continue;
        };
        let level =
            native_gsd_m(c, ground_z).map_or(0, |native| footprint_level(native, gsd, MAX_LEVELS));
        let margin = 2.0 * (1u64 << level) as f64;
        let Some(window) = images.window(
            &c.path,
            level,
            [u0 - margin, v0 - margin, u1 + margin, v1 + margin],
        )?
        else {
            continue;
        };
        for row in 0..h {
            for col in 0..w {
                if choice[row * w + col] != k as u32 {
                    continue;
                }
                let Some((u, v)) = c.camera.project_world(&ground(col, row)) else {
                    continue;
                };
                let (wu, wv) = window.from_full(u, v);
                let value = sample_bilinear(&window.image, wu, wv, Border::Clamp);
                img.set(col, row, value);
            }
        }
    }
    save_gray(out, &img).map_err(|e| e.to_string())?;
    Ok(Some(Background {
        bounds_world: [x0, y1 - h as f64 * gsd, x0 + w as f64 * gsd, y1],
    }))
}

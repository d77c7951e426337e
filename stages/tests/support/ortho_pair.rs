//! A synthetic MM-ortho / aerial image pair for the nadir registration tests: an MM ortho image (10 cm,
//! rotated 30°) of a ground pattern given in world metres, a 400 × 360 px aerial image that sees the same
//! pattern through a known similarity (ortho px → aerial px), and the tie points of a recording's window.

use nalgebra::{Vector2, Vector3};
use skytie_stages::correspondence::{MmTiePoint, PanoObservation};
use skytie_stages::geometry::Similarity2;
use skytie_stages::imaging::GrayImage;
use skytie_stages::nadir::{InitialTransform, MmWindowMatch, OrthoGeoref, OrthoParams};

/// World position of the ortho image's footprint centre (x, y, ground height), metres.
pub const FOOT_WORLD: [f64; 3] = [92_000.0, 437_000.0, 1.2];
/// Size of the aerial image, pixels (width, height).
pub const AERIAL_SIZE_PX: (usize, usize) = (400, 360);

/// The georeference of a 10 cm ortho image rotated by 30° around `foot_world`.
pub fn ortho_georef(foot_world: [f64; 3]) -> OrthoGeoref {
    let params = OrthoParams {
        gsd_m: 0.10,
        rotation_deg: 30.0,
        ..OrthoParams::default()
    };
    OrthoGeoref::new(foot_world, &params)
}

/// The ortho image of `ground` (grey value at world x, y in metres), sampled at pixel centres.
pub fn render_ortho(georef: &OrthoGeoref, ground: impl Fn(f64, f64) -> f64) -> GrayImage {
    let (w, h) = (georef.width_px, georef.height_px);
    let mut image = GrayImage::filled(w, h, 0.0);
    for r in 0..h {
        for c in 0..w {
            let p = georef.pixel_to_world(c as f64 + 0.5, r as f64 + 0.5);
            image.set(c, r, ground(p.x, p.y) as f32);
        }
    }
    image
}

/// The similarity from ortho pixels to aerial pixels that the pair's aerial image is rendered with.
pub fn true_similarity() -> Similarity2 {
    Similarity2::new(0.97, 0.21, 143.37, 61.81)
}

/// The aerial image seen through `truth`: `value(col, row, x_m, y_m)` gives the grey value of the aerial
/// pixel (col, row) whose centre maps to world (x_m, y_m) on the ground.
pub fn render_aerial(
    georef: &OrthoGeoref,
    truth: &Similarity2,
    mut value: impl FnMut(usize, usize, f64, f64) -> f64,
) -> GrayImage {
    let inv = truth.inverse();
    let (aw, ah) = AERIAL_SIZE_PX;
    let mut aerial = GrayImage::filled(aw, ah, 0.0);
    for r in 0..ah {
        for c in 0..aw {
            let o = inv.apply(&Vector2::new(c as f64 + 0.5, r as f64 + 0.5));
            let p = georef.pixel_to_world(o.x, o.y);
            aerial.set(c, r, value(c, r, p.x, p.y) as f32);
        }
    }
    aerial
}

/// Where `truth` puts the ground point `g_world` in the aerial image, pixels.
pub fn true_aerial_px(
    georef: &OrthoGeoref,
    truth: &Similarity2,
    g_world: [f64; 3],
) -> Vector2<f64> {
    let (u, v) = georef.world_to_pixel(&Vector3::new(g_world[0], g_world[1], g_world[2]));
    truth.apply(&Vector2::new(u, v))
}

/// An MM tie point at `point_world` seen in the panoramas "rec" and "rec2" (σ 1 cm per axis).
pub fn tie_point(id: &str, point_world: [f64; 3]) -> MmTiePoint {
    MmTiePoint {
        id: id.into(),
        observations: vec![
            PanoObservation {
                image_id: "rec".into(),
                u_px: 1.0,
                v_px: 2.0,
            },
            PanoObservation {
                image_id: "rec2".into(),
                u_px: 3.0,
                v_px: 4.0,
            },
        ],
        point_world,
        covariance_m2: [[1e-4, 0.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4]],
        max_angle_deg: 10.0,
    }
}

/// The window of recording "rec" holding a tie point `rec#<i>` at each of `ground_world`.
pub fn window_at(ground_world: Vec<[f64; 3]>) -> MmWindowMatch {
    let tie_points: Vec<MmTiePoint> = ground_world
        .iter()
        .enumerate()
        .map(|(i, &p)| tie_point(&format!("rec#{i}"), p))
        .collect();
    MmWindowMatch {
        recording_id: "rec".into(),
        pairs: vec![],
        corners_detected: tie_points.len(),
        tie_points,
        ground_world,
        neighbour_ground_world: Vec::new(),
    }
}

/// The index `i` of a tie point id `rec#<i>`.
pub fn tie_index(tie_point_id: &str) -> usize {
    tie_point_id.split('#').nth(1).unwrap().parse().unwrap()
}

/// The initial transform "rec" → "aer" given by the similarity `t`.
pub fn initial_transform(t: Similarity2) -> InitialTransform {
    InitialTransform {
        recording_id: "rec".into(),
        aerial_id: "aer".into(),
        ortho_to_aerial: t,
        matches: 0,
        inliers: 0,
        centre_offset_m: 0.0,
        centre_offset_world_m: [0.0, 0.0],
        reused_from: None,
    }
}

//! Aerial flight plans: nadir strips with forward/side overlap at high altitude (thesis 3.5.1.1, 5.5: ≈ 4470 m,
//! ≈ 10 cm GSD, 60 % / 40 % overlap, glancing intersections) and pentacam-style obliques in four directions
//! tilted 45° at ≈ 450 m (thesis 4.5), both covering a route. Poses are exact (never perturbed).

use super::preset::{NadirPlan, ObliquePlan};
use super::rng::{hash_str, Stream};
use crate::campaign::AerialImage;
use crate::geometry::{bounding_box, matrix_to_opk, rot_x, rot_z};

/// Margin around the route that the nadir block covers in addition, m.
const NADIR_MARGIN_M: f64 = 15.0;

/// Nadir strips over `route_points` (world XY), ground at `ground_z_m`. Strips run along the longer side of the
/// route's bounding box (serpentine), the image top pointing in the flight direction (κ = −flight azimuth);
/// at least two strips, so route points typically lie in the side overlap and are seen by 4+ images; the
/// exposures extend half a base beyond the covered extent so every route point is in ≥ 2 images of a strip.
pub fn plan_nadir(
    route_points: &[[f64; 2]],
    ground_z_m: f64,
    plan: &NadirPlan,
    seed: u64,
    id_prefix: &str,
) -> Vec<AerialImage> {
    if route_points.is_empty() {
        return Vec::new();
    }
    let (lo, hi) = bounding_box(route_points);
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let extent = [
        hi[0] - lo[0] + 2.0 * NADIR_MARGIN_M,
        hi[1] - lo[1] + 2.0 * NADIR_MARGIN_M,
    ];
    // Flight along x (east) when the block is wider than tall, else along y (north).
    let along_axis = if extent[0] >= extent[1] { 0 } else { 1 };
    let across_axis = 1 - along_axis;
    let footprint_across_m = f64::from(plan.width_px) * plan.gsd_m;
    let footprint_along_m = f64::from(plan.height_px) * plan.gsd_m;
    let base_m = (1.0 - plan.forward_overlap) * footprint_along_m;
    let spacing_m = (1.0 - plan.side_overlap) * footprint_across_m;
    let n_strips = (((extent[across_axis] - footprint_across_m) / spacing_m)
        .ceil()
        .max(0.0) as usize
        + 1)
    .max(2);
    let n_exposures = (extent[along_axis] / base_m).ceil() as usize + 2;
    let focal_px = plan.altitude_m / plan.gsd_m;
    let [k1, k2, p1, p2] = if plan.corner_distortion_px > 0.0 {
        small_distortion(
            focal_px,
            plan.width_px,
            plan.height_px,
            plan.corner_distortion_px,
        )
    } else {
        [0.0; 4]
    };
    let clamp_deg = 0.9;
    let mut out = Vec::with_capacity(n_strips * n_exposures);
    for s in 0..n_strips {
        let across = centre[across_axis] + (s as f64 - (n_strips - 1) as f64 / 2.0) * spacing_m;
        // Serpentine: odd strips fly back.
        let forward = s % 2 == 0;
        let azimuth_deg = match (along_axis, forward) {
            (0, true) => 90.0,
            (0, false) => 270.0,
            (_, true) => 0.0,
            (_, false) => 180.0,
        };
        for j in 0..n_exposures {
            let k = if forward { j } else { n_exposures - 1 - j };
            let along = centre[along_axis] + (k as f64 - (n_exposures - 1) as f64 / 2.0) * base_m;
            let mut xy = [0.0; 2];
            xy[along_axis] = along;
            xy[across_axis] = across;
            let image_id = format!("{id_prefix}_s{s}_{j:02}");
            let mut r = Stream::new(&[seed, hash_str("nadir-attitude"), hash_str(&image_id)]);
            let q = |v: f64| (v * 1e4).round() / 1e4;
            let omega_deg = q((plan.attitude_sigma_deg * r.normal()).clamp(-clamp_deg, clamp_deg));
            let phi_deg = q((plan.attitude_sigma_deg * r.normal()).clamp(-clamp_deg, clamp_deg));
            let kappa_deg =
                q(-azimuth_deg
                    + (plan.attitude_sigma_deg * r.normal()).clamp(-clamp_deg, clamp_deg));
            out.push(AerialImage {
                k1,
                k2,
                p1,
                p2,
                ..AerialImage::ideal(
                    &image_id,
                    [xy[0], xy[1], ground_z_m + plan.altitude_m],
                    [omega_deg, phi_deg, kappa_deg],
                    focal_px,
                    [plan.width_px, plan.height_px],
                )
            });
        }
    }
    out
}

/// Brown coefficients giving ≈ `corner_px` radial displacement at the image corner (k1 term), a smaller
/// opposite k2 term and tangential terms of a fraction of a pixel, for a camera of `focal_px` and size W × H.
pub fn small_distortion(focal_px: f64, width_px: u32, height_px: u32, corner_px: f64) -> [f64; 4] {
    let r_c = (f64::from(width_px) / 2.0).hypot(f64::from(height_px) / 2.0) / focal_px;
    let k1 = corner_px / (focal_px * r_c.powi(3));
    let k2 = -0.25 * corner_px / (focal_px * r_c.powi(5));
    let p1 = 0.15 * corner_px / (focal_px * r_c * r_c);
    let p2 = -0.10 * corner_px / (focal_px * r_c * r_c);
    [k1, k2, p1, p2]
}

/// Points every `step_m` along a polyline (first and last included).
fn points_along(poly: &[[f64; 2]], step_m: f64) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    if poly.is_empty() {
        return out;
    }
    out.push(poly[0]);
    let mut carry = 0.0;
    for w in poly.windows(2) {
        let len = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        let mut s = step_m - carry;
        while s <= len {
            let t = s / len;
            out.push([
                w[0][0] + t * (w[1][0] - w[0][0]),
                w[0][1] + t * (w[1][1] - w[0][1]),
            ]);
            s += step_m;
        }
        carry = (carry + len) % step_m;
    }
    let last = *poly.last().unwrap();
    let end = *out.last().unwrap();
    if (last[0] - end[0]).hypot(last[1] - end[1]) > 0.25 * step_m {
        out.push(last);
    }
    out
}

/// The polyline lengthened by `by_m` at both ends along its end segments (so the route's ends are not at the
/// edge of the first and last footprints).
fn extend_ends(poly: &[[f64; 2]], by_m: f64) -> Vec<[f64; 2]> {
    let mut out = poly.to_vec();
    let n = poly.len();
    if n < 2 {
        return out;
    }
    let push_out = |a: [f64; 2], b: [f64; 2]| {
        let len = (a[0] - b[0]).hypot(a[1] - b[1]).max(1e-9);
        [
            a[0] + (a[0] - b[0]) / len * by_m,
            a[1] + (a[1] - b[1]) / len * by_m,
        ]
    };
    out.insert(0, push_out(poly[0], poly[1]));
    out.push(push_out(poly[n - 1], poly[n - 2]));
    out
}

/// The four oblique viewing azimuths (camera looks towards N, E, S, W) with their id letters.
pub const OBLIQUE_DIRECTIONS: [(f64, char); 4] =
    [(0.0, 'n'), (90.0, 'e'), (180.0, 's'), (270.0, 'w')];

/// Pentacam-style obliques: for each of the four viewing directions, exposures whose image centres fall on
/// points along the route (extended by one step at both ends) spaced so that consecutive footprints overlap by
/// `plan.overlap_along_route` (every route point, hence every façade along it, in ≥ 2 obliques per direction). Camera at
/// `ground_z_m + altitude`, tilted `tilt_deg` from the nadir, image top away from the camera; small Brown
/// distortion and a slightly off-centre principal point.
pub fn plan_oblique(
    route_polyline: &[[f64; 2]],
    ground_z_m: f64,
    plan: &ObliquePlan,
    id_prefix: &str,
) -> Vec<AerialImage> {
    let tilt = plan.tilt_deg.to_radians();
    let slant_m = plan.altitude_m / tilt.cos();
    let focal_px = slant_m / plan.gsd_center_m;
    let across_m = f64::from(plan.width_px) * plan.gsd_center_m;
    let depth_m = f64::from(plan.height_px) * plan.gsd_center_m / tilt.cos();
    let step_m = (1.0 - plan.overlap_along_route) * across_m.min(depth_m);
    let targets = points_along(&extend_ends(route_polyline, step_m), step_m);
    let [k1, k2, p1, p2] = small_distortion(
        focal_px,
        plan.width_px,
        plan.height_px,
        plan.corner_distortion_px,
    );
    let horizontal_m = plan.altitude_m * tilt.tan();
    let mut out = Vec::with_capacity(targets.len() * 4);
    for (azimuth_deg, letter) in OBLIQUE_DIRECTIONS {
        let a = azimuth_deg.to_radians();
        // Tilt north-looking about X, then turn clockwise (seen from above) to the azimuth.
        let r = rot_z(-a) * rot_x(tilt);
        let (omega_deg, phi_deg, kappa_deg) = matrix_to_opk(&r);
        for (j, t) in targets.iter().enumerate() {
            let image_id = format!("{id_prefix}_{letter}_{j:02}");
            out.push(AerialImage {
                k1,
                k2,
                p1,
                p2,
                cx_px: f64::from(plan.width_px) / 2.0 + 3.25,
                cy_px: f64::from(plan.height_px) / 2.0 - 2.75,
                ..AerialImage::ideal(
                    &image_id,
                    [
                        t[0] - horizontal_m * a.sin(),
                        t[1] - horizontal_m * a.cos(),
                        ground_z_m + plan.altitude_m,
                    ],
                    [omega_deg, phi_deg, kappa_deg],
                    focal_px,
                    [plan.width_px, plan.height_px],
                )
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{BrownDistortion, FrameCamera};
    use nalgebra::Vector3;

    fn nadir_plan() -> NadirPlan {
        NadirPlan {
            altitude_m: 4470.0,
            gsd_m: 0.1,
            width_px: 2000,
            height_px: 1500,
            forward_overlap: 0.6,
            side_overlap: 0.4,
            attitude_sigma_deg: 0.3,
            corner_distortion_px: 0.0,
        }
    }

    #[test]
    fn every_route_point_is_seen_by_at_least_two_nadirs_with_the_thesis_geometry() {
        let route: Vec<[f64; 2]> = (0..40)
            .map(|i| [92_000.0 + 5.0 * i as f64, 437_000.0 + 0.5 * i as f64])
            .collect();
        let imgs = plan_nadir(&route, 1.0, &nadir_plan(), 7, "nadir");
        let mut counts = Vec::new();
        for p in &route {
            let pw = Vector3::new(p[0], p[1], 1.0);
            let n = imgs
                .iter()
                .filter(|a| {
                    let c = FrameCamera::from_aerial(a);
                    c.project_world(&pw).is_some_and(|(u, v)| c.contains(u, v))
                })
                .count();
            counts.push(n);
        }
        assert!(counts.iter().all(|&n| n >= 2), "{counts:?}");
        let four_plus = counts.iter().filter(|&&n| n >= 4).count();
        assert!(
            four_plus * 2 > counts.len(),
            "most points in 4+ images: {counts:?}"
        );
        for a in &imgs {
            assert!(a.omega_deg.abs() < 1.0 && a.phi_deg.abs() < 1.0);
            assert!(
                ((a.kappa_deg + 90.0).abs() < 1.0) || ((a.kappa_deg + 270.0).abs() < 1.0),
                "κ {}",
                a.kappa_deg
            );
            assert!((a.z - 4471.0).abs() < 1e-9 && (a.focal_px - 44_700.0).abs() < 1e-6);
        }
    }

    #[test]
    fn obliques_look_at_the_route_from_four_sides_at_45_degrees() {
        let route = [[0.0, 0.0], [100.0, 0.0]];
        let plan = ObliquePlan {
            altitude_m: 450.0,
            tilt_deg: 45.0,
            gsd_center_m: 0.1,
            width_px: 1000,
            height_px: 750,
            overlap_along_route: 0.5,
            corner_distortion_px: 2.0,
        };
        let imgs = plan_oblique(&route, 0.0, &plan, "obl");
        assert_eq!(imgs.len() % 4, 0);
        for a in &imgs {
            let c = FrameCamera::from_aerial(a);
            let d = c.viewing_direction_world();
            assert!((d.z + 45f64.to_radians().cos()).abs() < 1e-9, "45° down");
            let az = d.x.atan2(d.y).to_degrees().rem_euclid(360.0);
            let want = match a.image_id.as_bytes()[4] {
                b'n' => 0.0,
                b'e' => 90.0,
                b's' => 180.0,
                _ => 270.0,
            };
            assert!(
                (az - want).abs() < 1e-6 || (az - want - 360.0).abs() < 1e-6,
                "{} looks at {az}",
                a.image_id
            );
            // The far side of the footprint is at the image top.
            let up = c.rotation_cam_to_world * Vector3::new(0.0, 1.0, 0.0);
            assert!(up.x * d.x + up.y * d.y > 0.0);
            // GSD at the centre 0.10 m; corner distortion of a few pixels at most.
            let centre_ground = c.center_world + d * (450.0 / 45f64.to_radians().cos());
            assert!((c.gsd_at(&centre_ground) - 0.1).abs() < 1e-9);
            let dist = BrownDistortion {
                k1: a.k1,
                k2: a.k2,
                p1: a.p1,
                p2: a.p2,
                ..BrownDistortion::NONE
            };
            let (x, y) = (500.0 / a.focal_px, 375.0 / a.focal_px);
            let (xd, yd) = dist.distort(x, y);
            let shift_px = ((xd - x).hypot(yd - y)) * a.focal_px;
            assert!(
                shift_px > 0.5 && shift_px < 4.0,
                "corner distortion {shift_px} px"
            );
        }
        // Each route point is within the footprint of ≥ 2 obliques per direction.
        for x in [0.0, 33.0, 50.0, 77.0, 100.0] {
            let p = Vector3::new(x, 0.0, 0.0);
            for (_, letter) in OBLIQUE_DIRECTIONS {
                let n = imgs
                    .iter()
                    .filter(|a| a.image_id.as_bytes()[4] == letter as u8)
                    .filter(|a| {
                        let c = FrameCamera::from_aerial(a);
                        c.project_world(&p).is_some_and(|(u, v)| c.contains(u, v))
                    })
                    .count();
                assert!(n >= 2, "x = {x}, direction {letter}: {n}");
            }
        }
    }
}

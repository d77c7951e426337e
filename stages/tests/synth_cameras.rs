//! Known-answer test across renderer, geometry core and the documented conventions (campaign-format.md):
//! emissive marker spheres at known world points are rendered into panoramas (levelled and with
//! yaw/pitch/roll) and into aerial nadir and oblique (distorted) frames; each marker's pixel centroid, found
//! by image analysis alone, must lie within 0.5 px of `project_world` with the true pose. Independent checks
//! pin the conventions themselves (north at u = W/2, east at u = 3W/4, yaw/pitch signs, nadir image top north).
//!
//! Image analysis: each image is rendered twice with the markers in two colours; all else being identical,
//! the difference is (coverage α) × (colour difference), so α per pixel is exact up to supersampling and the
//! centroid Σα·(col + ½, row + ½) / Σα is the marker's image centre (pixel centres at +0.5).

use nalgebra::Vector3;
use skytie_stages::geometry::{BrownDistortion, FrameCamera, PanoramaCamera};
use skytie_stages::imaging::RgbImage;
use skytie_stages::synth::aerial_plan::small_distortion;
use skytie_stages::synth::render::{render_frame, render_panorama};
use skytie_stages::synth::scene::{Epoch, Marker, Scene};

const ORIGIN: [f64; 2] = [92_000.0, 437_000.0];
const GROUND_Z: f64 = 1.3;
const RED: [f32; 3] = [1.0, 0.1, 0.1];
const GREEN: [f32; 3] = [0.1, 1.0, 0.1];

fn scene_with(centres: &[Vector3<f64>], radius_m: f64, rgb: [f32; 3]) -> Scene {
    let markers = centres
        .iter()
        .map(|c| Marker {
            center_world: *c,
            radius_m,
            rgb,
        })
        .collect();
    Scene::markers_only(ORIGIN, GROUND_Z, markers)
}

/// Centroid (continuous pixels) of marker coverage within `radius_px` of `around`, from two renderings that
/// differ only in the marker colour. `wrap` handles the panorama's horizontal wrap-around.
fn centroid(
    a: &RgbImage,
    b: &RgbImage,
    around: (f64, f64),
    radius_px: f64,
    wrap: bool,
) -> Option<(f64, f64)> {
    let diff = [RED[0] - GREEN[0], RED[1] - GREEN[1], RED[2] - GREEN[2]];
    let norm2: f32 = diff.iter().map(|d| d * d).sum();
    let (w, h) = (a.width as i64, a.height as i64);
    let r = radius_px.ceil() as i64;
    let (cu, cv) = (around.0.floor() as i64, around.1.floor() as i64);
    let (mut sw, mut su, mut sv) = (0.0f64, 0.0f64, 0.0f64);
    for row in (cv - r).max(0)..=(cv + r).min(h - 1) {
        for dc in -r..=r {
            let col_unwrapped = cu + dc;
            let col = if wrap {
                col_unwrapped.rem_euclid(w)
            } else {
                col_unwrapped
            };
            if !(0..w).contains(&col) {
                continue;
            }
            let (pa, pb) = (
                a.get(col as usize, row as usize),
                b.get(col as usize, row as usize),
            );
            let alpha =
                ((pa[0] - pb[0]) * diff[0] + (pa[1] - pb[1]) * diff[1] + (pa[2] - pb[2]) * diff[2])
                    / norm2;
            if alpha.abs() < 1e-4 {
                continue;
            }
            let alpha = f64::from(alpha);
            sw += alpha;
            su += alpha * (col_unwrapped as f64 + 0.5);
            sv += alpha * (row as f64 + 0.5);
        }
    }
    (sw > 1.0).then(|| (su / sw, sv / sw))
}

/// [`worst_error_px`] of an aerial frame camera: 0.6 m markers rendered at 3 × 3 samples per pixel, found
/// within 10 px of their projections.
fn frame_marker_errors_px(cam: &FrameCamera, markers: &[Vector3<f64>]) -> (f64, Vec<(f64, f64)>) {
    worst_error_px(
        |s| render_frame(s, cam, Epoch::Aerial, 3),
        |p| cam.project_world(p),
        markers,
        0.6,
        10.0,
        false,
    )
}

/// Largest distance between rendered centroid and `project` over all markers.
fn worst_error_px<P>(
    render: impl Fn(&Scene) -> RgbImage,
    project: P,
    centres: &[Vector3<f64>],
    radius_m: f64,
    window_px: f64,
    wrap: bool,
) -> (f64, Vec<(f64, f64)>)
where
    P: Fn(&Vector3<f64>) -> Option<(f64, f64)>,
{
    let a = render(&scene_with(centres, radius_m, RED));
    let b = render(&scene_with(centres, radius_m, GREEN));
    let mut worst: f64 = 0.0;
    let mut found = Vec::new();
    for c in centres {
        let want = project(c).expect("marker projects into the image");
        let got = centroid(&a, &b, want, window_px, wrap)
            .unwrap_or_else(|| panic!("marker {c:?} not seen near {want:?}"));
        let mut du = got.0 - want.0;
        if wrap {
            let w = a.width as f64;
            du = (du + w / 2.0).rem_euclid(w) - w / 2.0;
        }
        worst = worst.max(du.hypot(got.1 - want.1));
        found.push(got);
    }
    (worst, found)
}

const PANO_W: u32 = 720;
const PANO_H: u32 = 360;

fn pano_centre() -> Vector3<f64> {
    Vector3::new(ORIGIN[0] + 3.0, ORIGIN[1] - 2.0, GROUND_Z + 2.2)
}

/// Markers around the panorama: various azimuths (none due south, the image seam) and elevations.
fn pano_markers() -> Vec<Vector3<f64>> {
    let c = pano_centre();
    [
        (0.0, 8.0, 0.0),
        (90.0, 7.0, -1.2),
        (45.0, 9.0, 1.5),
        (300.0, 6.0, -2.0),
        (230.0, 10.0, 2.5),
        (135.0, 8.0, -0.5),
    ]
    .iter()
    .map(|&(az_deg, dist_m, dz_m)| {
        let a = f64::to_radians(az_deg);
        Vector3::new(c.x + dist_m * a.sin(), c.y + dist_m * a.cos(), c.z + dz_m)
    })
    .collect()
}

fn check_panorama(yaw_deg: f64, pitch_deg: f64, roll_deg: f64) -> Vec<(f64, f64)> {
    let cam = PanoramaCamera::new(PANO_W, PANO_H, pano_centre(), yaw_deg, pitch_deg, roll_deg);
    let (worst, found) = worst_error_px(
        |s| render_panorama(s, &cam, Epoch::MobileMapping, 3),
        |p| cam.project_world(p),
        &pano_markers(),
        0.25,
        12.0,
        true,
    );
    eprintln!("panorama yaw {yaw_deg} pitch {pitch_deg} roll {roll_deg}: worst centroid error {worst:.4} px");
    assert!(
        worst < 0.5,
        "panorama yaw/pitch/roll ({yaw_deg}, {pitch_deg}, {roll_deg}): {worst} px"
    );
    found
}

#[test]
fn panorama_markers_land_where_project_world_says_and_the_conventions_hold() {
    let found = check_panorama(0.0, 0.0, 0.0);
    let (w, h) = (f64::from(PANO_W), f64::from(PANO_H));
    // Independent of the geometry code (campaign-format.md): the marker due north at camera height is at
    // u = W/2, v = H/2; the one due east (1.2 m below the camera, 7 m away) at u = 3W/4,
    // v = H/2 + atan(1.2/7)·H/180°.
    assert!(
        (found[0].0 - w / 2.0).abs() < 0.5 && (found[0].1 - h / 2.0).abs() < 0.5,
        "{:?}",
        found[0]
    );
    let v_east = h / 2.0 + (1.2f64 / 7.0).atan().to_degrees() * h / 180.0;
    assert!(
        (found[1].0 - 0.75 * w).abs() < 0.5 && (found[1].1 - v_east).abs() < 0.5,
        "{:?}",
        found[1]
    );

    // Positive yaw turns the panorama clockwise: north now appears yaw degrees left of the centre column.
    let yawed = check_panorama(10.0, 0.0, 0.0);
    assert!(
        (yawed[0].0 - (w / 2.0 - 10.0 / 360.0 * w)).abs() < 0.5,
        "{:?}",
        yawed[0]
    );
    // Positive pitch raises the centre column's direction: the northern horizon moves down by pitch.
    let pitched = check_panorama(0.0, 3.0, 0.0);
    assert!(
        (pitched[0].1 - (h / 2.0 + 3.0 / 180.0 * h)).abs() < 0.5,
        "{:?}",
        pitched[0]
    );
    // Positive roll lowers the direction shown at u = 3W/4 (east): an eastern point moves up in the image.
    let rolled = check_panorama(0.0, 0.0, 4.0);
    assert!(
        rolled[1].1 < found[1].1 - 0.9 * 4.0 / 180.0 * h,
        "{:?} vs {:?}",
        rolled[1],
        found[1]
    );

    check_panorama(-7.5, 1.2, -2.3);
}

/// A regular pattern of ground/raised markers around a ground point, within the frame's footprint.
fn frame_markers(
    centre_ground: Vector3<f64>,
    half_extent_m: [f64; 2],
    dz_m: &[f64],
) -> Vec<Vector3<f64>> {
    let mut out = Vec::new();
    let mut k = 0;
    for i in -2..=2 {
        for j in -2..=2 {
            let dz = dz_m[k % dz_m.len()];
            k += 1;
            out.push(Vector3::new(
                centre_ground.x + 0.45 * half_extent_m[0] * f64::from(i),
                centre_ground.y + 0.45 * half_extent_m[1] * f64::from(j),
                centre_ground.z + dz,
            ));
        }
    }
    out
}

#[test]
fn nadir_markers_land_where_project_world_says_and_the_image_top_is_north() {
    // 4470 m above ground, focal 44 700 px (GSD 0.10 m), small ω/φ, κ along an eastward strip.
    let (w, h) = (400u32, 300u32);
    let c = Vector3::new(ORIGIN[0] + 10.0, ORIGIN[1] + 5.0, GROUND_Z + 4470.0);
    for (omega, phi, kappa) in [(0.0, 0.0, 0.0), (0.4, -0.7, -90.0), (-0.6, 0.3, 183.0)] {
        let cam = FrameCamera::from_opk(
            c,
            omega,
            phi,
            kappa,
            44_700.0,
            200.0,
            150.0,
            w,
            h,
            BrownDistortion::default(),
        );
        // A 0.7° tilt moves the footprint by 4470 m · tan 0.7° ≈ 55 m: centre the markers where the optical
        // axis meets the ground.
        let d = cam.viewing_direction_world();
        let ground = c + d * ((GROUND_Z - c.z) / d.z);
        let markers = frame_markers(ground, [14.0, 14.0], &[0.8, 0.8, 6.0, 12.0]);
        let (worst, found) = frame_marker_errors_px(&cam, &markers);
        eprintln!("nadir ω {omega} φ {phi} κ {kappa}: worst centroid error {worst:.4} px");
        assert!(worst < 0.5, "nadir ({omega}, {phi}, {kappa}): {worst} px");
        if kappa == 0.0 {
            // ω = φ = κ = 0: looks straight down, image top north, u grows east. Marker grid index 12 is
            // under the camera; index 13 (+y, north) is 0.45·14 m = 6.3 m north ⇒ ≈ 63 px above (exactly:
            // focal · 6.3 m / depth of the marker).
            let centre_marker = found[12];
            assert!((centre_marker.0 - 200.0).abs() < 0.5, "{centre_marker:?}");
            let north = found[13];
            let dz = markers[13].z - c.z;
            let want_v = 150.0 - 44_700.0 * 6.3 / -dz;
            assert!(
                (north.1 - want_v).abs() < 0.5 && (north.0 - 200.0).abs() < 0.5,
                "{north:?} vs v {want_v}"
            );
            let east = found[17]; // i = +1, j = 0: 6.3 m east
            assert!(
                east.0 > 200.0 + 55.0 && (east.1 - 150.0).abs() < 0.5,
                "{east:?}"
            );
        }
    }
}

#[test]
fn distorted_oblique_markers_land_where_project_world_says() {
    // Pentacam-style oblique: 450 m above ground, tilted 45°, looking east, GSD 0.10 m at the centre; a
    // deliberately visible distortion (4 px at the corners) and an off-centre principal point.
    let (w, h) = (400u32, 300u32);
    let tilt = 45f64.to_radians();
    let slant = 450.0 / tilt.cos();
    let focal = slant / 0.10;
    let target = Vector3::new(ORIGIN[0] + 20.0, ORIGIN[1] - 10.0, GROUND_Z);
    let c = Vector3::new(target.x - 450.0, target.y, GROUND_Z + 450.0);
    let [k1, k2, p1, p2] = small_distortion(focal, w, h, 4.0);
    let dist = BrownDistortion {
        k1,
        k2,
        p1,
        p2,
        ..BrownDistortion::NONE
    };
    let r =
        skytie_stages::geometry::rot_z(-90f64.to_radians()) * skytie_stages::geometry::rot_x(tilt);
    let (omega, phi, kappa) = skytie_stages::geometry::matrix_to_opk(&r);
    let cam = FrameCamera::from_opk(c, omega, phi, kappa, focal, 203.25, 147.25, w, h, dist);
    let no_dist = FrameCamera::from_opk(
        c,
        omega,
        phi,
        kappa,
        focal,
        203.25,
        147.25,
        w,
        h,
        BrownDistortion::default(),
    );
    // Footprint ≈ 40 m across (north-south) and ≈ 42 m deep (east-west) around the target.
    let markers = frame_markers(target, [19.0, 17.0], &[0.5, 3.0]);
    let (worst, found) = frame_marker_errors_px(&cam, &markers);
    eprintln!("oblique (distorted): worst centroid error {worst:.4} px");
    assert!(worst < 0.5, "oblique: {worst} px");
    // The distortion is really exercised: near the corners the undistorted projection is off by > 1 px.
    let max_shift = markers
        .iter()
        .zip(&found)
        .map(|(m, f)| {
            let (u, v) = no_dist.project_world(m).unwrap();
            (u - f.0).hypot(v - f.1)
        })
        .fold(0.0, f64::max);
    assert!(max_shift > 1.0, "distortion effect only {max_shift} px");
    // Looking east: a marker farther east appears higher in the image (the far side is at the top).
    assert!(
        found[22].1 < found[12].1 - 50.0,
        "{:?} {:?}",
        found[22],
        found[12]
    );
}

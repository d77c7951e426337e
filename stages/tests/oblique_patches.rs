//! Image-to-plane patches and patch registration (thesis 4.4.5–4.4.7) on an analytic scene: a textured
//! vertical façade rendered into an equirectangular panorama and into an oblique frame image with known poses.
//! With the true panorama pose the patches must register with |shift| ≤ 1 patch pixel; with the panorama
//! (and its object points) moved 0.5 m along the façade the recovered shift must be ≈ −0.5 m along `axis_u`.

use nalgebra::Vector3;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::correspondence::{MmTiePoint, PanoObservation};
use skytie_stages::geometry::frame::FrameCamera;
use skytie_stages::geometry::panorama::PanoramaCamera;
use skytie_stages::geometry::Ray;
use skytie_stages::imaging::equirect::PanoramaLevels;
use skytie_stages::imaging::pyramid::{MemoryPyramid, ScaledWindow};
use skytie_stages::imaging::GrayImage;
use skytie_stages::oblique::patch::{
    fill_from_frame, fill_from_panorama, real_resolution_ratio, PatchGrid,
};
use skytie_stages::oblique::patch_registration::{register_patches, PatchParams, Similarity};
use skytie_stages::oblique::types::{
    FacadePlane, FacadeStats, ObliqueView, SparseCloud, SparseCloudStats, SparsePoint, StreetSide,
    TripletFacades,
};
use skytie_stages::params::Params;
use std::sync::OnceLock;

/// The façade: the plane y = FACADE_Y (normal −y towards the street), x ∈ [X0 − 40, X0 + 40], z ∈ [0, 25].
const X0: f64 = 431_000.0;
const Y0: f64 = 5_702_000.0;
const FACADE_Y: f64 = Y0 + 10.0;

/// Texture on the façade (u = x − X0, v = z), a sum of incommensurate sinusoids (wavelengths 0.5–4 m) scaled
/// to about [20, 235].
fn facade_texture(u: f64, v: f64) -> f64 {
    const WAVES: [(f64, f64, f64, f64); 10] = [
        (0.0, 1.0, 0.53, 0.3),
        (1.0, 0.2, 0.71, 1.1),
        (0.6, -0.8, 1.13, 2.0),
        (-0.3, 0.95, 1.57, 0.7),
        (0.9, 0.45, 2.3, 2.9),
        (0.2, -0.98, 2.9, 1.9),
        (-0.7, -0.7, 3.7, 0.4),
        (1.0, 0.0, 0.87, 1.5),
        (0.4, 0.9, 1.9, 2.4),
        (-0.95, 0.3, 1.3, 0.1),
    ];
    let s: f64 = WAVES
        .iter()
        .map(|&(a, b, wl, ph)| {
            (std::f64::consts::TAU * (a * u + b * v) / (wl * (a * a + b * b).sqrt()) + ph).sin()
        })
        .sum();
    128.0 + 30.0 * s
}

/// Value seen along a ray: the façade texture if it hits the façade first, else flat ground / sky.
fn trace(origin: &Vector3<f64>, dir: &Vector3<f64>) -> f32 {
    if dir.y > 1e-9 {
        let t = (FACADE_Y - origin.y) / dir.y;
        let hit = origin + dir * t;
        let (u, v) = (hit.x - X0, hit.z);
        if t > 0.0 && u.abs() <= 40.0 && (0.0..=25.0).contains(&v) {
            return facade_texture(u, v) as f32;
        }
    }
    if dir.z < 0.0 {
        90.0
    } else {
        200.0
    }
}

fn true_recording() -> Recording {
    Recording {
        time: "2020-01-01T00:00:00Z".into(),
        ..Recording::new("pano_0001", 0.0, [X0, Y0, 2.5], 90.0, 2.5)
    }
}

/// Oblique camera south of the façade, 300 m up, looking north 45° down at the façade centre (ω = 45°).
fn oblique_image() -> AerialImage {
    let centre = [X0, FACADE_Y - 290.0, 300.0];
    AerialImage {
        file: "obl_0001.tif".into(),
        ..AerialImage::ideal("obl_0001", centre, [45.0, 0.0, 0.0], 7000.0, [1000, 1000])
    }
}

fn render_panorama(rec: &Recording) -> GrayImage {
    let (w, h) = (1600usize, 800usize);
    let cam = PanoramaCamera::from_recording(rec, w as u32, h as u32);
    render((w, h), |u, v| cam.pixel_ray(u, v))
}

fn render_oblique(a: &AerialImage) -> GrayImage {
    let cam = FrameCamera::from_aerial(a);
    render((a.width_px as usize, a.height_px as usize), |u, v| {
        cam.pixel_ray(u, v)
    })
}

/// The `(w, h)` image of the scene traced along `pixel_ray` of each pixel centre.
fn render((w, h): (usize, usize), pixel_ray: impl Fn(f64, f64) -> Ray) -> GrayImage {
    let mut img = GrayImage::filled(w, h, 0.0);
    for r in 0..h {
        for c in 0..w {
            let ray = pixel_ray(c as f64 + 0.5, r as f64 + 0.5);
            img.set(c, r, trace(&ray.origin_world, &ray.dir_world));
        }
    }
    img
}

/// Object points on (or `offset_m` in front of) the façade, moved by `shift_x_m` along x (as a triangulation
/// from panorama poses that are all off by that much would place them), with observations from `rec`.
fn cloud_and_facades(
    rec: &Recording,
    points_uv: &[(f64, f64, f64)],
    shift_x_m: f64,
    resolution_m: f64,
) -> (SparseCloud, TripletFacades) {
    let cam = PanoramaCamera::from_recording(rec, 1600, 800);
    let points: Vec<SparsePoint> = points_uv
        .iter()
        .enumerate()
        .map(|(i, &(u, v, offset))| {
            let p = [X0 + u + shift_x_m, FACADE_Y - offset, v];
            let (pu, pv) = cam.project_world(&Vector3::from(p)).unwrap();
            SparsePoint {
                side: StreetSide::Left,
                tie: MmTiePoint {
                    id: format!("pano_0001#left#{i}"),
                    observations: vec![PanoObservation {
                        image_id: rec.image_id.clone(),
                        u_px: pu,
                        v_px: pv,
                    }],
                    point_world: p,
                    covariance_m2: [[0.0; 3]; 3],
                    max_angle_deg: 10.0,
                },
            }
        })
        .collect();
    let n = points.len();
    let cloud = SparseCloud {
        recordings: ["pano_0000".into(), rec.image_id.clone(), "pano_0002".into()],
        points,
        stats: SparseCloudStats::default(),
    };
    let obl = oblique_image();
    let cam_o = FrameCamera::from_aerial(&obl);
    let centroid = [X0 + shift_x_m, FACADE_Y, 8.0];
    let (cu, cv) = cam_o.project_world(&Vector3::from(centroid)).unwrap();
    let plane = FacadePlane {
        side: StreetSide::Left,
        normal_world: [0.0, -1.0, 0.0],
        centroid_world: centroid,
        axis_u_world: [1.0, 0.0, 0.0],
        axis_v_world: [0.0, 0.0, 1.0],
        inliers: (0..n).collect(),
        thinned: (0..n).collect(),
        occluding_points: 0,
        views: vec![ObliqueView {
            image_id: obl.image_id.clone(),
            theta_deg: 45.0,
            phi_deg: 0.0,
            resolution_m,
            centroid_px: [cu, cv],
        }],
    };
    let facades = TripletFacades {
        recording: rec.image_id.clone(),
        planes: vec![plane],
        stats: FacadeStats::default(),
    };
    (cloud, facades)
}

const ON_FACADE: [(f64, f64, f64); 6] = [
    (-6.0, 7.0, 0.0),
    (-2.0, 9.0, 0.0),
    (0.0, 6.0, 0.0),
    (2.5, 8.0, 0.0),
    (5.0, 10.0, 0.0),
    (7.0, 7.5, 0.0),
];

#[test]
fn patch_grid_pixel_convention_and_shift_sign() {
    let g = upright_grid([10.0, 20.0, 30.0], 6.0, 0.1);
    assert_eq!(g.size_px, 60);
    assert!((g.world_at(30.0, 30.0) - Vector3::new(10.0, 20.0, 30.0)).norm() < 1e-12);
    // One pixel right = +s along axis_u; one pixel down = −s along axis_v.
    assert!((g.world_at(31.0, 30.0) - Vector3::new(10.1, 20.0, 30.0)).norm() < 1e-12);
    assert!((g.world_at(30.0, 31.0) - Vector3::new(10.0, 20.0, 29.9)).norm() < 1e-12);
    let m = g.shift_px_to_plane_m([2.0, 3.0]);
    assert!((m[0] - 0.2).abs() < 1e-12 && (m[1] + 0.3).abs() < 1e-12);
    let px = g.plane_m_to_shift_px(m);
    assert!((px[0] - 2.0).abs() < 1e-12 && (px[1] - 3.0).abs() < 1e-12);
    let s = g.shifted([1.0, -2.0]);
    assert!((s.centre_world - Vector3::new(11.0, 20.0, 28.0)).norm() < 1e-12);
    assert!(PatchGrid::new([0.0; 3], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], 6.0, 0.0).is_none());
}

/// A patch grid on a façade facing ±y: `extent_m` wide along +x and high along +z around `centre_world`, with
/// pixels of `gsd_m`.
fn upright_grid(centre_world: [f64; 3], extent_m: f64, gsd_m: f64) -> PatchGrid {
    PatchGrid::new(
        centre_world,
        [1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        extent_m,
        gsd_m,
    )
    .unwrap()
}

#[test]
fn patches_of_a_textured_facade_from_two_cameras_agree_and_resolution_ratio_follows_sampling() {
    let rec = true_recording();
    let pano = render_panorama(&rec);
    let obl = oblique_image();
    let obl_img = render_oblique(&obl);
    let pano_cam = PanoramaCamera::from_recording(&rec, 1600, 800);
    let cam_o = FrameCamera::from_aerial(&obl);
    // The façade centre is near the oblique image centre (ω = 45° looks north and down).
    let (u, v) = cam_o
        .project_world(&Vector3::new(X0, FACADE_Y, 10.0))
        .unwrap();
    assert!(
        (u - 500.0).abs() < 1.0 && (v - 500.0).abs() < 50.0,
        "({u}, {v})"
    );
    let grid = upright_grid([X0, FACADE_Y, 8.0], 4.0, 0.1);
    let pano = PanoramaLevels::from_image(&pano, 3);
    let obl_img = ScaledWindow::whole(obl_img);
    let mm = fill_from_panorama(&grid, &pano_cam, &pano);
    let ob = fill_from_frame(&grid, &cam_o, &obl_img);
    assert_eq!(ob.valid_pixels, grid.size_px * grid.size_px);
    // Both patches show the texture at the grid (up to interpolation blur): small mean absolute difference
    // against the analytic texture.
    let mut diff_mm = 0.0;
    let mut diff_ob = 0.0;
    for row in 0..grid.size_px {
        for col in 0..grid.size_px {
            let w = grid.world_at(col as f64 + 0.5, row as f64 + 0.5);
            let t = facade_texture(w.x - X0, w.z);
            diff_mm += (f64::from(mm.get(col, row)) - t).abs();
            diff_ob += (f64::from(ob.image.get(col, row)) - t).abs();
        }
    }
    let n = (grid.size_px * grid.size_px) as f64;
    assert!(diff_mm / n < 6.0, "panorama patch mean |Δ| {}", diff_mm / n);
    assert!(diff_ob / n < 6.0, "oblique patch mean |Δ| {}", diff_ob / n);
    // Real-resolution ratio: the façade footprint of an oblique pixel is ≈ 0.058 m across × 0.082 m up; a
    // grid at 0.2 m assigns a distinct pixel to every grid pixel, a grid at 0.02 m reuses pixels ≈ 12 times.
    let coarse = upright_grid([X0, FACADE_Y, 8.0], 4.0, 0.2);
    let (r_coarse, inside) = real_resolution_ratio(&coarse, &cam_o, &obl_img);
    assert_eq!(r_coarse, 1.0);
    assert_eq!(inside, 1.0);
    let fine = upright_grid([X0, FACADE_Y, 8.0], 4.0, 0.02);
    let (r_fine, _) = real_resolution_ratio(&fine, &cam_o, &obl_img);
    let expected = 0.02 * 0.02 / (0.0586 * 0.0829);
    assert!((r_fine - expected).abs() < 0.03, "{r_fine} vs {expected}");
    // The sampling-free ratio equals the one counted while filling.
    let filled = fill_from_frame(&fine, &cam_o, &obl_img);
    assert_eq!(filled.real_resolution_ratio(), r_fine);
    // Grid outside the image: no data.
    let away = upright_grid([X0 + 500.0, FACADE_Y, 8.0], 4.0, 0.1);
    assert_eq!(fill_from_frame(&away, &cam_o, &obl_img).valid_pixels, 0);
}

/// `img` (0..255) scaled to 0..1.
fn unit_range(img: &GrayImage) -> GrayImage {
    let mut out = img.clone();
    out.data.iter_mut().for_each(|v| *v /= 255.0);
    out
}

fn run(
    rec_true: &Recording,
    shift_x_m: f64,
    params: &PatchParams,
    points: &[(f64, f64, f64)],
    resolution_m: f64,
) -> skytie_stages::oblique::types::PatchRegistrationSet {
    // The scene is rendered once per test binary (the panorama always from the true pose).
    static IMAGES: OnceLock<(GrayImage, GrayImage)> = OnceLock::new();
    static PYRAMIDS: OnceLock<(MemoryPyramid, MemoryPyramid)> = OnceLock::new();
    let (pano, obl_img) = IMAGES.get_or_init(|| {
        (
            render_panorama(&true_recording()),
            render_oblique(&oblique_image()),
        )
    });
    assert_eq!(rec_true, &true_recording());
    let obl = oblique_image();
    let mut recorded = rec_true.clone();
    recorded.x += shift_x_m;
    let (cloud, facades) = cloud_and_facades(&recorded, points, shift_x_m, resolution_m);
    // Pyramids hold images as decoded files are: 0..1 (the renders are in 0..255).
    let pyramids = PYRAMIDS.get_or_init(|| {
        (
            MemoryPyramid::from_gray(&unit_range(pano)),
            MemoryPyramid::from_gray(&unit_range(obl_img)),
        )
    });
    register_patches(
        &recorded,
        &pyramids.0,
        &obl,
        &pyramids.1,
        &cloud,
        &facades,
        params,
    )
    .unwrap()
}

#[test]
fn true_poses_register_to_zero_shift_and_a_half_metre_pose_error_is_recovered() {
    let rec = true_recording();
    let p = PatchParams::default();
    assert!(p.validate().is_ok());
    let set = run(&rec, 0.0, &p, &ON_FACADE, 0.06);
    assert_eq!(set.stats.candidates, ON_FACADE.len());
    assert_eq!(set.stats.matches, ON_FACADE.len(), "{:?}", set.stats);
    for m in &set.matches {
        let s = m.shift_plane_m;
        assert!(!m.rejected_coarse);
        assert!(s[0].hypot(s[1]) <= 0.06, "{}: shift {s:?} m", m.point_id);
        assert!(m.real_resolution_ratio >= 0.6);
        assert!(m.score > 0.3, "MI {}", m.score);
        // The oblique observation is the matched point's projection.
        let cam = FrameCamera::from_aerial(&oblique_image());
        let (u, v) = cam
            .project_world(&Vector3::from(m.matched_point_world))
            .unwrap();
        assert_eq!([u, v], m.oblique_px);
    }
    // Panorama 0.5 m east of its true position (and its object points with it): the MM patch centre's
    // content is 0.5 m west (−axis_u) in the oblique patch.
    let set = run(&rec, 0.5, &p, &ON_FACADE, 0.06);
    assert_eq!(set.stats.matches, ON_FACADE.len(), "{:?}", set.stats);
    for m in &set.matches {
        let s = m.shift_plane_m;
        assert!(
            (s[0] + 0.5).abs() <= 0.06 && s[1].abs() <= 0.06,
            "{}: shift {s:?} m",
            m.point_id
        );
        let coarse = m.coarse_shift_plane_m.unwrap();
        assert!((coarse[0] + 0.5).abs() <= 0.15, "coarse {coarse:?}");
        // matched point = object point + shift.
        let expect_x = m.object_point_world[0] + s[0];
        assert!((m.matched_point_world[0] - expect_x).abs() < 1e-9);
    }
    // Deterministic: a rerun gives the identical set.
    assert_eq!(set, run(&rec, 0.5, &p, &ON_FACADE, 0.06));
}

#[test]
fn single_level_and_ncc_variants_recover_the_pose_error() {
    let rec = true_recording();
    for params in [
        PatchParams {
            hierarchical: false,
            ..PatchParams::default()
        },
        PatchParams {
            hierarchical: false,
            fine: Similarity::Ncc,
            ..PatchParams::default()
        },
        PatchParams {
            fine: Similarity::Ncc,
            ..PatchParams::default()
        },
        PatchParams {
            coarse: Similarity::Mi,
            ..PatchParams::default()
        },
    ] {
        let set = run(&rec, 0.5, &params, &ON_FACADE[..3], 0.06);
        assert_eq!(set.stats.matches, 3, "{params:?}: {:?}", set.stats);
        for m in &set.matches {
            let s = m.shift_plane_m;
            assert!(
                (s[0] + 0.5).abs() <= 0.06 && s[1].abs() <= 0.06,
                "{params:?}: shift {s:?}"
            );
            assert_eq!(m.coarse_shift_plane_m.is_some(), params.hierarchical);
        }
    }
}

#[test]
fn off_plane_points_low_resolution_and_outside_points_are_counted() {
    let rec = true_recording();
    let p = PatchParams::default();
    // 5 points on the façade, one 2.5 m in front of it (its patch plane sees the façade with parallax),
    // one far outside the oblique image.
    let mut pts: Vec<(f64, f64, f64)> = ON_FACADE[..5].to_vec();
    pts.push((1.0, 8.0, 2.5));
    pts.push((300.0, 8.0, 0.0));
    let set = run(&rec, 0.0, &p, &pts, 0.06);
    let s = &set.stats;
    assert_eq!(s.candidates, 7);
    assert_eq!(s.rejected_outside, 1, "{s:?}");
    assert_eq!(s.rejected_coarse, 1, "{s:?}");
    assert_eq!(s.matches, 6, "{s:?}");
    let off = set
        .matches
        .iter()
        .find(|m| m.point_id.ends_with("#5"))
        .unwrap();
    assert!(off.rejected_coarse);
    assert!(set
        .matches
        .iter()
        .filter(|m| !m.point_id.ends_with("#5"))
        .all(|m| !m.rejected_coarse));
    // A theoretical resolution far finer than the image: every patch fails the real-resolution ratio.
    let set = run(&rec, 0.0, &p, &ON_FACADE[..2], 0.02);
    assert_eq!(set.stats.rejected_resolution, 2, "{:?}", set.stats);
    assert_eq!(set.stats.matches, 0);
}

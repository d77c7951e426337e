//! Known-answer tests of the façade stage (thesis 4.4.2–4.4.4): trajectory criteria, local plane frame,
//! occlusion, visibility hypothesis, box-grid thinning (Pomerleau et al. 2013) and `find_facades` on synthetic
//! sparse clouds with two façades and clutter.

use nalgebra::Vector3;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::correspondence::{MmTiePoint, PanoObservation};
use skytie_stages::estimators::SplitMix64;
use skytie_stages::geometry::FrameCamera;
use skytie_stages::oblique::facades::occlusion::OcclusionCorridor;
use skytie_stages::oblique::facades::plane::plane_axes;
use skytie_stages::oblique::facades::thinning::box_grid_thin;
use skytie_stages::oblique::facades::trajectory::{
    check_collinearity, reference_normal, TrajectoryRejection,
};
use skytie_stages::oblique::facades::visibility::{
    check_visibility, view_angles_deg, VisibilityRejection,
};
use skytie_stages::oblique::facades::{find_facades, FacadeParams, ThinningSplit};
use skytie_stages::oblique::{SparseCloud, SparseCloudStats, SparsePoint, StreetSide};
use skytie_stages::params::Params;

const X0: f64 = 92_000.0;
const Y0: f64 = 437_000.0;

fn recording(id: &str, x: f64, y: f64, heading_deg: f64) -> Recording {
    Recording {
        time: "2019-06-14T10:00:00Z".into(),
        ..Recording::new(id, 0.0, [x, y, 2.2], heading_deg, 2.2)
    }
}

/// Three recordings 5 m apart driving east (heading 90°) through (X0, Y0).
fn east_triplet() -> [Recording; 3] {
    [
        recording("r0", X0 - 5.0, Y0, 90.0),
        recording("r1", X0, Y0, 90.0),
        recording("r2", X0 + 5.0, Y0, 90.0),
    ]
}

fn point(side: StreetSide, i: usize, local: [f64; 3]) -> SparsePoint {
    SparsePoint {
        side,
        tie: MmTiePoint {
            id: format!("r1#{}#{i}", side.label()),
            // find_facades reads only which recordings observe a point (patch centres must be seen by the
            // centre recording r1); the pixel values do not matter here.
            observations: ["r0", "r1", "r2"]
                .iter()
                .map(|id| PanoObservation {
                    image_id: (*id).to_string(),
                    u_px: 0.0,
                    v_px: 0.0,
                })
                .collect(),
            point_world: [X0 + local[0], Y0 + local[1], local[2]],
            covariance_m2: [[0.0; 3]; 3],
            max_angle_deg: 10.0,
        },
    }
}

fn cloud(points: Vec<SparsePoint>) -> SparseCloud {
    SparseCloud {
        recordings: ["r0".into(), "r1".into(), "r2".into()],
        stats: SparseCloudStats {
            points: points.len(),
            ..Default::default()
        },
        points,
    }
}

/// Local points (relative to (X0, Y0, 0)) of the street scene, in the order: left façade (y = 8, 90 points),
/// right façade (y = −9, 70 points), then clutter: cars (low, in the street), tree crowns beyond the façades'
/// ends, ground points, points behind the façades. Returns the points and the index ranges of the façades.
fn street_scene(
    seed: u64,
) -> (
    Vec<SparsePoint>,
    std::ops::Range<usize>,
    std::ops::Range<usize>,
) {
    let mut rng = SplitMix64::new(seed);
    let mut pts = Vec::new();
    let mut u = |a: f64, b: f64| a + (b - a) * rng.next_f64();
    let mut raw: Vec<(StreetSide, [f64; 3])> = Vec::new();
    for _ in 0..90 {
        raw.push((
            StreetSide::Left,
            [u(-15.0, 15.0), 8.0 + u(-0.03, 0.03), u(3.0, 15.0)],
        ));
    }
    for _ in 0..70 {
        raw.push((
            StreetSide::Right,
            [u(-15.0, 15.0), -9.0 + u(-0.03, 0.03), u(3.0, 12.0)],
        ));
    }
    // Cars in the street on both sides.
    for _ in 0..20 {
        raw.push((StreetSide::Left, [u(-12.0, 12.0), u(3.0, 5.0), u(0.3, 1.5)]));
        raw.push((
            StreetSide::Right,
            [u(-12.0, 12.0), u(-6.0, -3.0), u(0.3, 1.5)],
        ));
    }
    // Tree crowns beyond the façades' ends (x ≈ ±20 m) on the pavements.
    for _ in 0..15 {
        raw.push((StreetSide::Left, [u(19.0, 22.0), u(4.0, 6.0), u(4.0, 8.0)]));
        raw.push((
            StreetSide::Right,
            [u(-22.0, -19.0), u(-7.0, -5.0), u(4.0, 8.0)],
        ));
    }
    // Ground points and points behind the façades (courtyards, roofs seen through gaps).
    for _ in 0..15 {
        raw.push((StreetSide::Left, [u(-15.0, 15.0), u(1.0, 7.0), 0.0]));
        raw.push((StreetSide::Right, [u(-15.0, 15.0), u(-8.0, -1.0), 0.0]));
        raw.push((
            StreetSide::Left,
            [u(-15.0, 15.0), u(10.0, 14.0), u(0.0, 20.0)],
        ));
        raw.push((
            StreetSide::Right,
            [u(-15.0, 15.0), u(-14.0, -11.0), u(0.0, 20.0)],
        ));
    }
    for (i, (side, p)) in raw.into_iter().enumerate() {
        pts.push(point(side, i, p));
    }
    (pts, 0..90, 90..160)
}

/// An oblique camera 450 m up looking north, tilted 45°, whose axis passes through local (x, y_aim, 9 m).
fn oblique_north(id: &str, x: f64, y_aim: f64, focal_px: f64) -> AerialImage {
    AerialImage::ideal(
        id,
        [X0 + x, Y0 + y_aim - 441.0, 450.0],
        [45.0, 0.0, 0.0],
        focal_px,
        [800, 600],
    )
}

fn angle_deg(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (a, b) = (Vector3::from(a), Vector3::from(b));
    (a.dot(&b) / (a.norm() * b.norm()))
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

// ---------------------------------------------------------------------------------------------------------
// find_facades

#[test]
fn two_facades_with_clutter_give_one_plane_per_side() {
    let (pts, left, right) = street_scene(1);
    let c = cloud(pts);
    let t = east_triplet();
    let obliques = [
        oblique_north("a_left", 0.0, 8.0, 10_000.0),
        oblique_north("b_far", 300.0, 8.0, 10_000.0),
    ];
    let f = find_facades(
        &c,
        [&t[0], &t[1], &t[2]],
        &obliques,
        &FacadeParams::default(),
    );
    assert_eq!(f.recording, "r1");
    assert_eq!(f.planes.len(), 2, "{:?}", f.stats);
    assert_eq!(f.stats.planes, 2);
    assert_eq!(f.stats.sides_without_plane, 0);
    assert_eq!(f.stats.occluded, 0);
    assert_eq!(f.stats.candidate_points, c.points.len());

    for plane in &f.planes {
        let (expected_normal, offset_y, range) = match plane.side {
            StreetSide::Left => ([0.0, -1.0, 0.0], 8.0, left.clone()),
            StreetSide::Right => ([0.0, 1.0, 0.0], -9.0, right.clone()),
        };
        let err = angle_deg(plane.normal_world, expected_normal);
        assert!(
            err < 1.0,
            "{:?}: normal {:?} off by {err}°",
            plane.side,
            plane.normal_world
        );
        let offset = plane.centroid_world[1] - Y0;
        assert!(
            (offset - offset_y).abs() < 0.05,
            "{:?}: offset {offset}",
            plane.side
        );
        // Every façade point is an inlier, no clutter point is.
        assert_eq!(
            plane.inliers,
            range.clone().collect::<Vec<_>>(),
            "{:?}",
            plane.side
        );
        assert_eq!(plane.occluding_points, 0);
        // Local frame (eq. 4/7): orthonormal, right-handed, u horizontal along the façade, v up.
        let (u, v, n) = (
            Vector3::from(plane.axis_u_world),
            Vector3::from(plane.axis_v_world),
            Vector3::from(plane.normal_world),
        );
        assert!((u.norm() - 1.0).abs() < 1e-9 && (v.norm() - 1.0).abs() < 1e-9);
        assert!((u.cross(&v) - n).norm() < 1e-9, "u × v ≠ n");
        // u is the inliers' largest covariance eigenvector (eq. 4/7) projected into the plane; with 70–90
        // random points that is within ~10° of the horizontal, so u is horizontal-ish and v up-ish.
        let pts: Vec<Vector3<f64>> = plane
            .inliers
            .iter()
            .map(|&i| Vector3::from(c.points[i].tie.point_world))
            .collect();
        let mean = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
        let cov = pts.iter().fold(nalgebra::Matrix3::zeros(), |acc, p| {
            acc + (p - mean) * (p - mean).transpose()
        });
        let eig = nalgebra::SymmetricEigen::new(cov);
        let imax = eig.eigenvalues.imax();
        let e: Vector3<f64> = eig.eigenvectors.column(imax).into_owned();
        let e_in_plane = (e - n * e.dot(&n)).normalize();
        assert!(
            u.dot(&e_in_plane).abs() > 1.0 - 1e-9,
            "u {u:?} vs eigenvector {e_in_plane:?}"
        );
        assert!(
            u.z.abs() < 15f64.to_radians().sin() && v.z > 15f64.to_radians().cos(),
            "u {u:?} v {v:?}"
        );
        // Thinning keeps a subset of the inliers.
        assert!(!plane.thinned.is_empty() && plane.thinned.len() < plane.inliers.len());
        assert!(plane.thinned.iter().all(|i| plane.inliers.contains(i)));
    }
    // Visibility: the camera looking north sees the left façade (facing south) at θ ≈ 45°, φ ≈ 0°; the one
    // 300 m east does not contain the centroid; neither sees the right façade (facing north) from the front.
    let left_plane = f
        .planes
        .iter()
        .find(|p| p.side == StreetSide::Left)
        .unwrap();
    let right_plane = f
        .planes
        .iter()
        .find(|p| p.side == StreetSide::Right)
        .unwrap();
    assert_eq!(left_plane.views.len(), 1);
    let view = &left_plane.views[0];
    assert_eq!(view.image_id, "a_left");
    assert!((view.theta_deg - 45.0).abs() < 1.5, "θ {}", view.theta_deg);
    assert!(view.phi_deg < 2.0, "φ {}", view.phi_deg);
    assert!(
        (view.resolution_m - 0.0624).abs() < 0.002,
        "t {}",
        view.resolution_m
    );
    assert!(right_plane.views.is_empty());
    assert_eq!(f.stats.visible_views, 1);
    assert_eq!(f.stats.rejected_views, 3);
    assert_eq!(f.stats.inliers, 160);
    assert_eq!(
        f.stats.thinned,
        left_plane.thinned.len() + right_plane.thinned.len()
    );
}

#[test]
fn an_occluding_cluster_marks_the_facade_occluded() {
    let (mut pts, _, _) = street_scene(2);
    // A tree crown between the recording and the left façade, in front of its middle.
    let mut rng = SplitMix64::new(3);
    let n0 = pts.len();
    for i in 0..20 {
        let p = [
            -3.0 + 6.0 * rng.next_f64(),
            4.0 + rng.next_f64(),
            4.0 + 4.0 * rng.next_f64(),
        ];
        pts.push(point(StreetSide::Left, n0 + i, p));
    }
    let c = cloud(pts);
    let t = east_triplet();
    let f = find_facades(&c, [&t[0], &t[1], &t[2]], &[], &FacadeParams::default());
    assert_eq!(f.stats.occluded, 1);
    assert_eq!(f.planes.len(), 1);
    assert_eq!(f.planes[0].side, StreetSide::Right);
    assert_eq!(f.stats.sides_without_plane, 0);
    // With a higher threshold the façade is kept and reports the 20 occluding points.
    let p = FacadeParams {
        occlusion_max_points: 25,
        ..Default::default()
    };
    let f = find_facades(&c, [&t[0], &t[1], &t[2]], &[], &p);
    let left = f
        .planes
        .iter()
        .find(|p| p.side == StreetSide::Left)
        .unwrap();
    assert_eq!(left.occluding_points, 20);
}

#[test]
fn a_bent_triplet_or_a_wrong_centre_gives_no_planes() {
    let (pts, _, _) = street_scene(4);
    let c = cloud(pts);
    let t = east_triplet();
    let bent = recording("r1", X0, Y0 + 1.0, 90.0);
    let f = find_facades(&c, [&t[0], &bent, &t[2]], &[], &FacadeParams::default());
    assert!(f.planes.is_empty());
    assert_eq!(f.stats.sides_without_plane, 2);
    let f = find_facades(&c, [&t[0], &t[2], &t[1]], &[], &FacadeParams::default());
    assert!(f.planes.is_empty());
    assert_eq!(f.stats.sides_without_plane, 2);
    // Invalid params: no planes, no panic.
    let bad = FacadeParams {
        min_points: 0,
        ..Default::default()
    };
    assert!(bad.validate().is_err());
    assert!(find_facades(&c, [&t[0], &t[1], &t[2]], &[], &bad)
        .planes
        .is_empty());
}

#[test]
fn too_few_facade_points_give_no_plane_on_that_side() {
    let (pts, _, _) = street_scene(5);
    // Keep only 9 of the left façade's points (min_points = 10) and the right side.
    let pts: Vec<SparsePoint> = pts
        .into_iter()
        .enumerate()
        .filter(|(i, p)| *i < 9 || p.side == StreetSide::Right)
        .map(|(_, p)| p)
        .collect();
    let c = cloud(pts);
    let t = east_triplet();
    let f = find_facades(&c, [&t[0], &t[1], &t[2]], &[], &FacadeParams::default());
    assert_eq!(f.planes.len(), 1);
    assert_eq!(f.planes[0].side, StreetSide::Right);
    assert_eq!(f.stats.sides_without_plane, 1);
}

#[test]
fn a_second_plane_per_side_finds_a_building_set_back() {
    // Left side: a façade at y = 8 for x < 0 and one set back at y = 12 for x > 0.
    let mut rng = SplitMix64::new(8);
    let mut pts = Vec::new();
    for i in 0..120 {
        let x = -15.0 + 15.0 * rng.next_f64();
        let (x, y) = if i % 2 == 0 { (x, 8.0) } else { (-x, 12.0) };
        pts.push(point(
            StreetSide::Left,
            i,
            [
                x,
                y + 0.02 * rng.next_gaussian(),
                3.0 + 9.0 * rng.next_f64(),
            ],
        ));
    }
    let c = cloud(pts);
    let t = east_triplet();
    let one = find_facades(&c, [&t[0], &t[1], &t[2]], &[], &FacadeParams::default());
    assert_eq!(one.planes.len(), 1);
    let p = FacadeParams {
        max_planes_per_side: 2,
        ..Default::default()
    };
    let two = find_facades(&c, [&t[0], &t[1], &t[2]], &[], &p);
    assert_eq!(two.planes.len(), 2);
    let mut offsets: Vec<f64> = two
        .planes
        .iter()
        .map(|p| p.centroid_world[1] - Y0)
        .collect();
    offsets.sort_by(f64::total_cmp);
    assert!(
        (offsets[0] - 8.0).abs() < 0.05 && (offsets[1] - 12.0).abs() < 0.05,
        "{offsets:?}"
    );
    assert_eq!(
        two.stats.sides_without_plane, 1,
        "the right side has no points"
    );
}

#[test]
fn find_facades_is_deterministic() {
    let (pts, _, _) = street_scene(6);
    let c = cloud(pts);
    let t = east_triplet();
    let obliques = [oblique_north("a", 0.0, 8.0, 10_000.0)];
    let p = FacadeParams {
        seed: 17,
        ..Default::default()
    };
    let a = find_facades(&c, [&t[0], &t[1], &t[2]], &obliques, &p);
    let b = find_facades(&c, [&t[0], &t[1], &t[2]], &obliques, &p);
    assert_eq!(a, b);
}

// ---------------------------------------------------------------------------------------------------------
// trajectory

#[test]
fn collinearity_and_reference_vectors() {
    let t = east_triplet();
    assert_eq!(check_collinearity([&t[0], &t[1], &t[2]], 0.5, 1.0), Ok(0.0));
    let bent = recording("r1", X0, Y0 + 0.7, 90.0);
    match check_collinearity([&t[0], &bent, &t[2]], 0.5, 1.0) {
        Err(TrajectoryRejection::NotCollinear { deviation_m }) => {
            assert!((deviation_m - 0.7).abs() < 1e-9)
        }
        other => panic!("{other:?}"),
    }
    let standing = [&t[1], &t[1], &t[1]];
    assert!(matches!(
        check_collinearity(standing, 0.5, 1.0),
        Err(TrajectoryRejection::TooShort { .. })
    ));
    // Driving east: left façades (north) face south, right façades face north.
    let l = reference_normal(&t[1], StreetSide::Left);
    let r = reference_normal(&t[1], StreetSide::Right);
    assert!((l - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
    assert!((r - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
    // Driving north: the left façades (west) face east.
    let n = recording("n", 0.0, 0.0, 0.0);
    assert!((reference_normal(&n, StreetSide::Left) - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
}

// ---------------------------------------------------------------------------------------------------------
// local frame (eq. 4/7)

#[test]
fn plane_axes_are_right_handed_with_u_horizontal_even_for_a_tall_facade() {
    // A tall narrow façade (x = 0 plane, normal +x): a regular grid 2 m wide, 20 m high (no y–z correlation,
    // so the eigenvectors are exactly the axes), the largest eigenvector vertical; u must still be the
    // horizontal one.
    let pts: Vec<Vector3<f64>> = (0..=10)
        .flat_map(|i| (0..=20).map(move |j| Vector3::new(0.0, 0.2 * i as f64, j as f64)))
        .collect();
    let c = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
    let n = Vector3::new(1.0, 0.0, 0.0);
    let (u, v) = plane_axes(&pts, &c, &n).unwrap();
    assert!((u.cross(&v) - n).norm() < 1e-12);
    assert!((v - Vector3::z()).norm() < 1e-9, "v {v:?}");
    assert!((u - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-9, "u {u:?}");
    // Mirrored normal: still right-handed.
    let (u2, v2) = plane_axes(&pts, &c, &-n).unwrap();
    assert!((u2.cross(&v2) + n).norm() < 1e-12);
    assert!(v2.z > 0.99);
}

// ---------------------------------------------------------------------------------------------------------
// occlusion

#[test]
fn occlusion_corridor_counts_only_points_on_sight_lines_to_the_facade() {
    // Façade y = 8 (normal −y towards the recording at the origin, 2.2 m up), inliers x ∈ [−10, 10],
    // z ∈ [3, 13].
    let inliers = [
        Vector3::new(-10.0, 8.0, 3.0),
        Vector3::new(10.0, 8.0, 3.0),
        Vector3::new(-10.0, 8.0, 13.0),
        Vector3::new(10.0, 8.0, 13.0),
    ];
    let centroid = Vector3::new(0.0, 8.0, 8.0);
    let corridor = OcclusionCorridor::new(
        centroid,
        Vector3::new(0.0, -1.0, 0.0),
        Vector3::new(-1.0, 0.0, 0.0),
        Vector3::z(),
        inliers,
        0.5,
    );
    let rec = Vector3::new(0.0, 0.0, 2.2);
    // In front, on a sight line to the façade's middle.
    assert!(corridor.occludes(&rec, &Vector3::new(0.0, 4.0, 5.0)));
    // Within the band (façade relief) — not an occluder.
    assert!(!corridor.occludes(&rec, &Vector3::new(0.0, 7.7, 5.0)));
    // Behind the façade, behind the recording, on the other side.
    assert!(!corridor.occludes(&rec, &Vector3::new(0.0, 9.0, 5.0)));
    assert!(!corridor.occludes(&rec, &Vector3::new(0.0, -3.0, 5.0)));
    // A car: its sight line meets the façade below the inliers (z = 2.2 − 1.2·2 = −0.2).
    assert!(!corridor.occludes(&rec, &Vector3::new(0.0, 4.0, 1.0)));
    // Beyond the façade's end along the street: hits x = 16 > 10.
    assert!(!corridor.occludes(&rec, &Vector3::new(8.0, 4.0, 5.0)));
    assert_eq!(
        corridor.count(
            &rec,
            &[
                Vector3::new(0.0, 4.0, 5.0),
                Vector3::new(1.0, 6.0, 9.0),
                Vector3::new(0.0, 4.0, 1.0)
            ]
        ),
        2
    );
}

// ---------------------------------------------------------------------------------------------------------
// visibility (thesis 4.4.3)

#[test]
fn view_angles_of_cameras_at_known_positions() {
    let n = Vector3::new(0.0, -1.0, 0.0);
    let c = Vector3::new(X0, Y0 + 8.0, 9.0);
    let at = |dx: f64, dz: f64| c + Vector3::new(dx, -100.0, dz);
    let (t, p) = view_angles_deg(&n, &c, &at(0.0, 0.0)).unwrap();
    assert!(t.abs() < 1e-9 && p.abs() < 1e-9);
    let (t, p) = view_angles_deg(&n, &c, &at(0.0, 100.0 * 60f64.to_radians().tan())).unwrap();
    assert!((t - 60.0).abs() < 1e-9 && p.abs() < 1e-9);
    let (t, p) = view_angles_deg(&n, &c, &at(-100.0 * 30f64.to_radians().tan(), 0.0)).unwrap();
    assert!(t.abs() < 1e-9 && (p - 30.0).abs() < 1e-9);
    let (t, p) = view_angles_deg(
        &n,
        &c,
        &at(
            100.0 * 20f64.to_radians().tan(),
            100.0 * 45f64.to_radians().tan(),
        ),
    )
    .unwrap();
    assert!((t - 45.0).abs() < 1e-9 && (p - 20.0).abs() < 1e-9);
    // Behind the plane or in it.
    assert!(view_angles_deg(&n, &c, &(c + Vector3::new(0.0, 100.0, 50.0))).is_none());
    assert!(view_angles_deg(&n, &c, &(c + Vector3::new(10.0, 0.0, 50.0))).is_none());
}

/// A camera at `centroid + (0, −dist, dist·tan(elev))` looking at the centroid (ω = 90° − elev: north and
/// down by `elev_deg`).
fn camera_looking_at(
    centroid: &Vector3<f64>,
    dist: f64,
    elev_deg: f64,
    focal_px: f64,
) -> FrameCamera {
    FrameCamera::from_aerial(&AerialImage::ideal(
        "cam",
        [
            centroid.x,
            centroid.y - dist,
            centroid.z + dist * elev_deg.to_radians().tan(),
        ],
        [90.0 - elev_deg, 0.0, 0.0],
        focal_px,
        [800, 600],
    ))
}

#[test]
fn visibility_hypothesis_pass_and_fail() {
    let n = Vector3::new(0.0, -1.0, 0.0);
    let c = Vector3::new(X0, Y0 + 8.0, 9.0);
    // Straight in front, 100 m away, f = 2000 px: θ = φ = 0, t = 5 cm, centroid at the principal point.
    let cam = camera_looking_at(&c, 100.0, 0.0, 2000.0);
    let v = check_visibility("front", &cam, &n, &c, 70.0, 0.08).unwrap();
    assert!(v.theta_deg.abs() < 1e-9 && v.phi_deg.abs() < 1e-9);
    assert!((v.resolution_m - 0.05).abs() < 1e-12);
    assert!((v.centroid_px[0] - 400.0).abs() < 1e-6 && (v.centroid_px[1] - 300.0).abs() < 1e-6);
    assert_eq!(v.image_id, "front");
    // 65° elevation passes, 75° fails (θ), both looking at the centroid.
    let cam = camera_looking_at(&c, 100.0, 65.0, 5000.0);
    let v = check_visibility("e65", &cam, &n, &c, 70.0, 0.08).unwrap();
    assert!((v.theta_deg - 65.0).abs() < 1e-9);
    // range = 100 / cos 65° = 236.6 m ⇒ t = 0.0473 m.
    assert!((v.resolution_m - 100.0 / 65f64.to_radians().cos() / 5000.0).abs() < 1e-12);
    let cam = camera_looking_at(&c, 100.0, 75.0, 5000.0);
    match check_visibility("e75", &cam, &n, &c, 70.0, 0.08) {
        Err(VisibilityRejection::Angle { theta_deg, .. }) => {
            assert!((theta_deg - 75.0).abs() < 1e-9)
        }
        other => panic!("{other:?}"),
    }
    // Too coarse: 100 m at f = 1000 px is 10 cm.
    let cam = camera_looking_at(&c, 100.0, 0.0, 1000.0);
    match check_visibility("coarse", &cam, &n, &c, 70.0, 0.08) {
        Err(VisibilityRejection::Resolution { resolution_m }) => {
            assert!((resolution_m - 0.1).abs() < 1e-12)
        }
        other => panic!("{other:?}"),
    }
    // Centroid outside the image: the camera looks at a point 50 m to the east.
    let cam = camera_looking_at(&(c + Vector3::new(50.0, 0.0, 0.0)), 100.0, 0.0, 2000.0);
    assert_eq!(
        check_visibility("aside", &cam, &n, &c, 70.0, 0.08),
        Err(VisibilityRejection::Outside)
    );
    // Behind the plane.
    assert_eq!(
        check_visibility("behind", &cam, &-n, &c, 70.0, 0.08),
        Err(VisibilityRejection::Behind)
    );
}

// ---------------------------------------------------------------------------------------------------------
// box-grid thinning (Pomerleau et al. 2013)

fn uniform_cube(n: usize, size: f64, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            [
                size * rng.next_f64(),
                size * rng.next_f64(),
                size * rng.next_f64(),
            ]
        })
        .collect()
}

#[test]
fn median_split_of_k_times_power_of_two_points_gives_exactly_the_leaves() {
    for (k, m) in [(8usize, 5u32), (5, 4), (3, 6)] {
        let pts = uniform_cube(k << m, 10.0, u64::from(m));
        let kept = box_grid_thin(&pts, k, f64::INFINITY, ThinningSplit::Median, 1);
        assert_eq!(kept.len(), 1 << m, "K = {k}, m = {m}");
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        assert!(kept.iter().all(|&i| i < pts.len()));
    }
}

#[test]
fn uniform_cloud_thinning_counts() {
    let pts = uniform_cube(10_000, 10.0, 2);
    let median = box_grid_thin(&pts, 8, f64::INFINITY, ThinningSplit::Median, 3);
    assert!(
        (1250..=2500).contains(&median.len()),
        "median kept {}",
        median.len()
    );
    let midpoint = box_grid_thin(&pts, 8, f64::INFINITY, ThinningSplit::Midpoint, 3);
    assert!(
        (1250..10_000).contains(&midpoint.len()),
        "midpoint kept {}",
        midpoint.len()
    );
}

#[test]
fn midpoint_split_keeps_isolated_points_median_split_does_not() {
    // 1000 points in 1 m³ + 10 isolated points 10 m apart.
    let mut pts = uniform_cube(1000, 1.0, 4);
    for i in 0..10 {
        pts.push([10.0 * (i + 1) as f64, 0.5, 0.5]);
    }
    let isolated = |kept: &[usize]| kept.iter().filter(|&&i| i >= 1000).count();
    let k = 8;
    // Midpoint split with the 2 m box cap (the façade default): every isolated point is kept.
    let midpoint = box_grid_thin(&pts, k, 2.0, ThinningSplit::Midpoint, 5);
    assert_eq!(isolated(&midpoint), 10);
    // The reference median split (no cap): leaves hold ⌈K/2⌉..K points, the 10 isolated points share 1–3
    // leaves.
    let median = box_grid_thin(&pts, k, f64::INFINITY, ThinningSplit::Median, 5);
    assert!(
        isolated(&median) <= 3,
        "median kept {} isolated points",
        isolated(&median)
    );
    // Without the cap the midpoint split also merges them (6 of them fall in the right half of the first
    // split, a box of ≤ K points).
    let uncapped = box_grid_thin(&pts, k, f64::INFINITY, ThinningSplit::Midpoint, 5);
    assert!(isolated(&uncapped) < 10);
    // All thin the cluster (1 m³, below the cap): between 1000 / K and 1000 points.
    for kept in [&midpoint, &median, &uncapped] {
        let cluster = kept.len() - isolated(kept);
        assert!(
            (125..1000).contains(&cluster),
            "{cluster} cluster points kept"
        );
    }
}

#[test]
fn thinning_degenerate_inputs_and_determinism() {
    let same = vec![[1.0, 2.0, 3.0]; 50];
    assert_eq!(
        box_grid_thin(&same, 8, 2.0, ThinningSplit::Median, 0).len(),
        1
    );
    assert_eq!(
        box_grid_thin(&same, 8, 2.0, ThinningSplit::Midpoint, 0).len(),
        1
    );
    assert!(box_grid_thin(&[], 8, 2.0, ThinningSplit::Midpoint, 0).is_empty());
    let mut pts = uniform_cube(500, 5.0, 9);
    pts[7] = [f64::NAN, 0.0, 0.0];
    let a = box_grid_thin(&pts, 6, 2.0, ThinningSplit::Midpoint, 11);
    assert_eq!(a, box_grid_thin(&pts, 6, 2.0, ThinningSplit::Midpoint, 11));
    assert!(!a.contains(&7));
    // Fewer points than K: one point.
    assert_eq!(
        box_grid_thin(&pts[..5], 6, f64::INFINITY, ThinningSplit::Median, 1).len(),
        1
    );
    // K = 1 keeps every distinct point.
    assert_eq!(
        box_grid_thin(&pts[8..40], 1, 2.0, ThinningSplit::Median, 1).len(),
        32
    );
}

/// Patch centres (`thinned`) are plane inliers that the centre recording observes and that lie within
/// `max_centre_offset_m` of the plane; points of a neighbouring triplet and off-plane inliers still count for
/// the plane fit.
#[test]
fn patch_centres_are_observed_by_the_centre_and_close_to_the_plane() {
    let (mut pts, left, _) = street_scene(1);
    let base = FacadeParams::default();
    // Half of the left façade's points come from a neighbouring triplet that r1 does not see them in.
    let unseen: Vec<usize> = left.clone().step_by(2).collect();
    for &i in &unseen {
        pts[i].tie.observations.retain(|o| o.image_id != "r1");
    }
    // One seen left point is pushed 0.3 m off the façade: still an inlier (band 0.5 m), never a centre.
    let off = left.clone().find(|i| !unseen.contains(i)).unwrap();
    pts[off].tie.point_world[1] -= 0.3;
    let c = cloud(pts);
    let t = east_triplet();
    let params = FacadeParams {
        thinning_max_points_per_box: 1, // boxes split down to single points: every eligible point is a centre
        ..base
    };
    let f = find_facades(&c, [&t[0], &t[1], &t[2]], &[], &params);
    let plane = f
        .planes
        .iter()
        .find(|p| p.side == StreetSide::Left)
        .expect("left plane");
    assert!(
        plane.inliers.contains(&off),
        "the off-plane point is an inlier"
    );
    assert!(unseen.iter().all(|i| plane.inliers.contains(i)));
    assert!(!plane.thinned.contains(&off));
    assert!(plane.thinned.iter().all(|i| !unseen.contains(i)));
    let near_seen = plane
        .inliers
        .iter()
        .filter(|&&i| {
            !unseen.contains(&i)
                && (c.points[i].tie.point_world[1] - (Y0 + 8.0)).abs() <= params.max_centre_offset_m
        })
        .count();
    assert!(near_seen > 0);
    assert_eq!(plane.thinned.len(), near_seen, "{:?}", plane.thinned);
}

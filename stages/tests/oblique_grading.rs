//! Known-answer tests of the oblique truth grading: exact synthetic correspondences are correct, one moved by
//! 5 oblique pixels (in either image direction, so also along the epipolar line) is wrong.

mod support;

use std::collections::HashMap;

use nalgebra::Vector3;
use skytie_stages::campaign::{AerialImage, AerialKind, Recording};
use skytie_stages::correspondence::{
    AerialControlPoint, AerialObservation, MmTiePoint, PanoObservation,
};
use skytie_stages::geometry::{FrameCamera, PanoramaCamera};
use skytie_stages::oblique::grading::{grade_match, grade_oblique, SceneOracle, Truth, Verdict};
use skytie_stages::oblique::{
    ConsensusStats, ObliqueCorrespondence, ObliqueResult, PatchMatch, SparseCloud,
    SparseCloudStats, SparsePoint, StreetSide,
};
use skytie_stages::synth::preset::Preset;
use skytie_stages::synth::scene_truth::{along_polyline, build_scenes};
use support::{oblique_looking_at, street_recording, E0, N0};

const W: u32 = 1600;
const H: u32 = 800;

struct Scene {
    truth: Truth,
    cloud: SparseCloud,
    matches: Vec<PatchMatch>,
    points: Vec<Vector3<f64>>,
}

/// Two panoramas 5 m apart (true poses), façade points 10 m north (left side when driving east) and south,
/// one oblique image looking north-down at the street; exact matches of every point from panorama r1.
fn scene() -> Scene {
    let recs = [
        street_recording("r1", 1, 102.5),
        street_recording("r2", 2, 102.5),
    ];
    let target = Vector3::new(E0 + 7.5, N0, 105.0);
    let oblique = oblique_looking_at("o1", Vector3::new(E0 + 7.5, N0 - 750.0, 850.0), target);
    let cam = FrameCamera::from_aerial(&oblique);
    let panos: Vec<PanoramaCamera> = recs
        .iter()
        .map(|r| PanoramaCamera::from_recording(r, W, H))
        .collect();
    let points: Vec<Vector3<f64>> = (0..6)
        .map(|i| {
            let north = if i % 2 == 0 { 10.0 } else { -10.0 };
            Vector3::new(E0 + 3.0 + i as f64, N0 + north, 104.0 + 0.5 * i as f64)
        })
        .collect();
    let mut sparse = Vec::new();
    let mut matches = Vec::new();
    for (i, x) in points.iter().enumerate() {
        let obs: Vec<PanoObservation> = recs
            .iter()
            .zip(&panos)
            .map(|(r, p)| {
                let (u, v) = p.project_world(x).unwrap();
                PanoObservation {
                    image_id: r.image_id.clone(),
                    u_px: u,
                    v_px: v,
                }
            })
            .collect();
        let id = format!("r1#{}#{i}", if i % 2 == 0 { "left" } else { "right" });
        let side = if i % 2 == 0 {
            StreetSide::Left
        } else {
            StreetSide::Right
        };
        let (u, v) = cam.project_world(x).unwrap();
        assert!(cam.contains(u, v));
        matches.push(PatchMatch {
            point_id: id.clone(),
            side,
            object_point_world: [x.x - 0.8, x.y, x.z],
            mm: obs[0].clone(),
            oblique_image_id: "o1".into(),
            shift_plane_m: [0.8, 0.0],
            coarse_shift_plane_m: None,
            matched_point_world: [x.x, x.y, x.z],
            oblique_px: [u, v],
            score: 0.7,
            real_resolution_ratio: 1.0,
            rejected_coarse: false,
            level: 0,
        });
        sparse.push(SparsePoint {
            side,
            tie: MmTiePoint {
                id,
                observations: obs,
                point_world: [x.x - 0.8, x.y, x.z],
                covariance_m2: [[0.0; 3]; 3],
                max_angle_deg: 20.0,
            },
        });
    }
    let truth = Truth {
        recordings: recs
            .iter()
            .map(|r| (r.image_id.clone(), (r.clone(), W, H)))
            .collect(),
        aerial: HashMap::from([("o1".to_string(), oblique)]),
    };
    let cloud = SparseCloud {
        recordings: ["r0".into(), "r1".into(), "r2".into()],
        points: sparse,
        stats: SparseCloudStats::default(),
    };
    Scene {
        truth,
        cloud,
        matches,
        points,
    }
}

fn tie<'a>(s: &'a Scene, m: &PatchMatch) -> Option<&'a MmTiePoint> {
    s.cloud
        .points
        .iter()
        .map(|p| &p.tie)
        .find(|t| t.id == m.point_id)
}

#[test]
fn exact_correspondences_are_correct_and_five_pixels_off_is_wrong() {
    let s = scene();
    for m in &s.matches {
        assert_eq!(
            grade_match(&s.truth, None, tie(&s, m), m),
            Some(Verdict::Correct),
            "{}",
            m.point_id
        );
        // Also without the tie point (closest-approach midpoint as the best point).
        assert_eq!(
            grade_match(&s.truth, None, None, m),
            Some(Verdict::Correct),
            "{}",
            m.point_id
        );
        for (du, dv) in [(5.0, 0.0), (0.0, 5.0), (-3.0, 4.0)] {
            let mut moved = m.clone();
            moved.oblique_px = [m.oblique_px[0] + du, m.oblique_px[1] + dv];
            assert_eq!(
                grade_match(&s.truth, None, tie(&s, m), &moved),
                Some(Verdict::Wrong),
                "{} moved by ({du}, {dv}) px",
                m.point_id
            );
        }
    }
    let mut unknown = s.matches[0].clone();
    unknown.oblique_image_id = "nope".into();
    assert_eq!(grade_match(&s.truth, None, None, &unknown), None);
}

#[test]
fn grade_counts_before_and_after_consensus_per_side() {
    let s = scene();
    let mut correspondences: Vec<ObliqueCorrespondence> = s
        .matches
        .iter()
        .map(|m| ObliqueCorrespondence {
            matched: m.clone(),
            recording: "r1".into(),
            deviation_from_median_m: 0.0,
            kept: true,
        })
        .collect();
    // Two wrong ones (moved 5 px): one rejected by the consensus, one kept.
    correspondences[0].matched.oblique_px[0] += 5.0;
    correspondences[0].kept = false;
    correspondences[1].matched.oblique_px[1] += 5.0;
    // A control point 3 cm east and 4 cm above the true point of point 2.
    let x = s.points[2];
    let control = vec![AerialControlPoint {
        map: None,
        ray_ground: None,
        tie_point_id: s.cloud.points[2].tie.id.clone(),
        mm: s.cloud.points[2].tie.observations.clone(),
        aerial: vec![AerialObservation {
            image_id: "o1".into(),
            kind: AerialKind::Oblique,
            u_px: 0.0,
            v_px: 0.0,
            score: 1.0,
            sigma_px: None,
        }],
        point_world: Some([x.x + 0.03, x.y, x.z + 0.04]),
        covariance_m2: None,
    }];
    let result = ObliqueResult {
        correspondences,
        control,
        stats: ConsensusStats::default(),
    };
    let g = grade_oblique(&s.truth, None, std::slice::from_ref(&s.cloud), &result);
    assert_eq!((g.correspondences, g.inliers, g.outliers), (6, 4, 2));
    assert!((g.inlier_ratio - 4.0 / 6.0).abs() < 1e-12);
    assert_eq!(
        (g.inliers_after_consensus, g.outliers_after_consensus),
        (4, 1)
    );
    assert!((g.inlier_ratio_after_consensus - 0.8).abs() < 1e-12);
    assert_eq!(
        (g.left.correspondences, g.left.inliers, g.left.kept),
        (3, 2, 2)
    );
    assert_eq!(
        (g.right.correspondences, g.right.inliers, g.right.kept),
        (3, 2, 3)
    );
    assert_eq!(g.control_points.count, 1);
    assert!((g.control_points.median_horizontal_m - 0.03).abs() < 1e-4);
    assert!((g.control_points.median_vertical_m - 0.04).abs() < 1e-4);
    assert_eq!(g.non_matchable, None);
    let m = g.metrics();
    assert_eq!(m["inliers_after_consensus"], 4);
    assert!((m["control_point_error_m"].as_f64().unwrap() - 0.05).abs() < 1e-4);
    assert!(m["non_matchable"].is_null());
    assert_eq!(m["sides"]["right"]["kept"], 3);
}

/// A match of panorama observation `(u, v)` of `rec` with oblique pixel `px` of image `o1`.
fn pano_match(rec: &Recording, u: f64, v: f64, px: [f64; 2]) -> PatchMatch {
    PatchMatch {
        point_id: "p".into(),
        side: StreetSide::Left,
        object_point_world: [0.0; 3],
        mm: PanoObservation {
            image_id: rec.image_id.clone(),
            u_px: u,
            v_px: v,
        },
        oblique_image_id: "o1".into(),
        shift_plane_m: [0.0, 0.0],
        coarse_shift_plane_m: None,
        matched_point_world: [0.0; 3],
        oblique_px: px,
        score: 1.0,
        real_resolution_ratio: 1.0,
        rejected_coarse: false,
        level: 0,
    }
}

#[test]
fn with_the_scene_the_reference_is_the_seen_surface_and_hidden_points_are_non_matchable() {
    // The tiny preset's scene; a panorama on its route looking sideways at a façade 2 m above the road.
    let scenes = build_scenes(Preset::Tiny, 3, None);
    let route = along_polyline(scenes[0].route_world(), 5.0);
    let (p, q) = (route[route.len() / 2], route[route.len() / 2 + 1]);
    let ground = scenes[0].ground_height_m(p[0], p[1]);
    let oracle = SceneOracle::new(scenes);
    let heading_deg = (q[0] - p[0]).atan2(q[1] - p[1]).to_degrees();
    let rec = Recording {
        x: p[0],
        y: p[1],
        z: ground + 2.2,
        heading_deg,
        camera_height_m: 2.2,
        ..street_recording("r1", 0, 102.5)
    };
    let pano = PanoramaCamera::from_recording(&rec, W, H);
    // Find a panorama column, on the horizon row, that sees a surface within 40 m (a façade).
    let v = f64::from(H) / 2.0 + 0.5;
    let (u, x) = (0..W)
        .step_by(8)
        .find_map(|u| {
            let u = f64::from(u) + 0.5;
            let ray = pano.pixel_ray(u, v);
            oracle
                .mm_surface_point(&ray)
                .filter(|x| (x - ray.origin_world).norm() < 40.0)
                .map(|x| (u, x))
        })
        .expect("a façade beside the tiny route");
    // An oblique camera on the panorama's side of the façade looking at the point, high enough to see over
    // the buildings across the street.
    let out = (Vector3::new(p[0], p[1], x.z) - x).normalize();
    let up = Vector3::new(0.0, 0.0, 1.0);
    let seeing = oblique_looking_at("o1", x + out * 150.0 + up * 900.0, x);
    // The same camera behind the façade: the building hides the point.
    let hidden = oblique_looking_at("o1", x - out * 150.0 + up * 900.0, x);
    let truth_with = |img: &AerialImage| Truth {
        recordings: HashMap::from([("r1".to_string(), (rec.clone(), W, H))]),
        aerial: HashMap::from([("o1".to_string(), img.clone())]),
    };
    let truth = truth_with(&seeing);
    let (ou, ov) = FrameCamera::from_aerial(&seeing).project_world(&x).unwrap();
    let exact = pano_match(&rec, u, v, [ou, ov]);
    assert_eq!(
        grade_match(&truth, Some(&oracle), None, &exact),
        Some(Verdict::Correct)
    );
    let off = pano_match(&rec, u, v, [ou, ov + 3.0]);
    assert_eq!(
        grade_match(&truth, Some(&oracle), None, &off),
        Some(Verdict::Wrong)
    );
    // Looking straight up: sky, nothing to match.
    let sky = pano_match(&rec, u, 0.5, [ou, ov]);
    assert_eq!(
        grade_match(&truth, Some(&oracle), None, &sky),
        Some(Verdict::NonMatchable)
    );
    let truth = truth_with(&hidden);
    let (hu, hv) = FrameCamera::from_aerial(&hidden).project_world(&x).unwrap();
    assert_eq!(
        grade_match(
            &truth,
            Some(&oracle),
            None,
            &pano_match(&rec, u, v, [hu, hv])
        ),
        Some(Verdict::NonMatchable)
    );
}

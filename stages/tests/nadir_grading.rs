//! Known-answer test of the nadir truth grading (`nadir::grading`): a point seen exactly by two panoramas and
//! observed in two aerial images, once exactly and once 3 px off, gives one correct and one wrong
//! correspondence, the wrong one listed with its error and offset; correct observations and a control point that
//! are biased show their bias in the signed means.

use nalgebra::Vector3;
use skytie_stages::campaign::{AerialImage, AerialKind, Recording};
use skytie_stages::correspondence::{
    AerialControlPoint, AerialObservation, MmTiePoint, PanoObservation,
};
use skytie_stages::geometry::{FrameCamera, PanoramaCamera};
use skytie_stages::nadir::grading::{grade_nadir, Truth};
use skytie_stages::nadir::{AerialMatch, AerialRefinement};
use std::collections::HashMap;

const PANO_W: u32 = 4000;
const PANO_H: u32 = 2000;

fn recording(id: &str, x: f64, y: f64) -> Recording {
    Recording {
        time: "2020-01-01T00:00:00Z".into(),
        ..Recording::new(id, 0.0, [x, y, 2.4], 90.0, 2.4)
    }
}

fn nadir_camera(id: &str, x: f64) -> AerialImage {
    AerialImage::ideal(id, [x, 0.0, 450.0], [0.0, 0.0, 0.0], 4500.0, [2000, 2000])
}

/// A point seen exactly by two panoramas, its MM tie point, two nadir cameras and the truth of all of them.
struct Scene {
    point: Vector3<f64>,
    tie_point: MmTiePoint,
    cams: [AerialImage; 2],
    truth: Truth,
}

fn scene() -> Scene {
    let point = Vector3::new(4.0, 3.0, 0.0);
    let recs = [recording("r0", 0.0, 0.0), recording("r1", 5.0, 0.0)];
    let observations: Vec<PanoObservation> = recs
        .iter()
        .map(|r| {
            let (u, v) = PanoramaCamera::from_recording(r, PANO_W, PANO_H)
                .project_world(&point)
                .unwrap();
            PanoObservation {
                image_id: r.image_id.clone(),
                u_px: u,
                v_px: v,
            }
        })
        .collect();
    let tie_point = MmTiePoint {
        id: "r0#1".into(),
        observations,
        point_world: [point.x, point.y, point.z],
        covariance_m2: [[0.0; 3]; 3],
        max_angle_deg: 30.0,
    };
    let cams = [nadir_camera("a", -20.0), nadir_camera("b", 20.0)];
    let truth = Truth {
        recordings: recs
            .iter()
            .map(|r| (r.image_id.clone(), (r.clone(), PANO_W, PANO_H)))
            .collect(),
        aerial: cams
            .iter()
            .map(|c| (c.image_id.clone(), c.clone()))
            .collect::<HashMap<_, _>>(),
    };
    Scene {
        point,
        tie_point,
        cams,
        truth,
    }
}

impl Scene {
    /// The tie point located in `cam` at its true projection shifted by `shift_u` px.
    fn refinement(&self, cam: &AerialImage, shift_u: f64) -> AerialRefinement {
        let (u, v) = FrameCamera::from_aerial(cam)
            .project_world(&self.point)
            .unwrap();
        let mut r = AerialRefinement::empty("r0", &cam.image_id);
        r.tried = 1;
        r.matches.push(AerialMatch {
            tie_point_id: self.tie_point.id.clone(),
            observation: AerialObservation {
                image_id: cam.image_id.clone(),
                kind: AerialKind::Nadir,
                u_px: u + shift_u,
                v_px: v,
                score: 0.9,
                sigma_px: None,
            },
            predicted_u_px: u,
            predicted_v_px: v,
            level: 0,
            view_disagreement_px: None,
        });
        r
    }
}

#[test]
fn a_shifted_aerial_observation_is_graded_wrong_and_listed() {
    let sc = scene();
    let (tie_point, cams, truth) = (&sc.tie_point, &sc.cams, &sc.truth);
    let (exact, shifted) = (sc.refinement(&cams[0], 0.0), sc.refinement(&cams[1], 3.0));
    // The control point keeps only the exact observation (as if the consistency check had dropped the other).
    let control = AerialControlPoint {
        map: None,
        ray_ground: None,
        tie_point_id: tie_point.id.clone(),
        mm: tie_point.observations.clone(),
        aerial: vec![exact.matches[0].observation.clone()],
        point_world: None,
        covariance_m2: None,
    };
    let g = grade_nadir(truth, &[tie_point], &[&exact, &shifted], &[&control]);
    assert_eq!((g.delivered_tie_points, g.delivered_correct), (1, 1));
    assert_eq!(g.delivered_inlier_ratio(), 1.0);
    assert_eq!(g.control_points.count, 0, "no triangulated control point");
    assert_eq!((g.tie_points, g.correct_tie_points, g.ungraded), (2, 1, 0));
    assert_eq!((g.mm_tie_points, g.mm_tie_points_correct), (1, 1));
    assert!((g.inlier_ratio() - 0.5).abs() < 1e-12);
    assert_eq!(g.wrong.len(), 1);
    let w = &g.wrong[0];
    assert_eq!(
        (
            w.tie_point_id.as_str(),
            w.aerial_id.as_str(),
            w.aerial_images
        ),
        ("r0#1", "b", 2)
    );
    assert!((w.error_px - 3.0).abs() < 1e-6, "{w:?}");
    assert!(
        (w.offset_px[0] - 3.0).abs() < 1e-6 && w.offset_px[1].abs() < 1e-6,
        "{w:?}"
    );
    // Median, 90th percentile and largest error over the two graded correspondences.
    assert!((g.correspondence_error_px[2] - 3.0).abs() < 1e-6);
    assert!(g.correspondence_error_px[0] > 1.4 && g.correspondence_error_px[0] < 1.6);
    // The one correct correspondence is exact: no bias.
    assert_eq!(g.correct_mean_offset_px, [0.0, 0.0]);
}

#[test]
fn a_systematic_offset_shows_in_the_signed_means() {
    let sc = scene();
    // Both correspondences correct (within the tolerance), both biased to +u: 0.2 and 0.4 px.
    let (a, b) = (
        sc.refinement(&sc.cams[0], 0.2),
        sc.refinement(&sc.cams[1], 0.4),
    );
    // The control point triangulated 1 cm east, 2 cm south and 0.5 m above the true point.
    let p = sc.point + Vector3::new(0.01, -0.02, 0.5);
    let control = AerialControlPoint {
        map: None,
        ray_ground: None,
        tie_point_id: sc.tie_point.id.clone(),
        mm: sc.tie_point.observations.clone(),
        aerial: vec![
            a.matches[0].observation.clone(),
            b.matches[0].observation.clone(),
        ],
        point_world: Some([p.x, p.y, p.z]),
        covariance_m2: None,
    };
    let g = grade_nadir(&sc.truth, &[&sc.tie_point], &[&a, &b], &[&control]);
    assert_eq!((g.tie_points, g.correct_tie_points), (2, 2));
    let [du, dv] = g.correct_mean_offset_px;
    assert!((du - 0.3).abs() < 1e-6 && dv.abs() < 1e-6, "{du} {dv}");
    assert_eq!(g.control_points.count, 1);
    let [mx, my, mz] = g.control_points.mean_m;
    assert!((mx - 0.01).abs() < 1e-6 && (my + 0.02).abs() < 1e-6 && (mz - 0.5).abs() < 1e-6);
    // The medians are unsigned: the sign is only in the means.
    assert!((g.control_points.median_horizontal_m - 0.01f64.hypot(0.02)).abs() < 1e-6);
}

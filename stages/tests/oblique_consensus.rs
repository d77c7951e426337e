//! Known-answer tests of the oblique 3-D median consensus, consensus tracking and the oblique control points
//! (thesis 4.4.7), on registration sets built in code.

mod support;

use nalgebra::Vector3;
use skytie_stages::campaign::{AerialImage, Recording};
use skytie_stages::correspondence::{MmTiePoint, PanoObservation};
use skytie_stages::crs::MapFrame;
use skytie_stages::geometry::FrameCamera;
use skytie_stages::oblique::consensus::{
    consensus, consensus_with_diagnostics, ConsensusDiagnostics, ConsensusParams, SmallSetPolicy,
};
use skytie_stages::oblique::{
    ObliqueResult, PatchMatch, PatchRegistrationSet, PatchStats, SparseCloud, SparseCloudStats,
    SparsePoint, StreetSide,
};
use skytie_stages::params::Params;
use skytie_stages::rng::SplitMix64;
use support::{oblique_looking_at, street_recording, E0, N0};

fn patch_match(point_id: &str, object: [f64; 3], t: [f64; 3], oblique: &str) -> PatchMatch {
    PatchMatch {
        point_id: point_id.into(),
        side: StreetSide::Left,
        object_point_world: object,
        mm: PanoObservation {
            image_id: "r".into(),
            u_px: 100.0,
            v_px: 300.0,
        },
        oblique_image_id: oblique.into(),
        shift_plane_m: [0.0, 0.0],
        coarse_shift_plane_m: None,
        matched_point_world: [object[0] + t[0], object[1] + t[1], object[2] + t[2]],
        oblique_px: [0.0, 0.0],
        score: 0.5,
        real_resolution_ratio: 1.0,
        rejected_coarse: false,
        level: 0,
    }
}

fn set(recording: &str, oblique: &str, matches: Vec<PatchMatch>) -> PatchRegistrationSet {
    PatchRegistrationSet {
        recording: recording.into(),
        oblique_image_id: oblique.into(),
        matches,
        stats: PatchStats::default(),
    }
}

/// 20 matches with a common 0.8 m translation ± 5 cm noise and 5 outliers at 2 m from it.
fn constructed_set(recording: &str, seed: u64) -> (PatchRegistrationSet, Vec<bool>) {
    let mut rng = SplitMix64::new(seed);
    let common = [0.8, 0.1, -0.05];
    let mut matches = Vec::new();
    let mut good = Vec::new();
    for i in 0..25 {
        let object = [E0 + i as f64, N0 + 10.0, 105.0 + (i % 5) as f64];
        let t = if i % 5 == 2 {
            let a = i as f64 * 0.7;
            [
                common[0] + 2.0 * a.cos(),
                common[1] + 2.0 * a.sin(),
                common[2],
            ]
        } else {
            let mut n = || (rng.next_f64() - 0.5) * 0.1;
            [common[0] + n(), common[1] + n(), common[2] + n()]
        };
        good.push(i % 5 != 2);
        matches.push(patch_match(
            &format!("{recording}#left#{i}"),
            object,
            t,
            "o1",
        ));
    }
    (set(recording, "o1", matches), good)
}

/// The consensus with default parameters in Cartesian map coordinates, with its diagnostics.
fn consensus_by_default(
    sets: &[PatchRegistrationSet],
    clouds: &[SparseCloud],
    recordings: &[Recording],
    oblique: &[AerialImage],
) -> (ObliqueResult, ConsensusDiagnostics) {
    consensus_with_diagnostics(
        sets,
        clouds,
        recordings,
        oblique,
        &[],
        &ConsensusParams::default(),
        &MapFrame::Cartesian,
    )
}

#[test]
fn consensus_keeps_exactly_the_twenty_inliers() {
    let (s, good) = constructed_set("r1", 7);
    let recs = vec![street_recording("r1", 1, 102.0)];
    let p = ConsensusParams::default();
    let r = consensus(&[s], &[], &recs, &[], &[(1600, 800)], &p);
    let kept: Vec<bool> = r.correspondences.iter().map(|c| c.kept).collect();
    assert_eq!(kept, good);
    assert_eq!(r.stats.correspondences, 25);
    assert_eq!(r.stats.kept, 20);
    assert_eq!(r.stats.rejected, 5);
    assert_eq!(r.stats.recordings_with_correspondences, 1);
    for c in &r.correspondences {
        if c.kept {
            assert!(
                c.deviation_from_median_m < 0.15,
                "{}",
                c.deviation_from_median_m
            );
        } else {
            assert!(
                c.deviation_from_median_m > 1.5,
                "{}",
                c.deviation_from_median_m
            );
        }
    }
    // Tighter threshold (Table 4-8: 0.3 m) still keeps the 20 (noise ≤ ±5 cm per axis).
    let p3 = ConsensusParams {
        threshold_m: 0.3,
        ..ConsensusParams::default()
    };
    let (s, _) = constructed_set("r1", 7);
    assert_eq!(consensus(&[s], &[], &recs, &[], &[], &p3).stats.kept, 20);
}

#[test]
fn coarse_rejected_matches_do_not_enter() {
    let (mut s, _) = constructed_set("r1", 9);
    s.matches[0].rejected_coarse = true;
    s.matches[2].rejected_coarse = true; // an outlier
    let recs = vec![street_recording("r1", 1, 102.0)];
    let (r, d) = consensus_by_default(&[s], &[], &recs, &[]);
    assert_eq!(r.stats.correspondences, 23);
    assert_eq!(r.stats.kept, 19);
    assert_eq!(d.coarse_rejected, 2);
}

/// A set of 3 where 2 translations are wrong (and agree with each other), between two neighbours with 10
/// good ones each, all sharing the oblique image.
fn tracking_sets() -> Vec<PatchRegistrationSet> {
    let good = [0.8, 0.0, 0.0];
    let mk = |rec: &str, n: usize, wrong: usize| {
        let matches = (0..n)
            .map(|i| {
                let object = [E0 + i as f64, N0 + 10.0, 105.0];
                let d = 0.01 * i as f64;
                let t = if i < wrong {
                    [good[0] + 1.5 + d, good[1] - 1.0, good[2]]
                } else {
                    [good[0] + d, good[1] - d, good[2]]
                };
                patch_match(&format!("{rec}#left#{i}"), object, t, "o1")
            })
            .collect();
        set(rec, "o1", matches)
    };
    vec![mk("r1", 10, 0), mk("r2", 3, 2), mk("r3", 10, 0)]
}

#[test]
fn tracking_rescues_a_small_wrong_set_with_its_neighbours() {
    let sets = tracking_sets();
    let recs: Vec<Recording> = (1..=3)
        .map(|i| street_recording(&format!("r{i}"), i, 102.0))
        .collect();
    let kept_of = |r: &skytie_stages::oblique::ObliqueResult| -> Vec<bool> {
        r.correspondences
            .iter()
            .filter(|c| c.recording == "r2")
            .map(|c| c.kept)
            .collect()
    };
    // Without tracking the median of r2 sits on the two wrong translations.
    let alone = consensus(&sets, &[], &recs, &[], &[], &ConsensusParams::default());
    assert_eq!(kept_of(&alone), vec![true, true, false]);
    // With tracking the pooled median is the neighbours' one: the wrong two go, the good one stays.
    let p = ConsensusParams {
        tracking: true,
        ..ConsensusParams::default()
    };
    let tracked = consensus(&sets, &[], &recs, &[], &[], &p);
    assert_eq!(kept_of(&tracked), vec![false, false, true]);
    assert_eq!(tracked.stats.kept, 21);
    // A neighbour with another oblique image is not pooled.
    let mut other = tracking_sets();
    for s in other.iter_mut().filter(|s| s.recording != "r2") {
        s.oblique_image_id = "o2".into();
        for m in &mut s.matches {
            m.oblique_image_id = "o2".into();
        }
    }
    let r = consensus(&other, &[], &recs, &[], &[], &p);
    assert_eq!(kept_of(&r), vec![true, true, false]);
}

#[test]
fn small_sets_follow_the_policy_and_are_counted() {
    let (mut s, _) = constructed_set("r1", 3);
    s.matches.truncate(2);
    let recs = vec![street_recording("r1", 1, 102.0)];
    let keep = consensus(
        &[s.clone()],
        &[],
        &recs,
        &[],
        &[],
        &ConsensusParams::default(),
    );
    assert_eq!((keep.stats.small_sets, keep.stats.kept), (1, 2));
    let p = ConsensusParams {
        small_sets: SmallSetPolicy::Drop,
        ..ConsensusParams::default()
    };
    let drop = consensus(&[s], &[], &recs, &[], &[], &p);
    assert_eq!(
        (drop.stats.small_sets, drop.stats.kept, drop.stats.rejected),
        (1, 0, 2)
    );
}

#[test]
fn control_points_from_two_oblique_cameras_triangulate_to_under_a_millimetre() {
    let target = Vector3::new(E0 + 10.0, N0 + 12.0, 105.0);
    let images = vec![
        oblique_looking_at("oA", Vector3::new(E0 - 700.0, N0 + 12.0, 900.0), target),
        oblique_looking_at("oB", Vector3::new(E0 + 10.0, N0 + 800.0, 950.0), target),
    ];
    let cams: Vec<FrameCamera> = images.iter().map(FrameCamera::from_aerial).collect();
    // Three sparse points; their MM positions are off by the common 0.8 m error, the matches point at the
    // true points; each point matched in both images from panorama r1 (and point 0 again from r2 in oA,
    // with a lower score: a duplicate).
    let truths = [
        Vector3::new(E0 + 8.0, N0 + 12.0, 104.0),
        Vector3::new(E0 + 11.0, N0 + 12.5, 107.0),
        Vector3::new(E0 + 13.0, N0 + 11.8, 103.0),
    ];
    let mut cloud_points = Vec::new();
    let mut s1 = Vec::new();
    let mut s1b = Vec::new();
    let mut s2 = Vec::new();
    for (i, x) in truths.iter().enumerate() {
        let id = format!("r1#left#{i}");
        let object = [x.x - 0.8, x.y, x.z];
        for (cam, img, out) in [(&cams[0], "oA", &mut s1), (&cams[1], "oB", &mut s1b)] {
            let (u, v) = cam.project_world(x).unwrap();
            let mut m = patch_match(&id, object, [0.8, 0.0, 0.0], img);
            m.oblique_px = [u, v];
            out.push(m);
        }
        if i == 0 {
            let mut m = patch_match(&id, object, [0.8, 0.0, 0.0], "oA");
            m.oblique_px = [5.0, 5.0]; // wrong, but lower score: must not be used
            m.score = 0.1;
            s2.push(m);
        }
        cloud_points.push(SparsePoint {
            side: StreetSide::Left,
            tie: MmTiePoint {
                id: id.clone(),
                observations: vec![
                    PanoObservation {
                        image_id: "r0".into(),
                        u_px: 1.0 + i as f64,
                        v_px: 2.0,
                    },
                    PanoObservation {
                        image_id: "r1".into(),
                        u_px: 3.0,
                        v_px: 4.0,
                    },
                ],
                point_world: object,
                covariance_m2: [[0.0; 3]; 3],
                max_angle_deg: 10.0,
            },
        });
    }
    let clouds = vec![SparseCloud {
        recordings: ["r0".into(), "r1".into(), "r2".into()],
        points: cloud_points,
        stats: SparseCloudStats::default(),
    }];
    let sets = vec![
        set("r1", "oA", s1),
        set("r1", "oB", s1b),
        set("r2", "oA", s2),
    ];
    let recs: Vec<Recording> = (0..3)
        .map(|i| street_recording(&format!("r{i}"), i, 102.0))
        .collect();
    let (r, d) = consensus_by_default(&sets, &clouds, &recs, &images);
    assert_eq!(r.stats.kept, 7);
    assert_eq!(d.duplicate_observations, 1);
    assert_eq!(r.control.len(), 3);
    assert_eq!(r.stats.control_points, 3);
    for (c, x) in r.control.iter().zip(&truths) {
        assert_eq!(c.aerial.len(), 2);
        assert_eq!(c.mm.len(), 2, "all panorama observations of the tie point");
        let p = c.point_world.expect("triangulated");
        let err = (Vector3::new(p[0], p[1], p[2]) - x).norm();
        assert!(err < 1e-3, "{} error {err} m", c.tie_point_id);
        let cov = c.covariance_m2.unwrap();
        assert!(cov[0][0] > 0.0 && cov[0][0] < 0.1);
    }
    // One oblique image only: a single-image point without coordinates.
    let (r, _) = consensus_by_default(&sets[..1], &clouds, &recs, &images);
    assert_eq!(
        (r.stats.control_points, r.stats.single_image_points),
        (0, 3)
    );
    assert!(r.control.iter().all(|c| c.point_world.is_none()));
}

#[test]
fn invalid_params_are_reported() {
    let p = ConsensusParams {
        threshold_m: -1.0,
        min_set_size: 0,
        ..ConsensusParams::default()
    };
    let e = p.validate().unwrap_err();
    let fields: Vec<&str> = e.iter().map(|v| v.field.as_str()).collect();
    assert_eq!(fields, vec!["threshold_m", "min_set_size"]);
    assert!(ConsensusParams::default().validate().is_ok());
}

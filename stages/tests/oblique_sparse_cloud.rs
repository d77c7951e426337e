//! Tests of the sparse cloud of panorama triplets (thesis 4.4.1) on a synthetic Tiny campaign generated once
//! into a temporary folder. A point is *correct* when its observations, triangulated with the TRUE poses
//! (`truth/recordings.csv`, read by the test only), have rays that meet within `RAYS_MEET_M`, and the true-pose
//! point lies within `SCENE_TOL_M` of the synthetic scene surface hit by the centre panorama's ray.
//!
//! `demo_report` (ignored; `SKYTIE_DEMO=/work/data/demo cargo test --release -p skytie-stages --test
//! oblique_sparse_cloud -- --ignored --nocapture`) prints points and time per triplet for a campaign folder.

mod support;

use skytie_stages::campaign::Recording;
use skytie_stages::imaging::equirect::PanoramaLevels;
use skytie_stages::oblique::sparse_cloud::{sparse_cloud, SparseCloudParams};
use skytie_stages::oblique::{SparseCloud, StreetSide};
use skytie_stages::params::Params;
use skytie_stages::synth::scene::{Epoch, Scene};
use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;
use support::tiny::{fixture, load_campaign, true_rays, Campaign, TrueRays};

/// True-pose rays of a correct point meet within this distance, m.
const RAYS_MEET_M: f64 = 0.15;
/// A correct true-pose point lies this close to the scene surface seen by the centre ray, m.
const SCENE_TOL_M: f64 = 0.15;

fn clouds(c: &Campaign, p: &SparseCloudParams) -> Vec<SparseCloud> {
    (1..c.recorded.len().saturating_sub(1))
        .map(|i| {
            let recs = [&c.recorded[i - 1], &c.recorded[i], &c.recorded[i + 1]];
            let levels: Vec<PanoramaLevels> = (i - 1..=i + 1)
                .map(|k| PanoramaLevels::from_image(&c.panoramas[k], 3))
                .collect();
            sparse_cloud(recs, [&levels[0], &levels[1], &levels[2]], p)
        })
        .collect()
}

/// (true-pose rays meet, true-pose point near the scene surface) for one point.
fn grade(
    tie: &skytie_stages::correspondence::MmTiePoint,
    centre: &str,
    truth: &HashMap<String, Recording>,
    scene: Option<&Scene>,
    pano: (u32, u32),
) -> (bool, Option<bool>) {
    let TrueRays {
        rays,
        triangulation,
        ..
    } = true_rays(tie, truth, pano);
    let Ok(t) = triangulation else {
        return (false, Some(false));
    };
    let meet = t.residuals_m.iter().all(|&r| r <= RAYS_MEET_M);
    let on_scene = scene.map(|s| {
        let k = tie
            .observations
            .iter()
            .position(|o| o.image_id == centre)
            .unwrap_or(0);
        s.first_hit(
            &rays[k].origin_world,
            &rays[k].dir_world,
            Epoch::MobileMapping,
        )
        .is_some_and(|hit| (hit.point_world - t.point_world).norm() <= SCENE_TOL_M)
    });
    (meet, on_scene)
}

#[test]
fn tiny_triplets_with_true_poses_give_correct_points() {
    let f = fixture();
    let c = &f.campaign;
    let pano = (c.panoramas[0].width as u32, c.panoramas[0].height as u32);
    let p = SparseCloudParams::default();
    assert_eq!(p.validate(), Ok(()));
    // Recorded (deteriorated) poses: counts only, for the report.
    for cloud in clouds(c, &p) {
        eprintln!("recorded poses {} {:?}", cloud.centre(), cloud.stats);
    }
    // The issue's rule: the sparse cloud computed with the TRUE poses.
    let true_campaign = Campaign {
        recorded: c
            .recorded
            .iter()
            .map(|r| c.truth[&r.image_id].clone())
            .collect(),
        truth: c.truth.clone(),
        panoramas: c.panoramas.clone(),
    };
    let start = Instant::now();
    let all = clouds(&true_campaign, &p);
    let secs = start.elapsed().as_secs_f64();
    let (mut total, mut meet, mut scene_ok) = (0usize, 0usize, 0usize);
    let mut per_side = [0usize; 2];
    for cloud in &all {
        eprintln!("{} {:?}", cloud.centre(), cloud.stats);
        assert_eq!(cloud.stats.points, cloud.points.len());
        assert_eq!(cloud.stats.views, 6);
        assert_eq!(
            cloud.stats.tracks,
            cloud.stats.rejected_trifocal + cloud.stats.rejected_triangulation + cloud.points.len()
        );
        for (i, sp) in cloud.points.iter().enumerate() {
            let tag = if sp.side == StreetSide::Left {
                "l"
            } else {
                "r"
            };
            assert!(sp.tie.id.starts_with(&format!("{}#{tag}#", cloud.centre())));
            assert!(sp.tie.observations.len() >= 2, "point {i}");
            let order: Vec<usize> = sp
                .tie
                .observations
                .iter()
                .map(|o| {
                    cloud
                        .recordings
                        .iter()
                        .position(|r| *r == o.image_id)
                        .unwrap()
                })
                .collect();
            assert!(order.windows(2).all(|w| w[0] < w[1]), "trajectory order");
            per_side[(sp.side == StreetSide::Right) as usize] += 1;
            let (m, s) = grade(&sp.tie, cloud.centre(), &c.truth, Some(&f.scene), pano);
            total += 1;
            meet += m as usize;
            scene_ok += s.unwrap_or(false) as usize;
        }
    }
    let meet_frac = meet as f64 / total.max(1) as f64;
    let scene_frac = scene_ok as f64 / total.max(1) as f64;
    eprintln!(
        "{} triplets in {secs:.2} s: {total} points (left {}, right {}), true-pose rays meet within {RAYS_MEET_M} m: {:.1} %, on the scene within {SCENE_TOL_M} m: {:.1} %",
        all.len(),
        per_side[0],
        per_side[1],
        100.0 * meet_frac,
        100.0 * scene_frac
    );
    assert!(total >= 20, "{total}");
    assert!(meet_frac >= 0.9, "{meet_frac}");
    assert!(scene_frac >= 0.8, "{scene_frac}");
}

/// Both sides of the tiny street (façades along the whole route on either side) give façade points. A stated
/// limitation, not a bar: with the default matching (ratio 0.8, mutual) only about one corner in ten per view
/// finds its partner, so a triplet holds a handful of points (demo seed 1: 235 points in 37 triplets, 6.4 per
/// triplet for both sides together); tiny's four triplets give tens of points, unevenly per side (seed 1: 10
/// left, 4 right). What the user sees of a weak side is the per-side report of the oblique chain
/// (`oblique.sides.{left,right}.correspondences` in metrics.json, asserted in `tests/pipeline_tiny.rs`).
#[test]
fn tiny_triplets_give_points_on_both_sides() {
    let f = fixture();
    let c = &f.campaign;
    let all = clouds(c, &SparseCloudParams::default());
    let mut per_side = [0usize; 2];
    for cloud in &all {
        for sp in &cloud.points {
            per_side[(sp.side == StreetSide::Right) as usize] += 1;
        }
    }
    eprintln!("points per side (left, right): {per_side:?}");
    assert!(per_side[0] >= 3 && per_side[1] >= 3, "{per_side:?}");
    assert!(
        per_side[0] + per_side[1] >= 10,
        "{per_side:?} in {} triplets: fewer than tens of points",
        all.len()
    );
}

#[test]
fn sparse_cloud_is_deterministic() {
    let c = &fixture().campaign;
    let p = SparseCloudParams::default();
    let recs = [&c.recorded[0], &c.recorded[1], &c.recorded[2]];
    let levels: Vec<PanoramaLevels> = (0..3)
        .map(|k| PanoramaLevels::from_image(&c.panoramas[k], 3))
        .collect();
    let panos = [&levels[0], &levels[1], &levels[2]];
    let a = sparse_cloud(recs, panos, &p);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(|| sparse_cloud(recs, panos, &p));
    assert_eq!(a, b);
}

#[test]
#[ignore]
fn demo_report() {
    let root = std::env::var("SKYTIE_DEMO").unwrap_or_else(|_| "/work/data/demo".into());
    let c = load_campaign(Path::new(&root));
    let pano = (c.panoramas[0].width as u32, c.panoramas[0].height as u32);
    let p = SparseCloudParams::default();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let start = Instant::now();
    let all = pool.install(|| clouds(&c, &p));
    let secs = start.elapsed().as_secs_f64();
    let (mut total, mut meet) = (0usize, 0usize);
    let mut counts = Vec::new();
    for cloud in &all {
        counts.push(cloud.points.len());
        for sp in &cloud.points {
            total += 1;
            meet += grade(&sp.tie, cloud.centre(), &c.truth, None, pano).0 as usize;
        }
    }
    counts.sort_unstable();
    let n = all.len().max(1);
    eprintln!(
        "demo: {} triplets, {:.3} s per triplet (1 thread), points per triplet min {} median {} max {}, total {total}, true-pose rays meet within {RAYS_MEET_M} m: {:.1} %",
        all.len(),
        secs / n as f64,
        counts.first().copied().unwrap_or(0),
        counts.get(counts.len() / 2).copied().unwrap_or(0),
        counts.last().copied().unwrap_or(0),
        100.0 * meet as f64 / total.max(1) as f64
    );
}

/// Outer recordings off by decimetres relative to the centre (a GNSS outage between them): the relative
/// positions measured from the triplet's tracks restore the cloud that the recorded ones lose at the
/// trifocal check, and the measured baselines point where the true ones do.
#[test]
fn relative_positions_off_by_decimetres_are_measured_from_the_tracks() {
    let f = fixture();
    let c = &f.campaign;
    let pano = (c.panoramas[0].width as u32, c.panoramas[0].height as u32);
    let truth: Vec<Recording> = c
        .recorded
        .iter()
        .map(|r| c.truth[&r.image_id].clone())
        .collect();
    let offsets_m = [[0.35, -0.25, 0.0], [0.0, 0.0, 0.0], [-0.30, 0.20, 0.05]];
    let recorded: Vec<Recording> = truth
        .iter()
        .take(3)
        .zip(offsets_m)
        .map(|(r, o)| Recording {
            x: r.x + o[0],
            y: r.y + o[1],
            z: r.z + o[2],
            ..r.clone()
        })
        .collect();
    let levels: Vec<PanoramaLevels> = (0..3)
        .map(|k| PanoramaLevels::from_image(&c.panoramas[k], 3))
        .collect();
    let panos = [&levels[0], &levels[1], &levels[2]];
    let run = |recs: &[Recording], measured: bool| {
        let p = SparseCloudParams {
            relative_pose: measured,
            ..SparseCloudParams::default()
        };
        sparse_cloud([&recs[0], &recs[1], &recs[2]], panos, &p)
    };
    let exact = run(&truth, false);
    let kept = run(&recorded, false);
    let measured = run(&recorded, true);
    eprintln!(
        "points: true poses {}, recorded kept {}, recorded measured {} ({:?})",
        exact.points.len(),
        kept.points.len(),
        measured.points.len(),
        measured.stats
    );
    assert_eq!(measured.stats.pose_corrected, 1);
    assert!(
        measured.points.len() as f64 >= 0.8 * exact.points.len() as f64,
        "{} of {}",
        measured.points.len(),
        exact.points.len()
    );
    assert!(measured.points.len() >= 2 * kept.points.len().max(1));
    // The points are right by the truth.
    let correct = measured
        .points
        .iter()
        .filter(|sp| grade(&sp.tie, measured.centre(), &c.truth, None, pano).0)
        .count();
    assert!(correct as f64 >= 0.9 * measured.points.len() as f64);
    // The measured positions put each outer recording in the true direction from the centre (the triplet's
    // scale, along the baselines, is what the prior holds): within 0.2° (a third of a view pixel).
    let corr = measured.stats.pose_corrections_m;
    let from_centre = |r: &Recording, d: [f64; 3]| {
        nalgebra::Vector3::new(
            r.x + d[0] - truth[1].x,
            r.y + d[1] - truth[1].y,
            r.z + d[2] - truth[1].z,
        )
    };
    for k in [0, 2] {
        let tru = from_centre(&truth[k], [0.0; 3]);
        let angle_deg = |v: nalgebra::Vector3<f64>| v.angle(&tru).to_degrees();
        let before = angle_deg(from_centre(&recorded[k], [0.0; 3]));
        let after = angle_deg(from_centre(&recorded[k], corr[k]));
        eprintln!("recording {k}: baseline direction {before:.2}° off as recorded, {after:.3}° as measured");
        assert!(after < 0.2, "{k}: {after}°");
    }
}

//! Known-answer tests of the initial MM→aerial transform (thesis 3.4.5.2) and its helpers (aerial overlap, aerial
//! ortho parameters, aerial patch):
//! - a rendered ground pattern seen by a κ = 30° aerial camera: the ortho made with `ortho_params_for_aerial` agrees
//!   with the aerial image up to translation, and `initial_transform` recovers a known position error;
//! - a generated tiny synthetic campaign (deteriorated by 0.8 m + noise): every accepted transform maps true ground
//!   points to their true aerial projection within the refinement's capture range (median about one aerial pixel),
//!   and its centre offset reproduces the recording's position error; a recording shifted further is rejected
//!   (plausibility; a chance consensus by the a-contrario test), a blank aerial image is rejected with a reason;
//! - `#[ignore]` demo statistics: `SKYTIE_DEMO=/work/data/demo cargo test --release --test nadir_initial_transform
//!   -- --ignored --nocapture`.
//!
//! RANSAC similarity with 50 % outliers is covered by `estimators::tests::ransac_similarity_tests`.

use nalgebra::Vector2;
use skytie_stages::campaign::{
    read_campaign, read_recordings_csv, AerialImage, Campaign, Recording,
};
use skytie_stages::estimators::SplitMix64;
use skytie_stages::geometry::{intersect_ray_plane, FrameCamera, Plane, PointPair, Similarity2};
use skytie_stages::imaging::io::load_gray;
use skytie_stages::imaging::pyramid::MemoryPyramid;
use skytie_stages::imaging::GrayImage;
use skytie_stages::nadir::aerial_overlap::{foot_point_world, overlapping_nadir};
use skytie_stages::nadir::aerial_patch::ortho_params_for_aerial;
use skytie_stages::nadir::initial_transform::{
    centre_offset_world, initial_transform, TransformParams,
};
use skytie_stages::nadir::neighbour_transform::reuse_neighbour;
use skytie_stages::nadir::refine::RefineParams;
use skytie_stages::nadir::transform_agreement::check_agreement;
use skytie_stages::nadir::{
    ortho_project_whole, OrthoGeoref, OrthoImage, OrthoParams, TransformOutcome,
};
use skytie_stages::params::Params;
use skytie_stages::synth::{generate, Preset, SynthOptions};
use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

// ---------------------------------------------------------------------------------------------------------------
// A synthetic ground pattern and an aerial camera looking at it.

/// Random Gaussian blobs on a grey ground: f(E, N) in 0..1.
struct BlobPattern {
    blobs: Vec<(f64, f64, f64, f64)>, // (east, north, sigma_m, amplitude)
}

impl BlobPattern {
    fn new(centre: [f64; 2], half_side_m: f64, count: usize, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let blobs = (0..count)
            .map(|_| {
                let e = centre[0] + (rng.next_f64() * 2.0 - 1.0) * half_side_m;
                let n = centre[1] + (rng.next_f64() * 2.0 - 1.0) * half_side_m;
                let sigma = 0.25 + 0.35 * rng.next_f64();
                let amp =
                    if rng.next_f64() < 0.5 { -0.35 } else { 0.35 } * (0.5 + 0.5 * rng.next_f64());
                (e, n, sigma, amp)
            })
            .collect();
        Self { blobs }
    }

    fn value(&self, e: f64, n: f64) -> f32 {
        let mut g = 0.5;
        for &(be, bn, s, a) in &self.blobs {
            let d2 = (e - be).powi(2) + (n - bn).powi(2);
            if d2 < 16.0 * s * s {
                g += a * (-d2 / (2.0 * s * s)).exp();
            }
        }
        g.clamp(0.0, 1.0) as f32
    }
}

fn aerial_row(kappa_deg: f64, omega_deg: f64, phi_deg: f64) -> AerialImage {
    AerialImage::ideal(
        "nadir_test",
        [100_000.0, 400_000.0, 4470.0 + 1.2],
        [omega_deg, phi_deg, kappa_deg],
        44_700.0,
        [512, 384],
    )
}

/// The aerial image of the pattern on the plane z = `ground_z` (one ray per pixel centre).
fn render_aerial(cam: &FrameCamera, pattern: &BlobPattern, ground_z: f64) -> GrayImage {
    let (w, h) = (cam.width_px as usize, cam.height_px as usize);
    let plane = Plane::horizontal(ground_z);
    let mut img = GrayImage::filled(w, h, 0.5);
    for row in 0..h {
        for col in 0..w {
            if let Some(p) =
                intersect_ray_plane(&cam.pixel_ray(col as f64 + 0.5, row as f64 + 0.5), &plane)
            {
                img.set(col, row, pattern.value(p.x, p.y));
            }
        }
    }
    img
}

/// An ortho image with georeference `georef` whose pixels show the pattern at `true_georef`'s world points (a
/// recording whose recorded position is off by `georef.foot − true_georef.foot`).
fn render_ortho(
    georef: &OrthoGeoref,
    true_georef: &OrthoGeoref,
    pattern: &BlobPattern,
) -> OrthoImage {
    let (w, h) = (georef.width_px, georef.height_px);
    let mut image = GrayImage::filled(w, h, 0.0);
    for row in 0..h {
        for col in 0..w {
            let p = true_georef.pixel_to_world(col as f64 + 0.5, row as f64 + 0.5);
            image.set(col, row, pattern.value(p.x, p.y));
        }
    }
    OrthoImage {
        image,
        valid: vec![1; w * h],
        georef: georef.clone(),
    }
}

fn recording_at(id: &str, foot: [f64; 3], camera_height_m: f64) -> Recording {
    Recording {
        time: "2020-01-01T00:00:00Z".into(),
        ..Recording::new(
            id,
            0.0,
            [foot[0], foot[1], foot[2] + camera_height_m],
            30.0,
            camera_height_m,
        )
    }
}

fn accepted(outcome: &TransformOutcome) -> &skytie_stages::nadir::InitialTransform {
    match outcome {
        TransformOutcome::Accepted(t) => t,
        TransformOutcome::Rejected { reason, .. } => panic!("rejected: {reason}"),
    }
}

/// The point on the horizontal plane z = `ground_z` seen at aerial pixel (u, v).
fn ground_at(cam: &FrameCamera, u_px: f64, v_px: f64, ground_z: f64) -> [f64; 3] {
    let p = intersect_ray_plane(&cam.pixel_ray(u_px, v_px), &Plane::horizontal(ground_z)).unwrap();
    [p.x, p.y, ground_z]
}

fn rotation_error_deg(s: &Similarity2) -> f64 {
    s.rotation_rad.to_degrees().abs()
}

#[test]
fn ortho_params_align_ortho_and_aerial_axes_for_kappa_30() {
    let row = aerial_row(30.0, 0.1, -0.08);
    let cam = FrameCamera::from_aerial(&row);
    // The foot point on the ground 60 px right of and 40 px above the principal point.
    let foot = ground_at(&cam, 316.0, 152.0, 0.0);
    let params = ortho_params_for_aerial(&cam, foot, &OrthoParams::default());
    let georef = OrthoGeoref::new(foot, &params);
    // Geometry: ortho pixels → world → aerial pixels is a pure translation (least squares over a 21 × 21 grid).
    let mut pairs = Vec::new();
    for i in 0..=20 {
        for j in 0..=20 {
            let (x, y) = (
                georef.width_px as f64 * i as f64 / 20.0,
                georef.height_px as f64 * j as f64 / 20.0,
            );
            let (u, v) = cam.project_world(&georef.pixel_to_world(x, y)).unwrap();
            pairs.push(PointPair::new(x, y, u, v));
        }
    }
    let fit = Similarity2::least_squares(&pairs).unwrap();
    assert!(
        rotation_error_deg(&fit) < 0.1,
        "rotation {} deg",
        fit.rotation_rad.to_degrees()
    );
    assert!((fit.scale - 1.0).abs() < 0.005, "scale {}", fit.scale);
    let worst = pairs
        .iter()
        .map(|p| fit.transfer_error(p))
        .fold(0.0, f64::max);
    assert!(
        worst < 0.1,
        "a similarity explains the mapping to {worst} px"
    );

    // Images: KAZE + RANSAC between the ortho of a pattern and the aerial image of it (no position error).
    let pattern = BlobPattern::new([foot[0], foot[1]], 20.0, 900, 7);
    let aerial = render_aerial(&cam, &pattern, foot[2]);
    let ortho = render_ortho(&georef, &georef, &pattern);
    let rec = recording_at("pattern", foot, 2.2);
    let p = TransformParams::default();
    let t = accepted(
        &initial_transform(&rec, &ortho, &MemoryPyramid::from_gray(&aerial), &row, &p).unwrap(),
    )
    .clone();
    assert!(
        rotation_error_deg(&t.ortho_to_aerial) < 0.1,
        "image rotation {} deg",
        t.ortho_to_aerial.rotation_rad.to_degrees()
    );
    assert!(
        (t.ortho_to_aerial.scale - 1.0).abs() < 0.005,
        "image scale {}",
        t.ortho_to_aerial.scale
    );
    assert!(
        t.centre_offset_m < 0.05,
        "centre offset {} m",
        t.centre_offset_m
    );
    assert!(t.inliers >= 20, "{} inliers", t.inliers);
}

#[test]
fn recovers_a_known_position_error_and_rejects_implausible_offsets() {
    let row = aerial_row(-90.0, 0.1, 0.15);
    let cam = FrameCamera::from_aerial(&row);
    let true_foot = ground_at(&cam, 226.0, 242.0, 0.0);
    let params = ortho_params_for_aerial(&cam, true_foot, &OrthoParams::default());
    let pattern = BlobPattern::new([true_foot[0], true_foot[1]], 20.0, 900, 11);
    let aerial = render_aerial(&cam, &pattern, true_foot[2]);
    let true_georef = OrthoGeoref::new(true_foot, &params);
    let p = TransformParams::default();
    let run = |error: [f64; 2]| {
        let recorded = [
            true_foot[0] + error[0],
            true_foot[1] + error[1],
            true_foot[2],
        ];
        let georef = OrthoGeoref::new(recorded, &params);
        let ortho = render_ortho(&georef, &true_georef, &pattern);
        let rec = recording_at("r", recorded, 2.2);
        (
            initial_transform(&rec, &ortho, &MemoryPyramid::from_gray(&aerial), &row, &p).unwrap(),
            georef,
        )
    };

    // 0.8 m error: accepted, and the centre offset is the correction (true − recorded).
    let error = [0.65, -0.47];
    let (outcome, georef) = run(error);
    let t = accepted(&outcome).clone();
    let offset = centre_offset_world(&t.ortho_to_aerial, &georef, &cam).unwrap();
    assert!(
        (offset[0] + error[0]).abs() < 0.03 && (offset[1] + error[1]).abs() < 0.03,
        "offset {offset:?}"
    );
    assert!((t.centre_offset_m - error[0].hypot(error[1])).abs() < 0.03);
    // Every ortho pixel maps to the aerial projection of the ground point it shows.
    for &(x, y) in &[(10.0, 10.0), (100.0, 30.0), (200.0, 200.0), (50.0, 170.0)] {
        let a = t.ortho_to_aerial.apply(&Vector2::new(x, y));
        let (u, v) = cam
            .project_world(&true_georef.pixel_to_world(x, y))
            .unwrap();
        assert!(
            (a.x - u).hypot(a.y - v) < 0.3,
            "({x}, {y}) → {a:?}, truth ({u}, {v})"
        );
    }

    // Reusing this transform for a neighbour 5 m further along (same position error) gives the same correction.
    let neighbour_true = [true_foot[0] + 4.0, true_foot[1] + 3.0, true_foot[2]];
    let neighbour_recorded = [
        neighbour_true[0] + error[0],
        neighbour_true[1] + error[1],
        neighbour_true[2],
    ];
    let n_georef = OrthoGeoref::new(neighbour_recorded, &params);
    let n_rec = recording_at("n", neighbour_recorded, 2.2);
    let reused = reuse_neighbour(&t, &georef, &n_rec, &n_georef, &row, &p);
    let r = accepted(&reused);
    assert_eq!(r.reused_from.as_deref(), Some("r"));
    let n_offset = centre_offset_world(&r.ortho_to_aerial, &n_georef, &cam).unwrap();
    assert!(
        (n_offset[0] + error[0]).abs() < 0.03 && (n_offset[1] + error[1]).abs() < 0.03,
        "{n_offset:?}"
    );

    // 1.3 m per axis: the true partners lie inside the ±1.5 m windows, but the centre is 1.84 m off.
    let (outcome, _) = run([1.3, 1.3]);
    match outcome {
        TransformOutcome::Rejected {
            reason, inliers, ..
        } => {
            assert!(reason.contains("centre offset"), "{reason}");
            assert!(inliers >= p.min_inliers);
        }
        TransformOutcome::Accepted(t) => panic!("accepted with offset {} m", t.centre_offset_m),
    }
    // 3 m: rejected, with a reason.
    let (outcome, _) = run([3.0, 0.0]);
    assert!(
        matches!(outcome, TransformOutcome::Rejected { ref reason, .. } if !reason.is_empty()),
        "{outcome:?}"
    );
}

#[test]
fn blank_or_mismatched_aerial_is_rejected_with_a_reason() {
    let row = aerial_row(0.0, 0.0, 0.0);
    let cam = FrameCamera::from_aerial(&row);
    let foot = ground_at(&cam, 256.0, 192.0, 0.0);
    let params = ortho_params_for_aerial(&cam, foot, &OrthoParams::default());
    let georef = OrthoGeoref::new(foot, &params);
    let pattern = BlobPattern::new([foot[0], foot[1]], 20.0, 900, 3);
    let ortho = render_ortho(&georef, &georef, &pattern);
    let rec = recording_at("r", foot, 2.2);
    let p = TransformParams::default();
    let blank = GrayImage::filled(512, 384, 0.4);
    match initial_transform(&rec, &ortho, &MemoryPyramid::from_gray(&blank), &row, &p).unwrap() {
        TransformOutcome::Rejected { reason, .. } => assert!(
            reason.contains("no KAZE keypoints in the aerial patch"),
            "{reason}"
        ),
        other => panic!("{other:?}"),
    }
    let wrong_size = GrayImage::filled(100, 50, 0.4);
    match initial_transform(
        &rec,
        &ortho,
        &MemoryPyramid::from_gray(&wrong_size),
        &row,
        &p,
    )
    .unwrap()
    {
        TransformOutcome::Rejected { reason, .. } => assert!(reason.contains("100×50"), "{reason}"),
        other => panic!("{other:?}"),
    }
    let far = recording_at("far", [foot[0] + 500.0, foot[1], 0.0], 2.2);
    let far_ortho = OrthoImage {
        georef: OrthoGeoref::new(foot_point_world(&far), &params),
        ..ortho.clone()
    };
    match initial_transform(
        &far,
        &far_ortho,
        &MemoryPyramid::from_gray(&render_aerial(&cam, &pattern, 0.0)),
        &row,
        &p,
    )
    .unwrap()
    {
        TransformOutcome::Rejected { reason, .. } => {
            assert!(reason.contains("does not overlap"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
    let bad = TransformParams {
        max_localisation_error_m: -1.0,
        ..p.clone()
    };
    let errs = bad.validate().unwrap_err();
    assert_eq!(errs[0].field, "max_localisation_error_m");
    let parsed: Result<TransformParams, _> = toml::from_str("max_localisation_error = 2.0");
    assert!(parsed.is_err(), "unknown fields are refused");
    let parsed: TransformParams = toml::from_str("max_localisation_error_m = 2.0").unwrap();
    assert_eq!(parsed.max_localisation_error_m, 2.0);
    assert_eq!(parsed.min_inliers, p.min_inliers);
}

// ---------------------------------------------------------------------------------------------------------------
// Synthetic campaigns.

/// Statistics of the initial transforms over a campaign, graded with the truth poses.
#[derive(Default, Debug)]
struct CampaignStats {
    pairs: usize,
    accepted: usize,
    recordings: usize,
    recordings_with_accepted: usize,
    /// Per accepted transform: max over the test ground points of |estimated − true aerial px|.
    max_point_error_px: Vec<f64>,
    /// Per accepted transform: |centre offset + (recorded − true)|, metres.
    offset_error_m: Vec<f64>,
    /// Per accepted transform: the estimated offset (east, north), metres.
    offsets: Vec<[f64; 2]>,
    seconds_per_pair: Vec<f64>,
    reasons: HashMap<String, usize>,
}

fn summarise(name: &str, v: &[f64]) -> String {
    if v.is_empty() {
        return format!("{name}: none");
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let rms = (s.iter().map(|x| x * x).sum::<f64>() / s.len() as f64).sqrt();
    format!(
        "{name}: n {} median {:.3} rms {:.3} p90 {:.3} max {:.3}",
        s.len(),
        s[s.len() / 2],
        rms,
        s[(s.len() * 9 / 10).min(s.len() - 1)],
        s[s.len() - 1]
    )
}

/// Runs `initial_transform` for every (recording, overlapping nadir image) of the campaign at `root`, then the
/// agreement check across each recording's images, and grades the accepted transforms with
/// `truth/recordings.csv`.
fn evaluate_campaign(root: &Path, p: &TransformParams) -> CampaignStats {
    let (campaign, problems): (Campaign, _) = read_campaign(root).unwrap();
    assert!(problems.iter().all(|pr| !pr.is_error()), "{problems:?}");
    let (truth, _) = read_recordings_csv(&root.join("truth/recordings.csv"));
    let truth: HashMap<&str, &Recording> = truth.iter().map(|r| (r.image_id.as_str(), r)).collect();
    let aerials: Vec<GrayImage> = campaign
        .nadir
        .iter()
        .map(|a| load_gray(&root.join("aerial/nadir").join(&a.file)).unwrap())
        .collect();
    let mut stats = CampaignStats::default();
    for rec in &campaign.recordings {
        stats.recordings += 1;
        let true_rec = truth[rec.image_id.as_str()];
        let pano = load_gray(&root.join("mm/panoramas").join(&rec.file)).unwrap();
        let foot = foot_point_world(rec);
        let true_foot = foot_point_world(true_rec);
        let error = [rec.x - true_rec.x, rec.y - true_rec.y];
        let mut any = false;
        // Every overlapping image's transform first, then the agreement check across them (as the pipeline's
        // `transform_agreement` does): a transform one period of a zebra off is rejected there.
        let mut runs = Vec::new();
        for i in overlapping_nadir(rec, &campaign.nadir, p.max_localisation_error_m) {
            let row = &campaign.nadir[i];
            let cam = FrameCamera::from_aerial(row);
            let params = ortho_params_for_aerial(&cam, foot, &OrthoParams::default());
            let ortho = ortho_project_whole(&pano, rec, &params);
            let start = Instant::now();
            let outcome =
                initial_transform(rec, &ortho, &MemoryPyramid::from_gray(&aerials[i]), row, p)
                    .unwrap();
            stats.seconds_per_pair.push(start.elapsed().as_secs_f64());
            runs.push((cam, params, ortho, outcome));
        }
        let outcomes: Vec<&TransformOutcome> = runs.iter().map(|r| &r.3).collect();
        for (k, (cam, params, ortho, outcome)) in runs.iter().enumerate() {
            let others: Vec<&TransformOutcome> = outcomes
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != k)
                .map(|(_, o)| *o)
                .collect();
            stats.pairs += 1;
            let t = match check_agreement(outcome, &others, p.max_offset_disagreement_m) {
                TransformOutcome::Accepted(t) => t,
                TransformOutcome::Rejected { reason, .. } => {
                    // Group reasons by their wording (numbers replaced by '#').
                    let key: String = reason
                        .chars()
                        .map(|c| {
                            if c.is_ascii_digit() || c == '.' {
                                '#'
                            } else {
                                c
                            }
                        })
                        .collect();
                    *stats.reasons.entry(key).or_default() += 1;
                    continue;
                }
            };
            any = true;
            stats.accepted += 1;
            // True ground points: ortho pixels within 4 m of the centre (the road around the vehicle), placed by the
            // TRUE pose's ortho georeference, projected into the aerial image.
            let true_georef = OrthoGeoref::new(true_foot, params);
            let c = georef_centre(&ortho.georef);
            let r_px = 4.0 / params.gsd_m;
            let mut worst = 0.0f64;
            for k in 0..16 {
                let ang = k as f64 * std::f64::consts::TAU / 16.0;
                let rad = if k % 2 == 0 { r_px } else { 0.5 * r_px };
                let q = Vector2::new(c.x + rad * ang.cos(), c.y + rad * ang.sin());
                let est = t.ortho_to_aerial.apply(&q);
                let truth_px = cam
                    .project_world(&true_georef.pixel_to_world(q.x, q.y))
                    .unwrap();
                worst = worst.max((est.x - truth_px.0).hypot(est.y - truth_px.1));
            }
            stats.max_point_error_px.push(worst);
            let offset = centre_offset_world(&t.ortho_to_aerial, &ortho.georef, cam).unwrap();
            stats
                .offset_error_m
                .push((offset[0] + error[0]).hypot(offset[1] + error[1]));
            stats.offsets.push(offset);
        }
        stats.recordings_with_accepted += usize::from(any);
    }
    stats
}

fn georef_centre(g: &OrthoGeoref) -> Vector2<f64> {
    Vector2::new(g.width_px as f64 / 2.0, g.height_px as f64 / 2.0)
}

fn report(name: &str, s: &CampaignStats) {
    println!(
        "{name}: {} recordings, {} with an accepted transform; {} (recording, nadir) pairs, {} accepted",
        s.recordings, s.recordings_with_accepted, s.pairs, s.accepted
    );
    println!(
        "  {}",
        summarise("max true-point error px", &s.max_point_error_px)
    );
    println!("  {}", summarise("offset error m", &s.offset_error_m));
    let n = s.offsets.len().max(1) as f64;
    let mean = s
        .offsets
        .iter()
        .fold([0.0, 0.0], |a, o| [a[0] + o[0] / n, a[1] + o[1] / n]);
    println!(
        "  mean estimated offset (E, N) = ({:.3}, {:.3}) m",
        mean[0], mean[1]
    );
    println!("  {}", summarise("seconds per pair", &s.seconds_per_pair));
    let mut reasons: Vec<_> = s.reasons.iter().collect();
    reasons.sort();
    for (r, c) in reasons {
        println!("  rejected {c}×: {r}");
    }
}

/// The initial transform is a coarse alignment (thesis 3.4.5.2: it only has to bring each tie point within the
/// phase-correlation refinement's capture range, 3.4.5.3); it is not sub-pixel. Off-ground KAZE matches (parked
/// cars, kerbs) sit a pixel or two off the ground plane's translation and enter the 2 px consensus, and a zebra
/// crossing can make a transform one stripe period (1 m, 10 px) off, which the agreement across the recording's
/// images removes when it has at least three accepted transforms (with fewer there is no majority to compare
/// with; the refinement's shift-consistency check and the control points' multi-image check then stop its
/// correspondences). The stated limit, for what reaches the refinement (transform + agreement): at least 80 % of
/// the accepted transforms within half the refinement's search margin (6 px) and 0.6 m of the truth, the median
/// within a third of that (2 px); the refinement's own accuracy is tested in `nadir_refine.rs` and end to end by the inlier ratio
/// in `tests/pipeline_tiny.rs`.
#[test]
fn tiny_campaign_transforms_lie_within_the_refinement_capture_range() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("tiny");
    generate(&SynthOptions::new(Preset::Tiny, 1), &root).unwrap();
    let p = TransformParams::default();
    let s = evaluate_campaign(&root, &p);
    report("tiny", &s);
    assert!(
        s.accepted >= s.pairs / 2 && s.accepted >= 3,
        "{} of {} accepted",
        s.accepted,
        s.pairs
    );
    let capture_px = RefineParams::default().search_margin_px as f64 / 2.0;
    let within = s
        .max_point_error_px
        .iter()
        .zip(&s.offset_error_m)
        .filter(|(&e, &o)| e <= capture_px && o <= 0.6)
        .count();
    assert!(
        within * 5 >= s.accepted * 4,
        "{within} of {} accepted transforms within {capture_px} px and 0.6 m of the truth (< 80 %): {:?}",
        s.accepted,
        s.max_point_error_px
    );
    let mut sorted = s.max_point_error_px.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    // The typical transform sits well inside the capture range: a third of it (2 px; measured 1.64 px, the
    // off-ground matches of the parked cars and the kerbs of the T-junction).
    assert!(
        median <= capture_px / 3.0,
        "median worst-point error {median} px"
    );
    // The estimated offsets reproduce the systematic deterioration (0.80 m): their mean magnitude.
    let n = s.offsets.len() as f64;
    let mean = s
        .offsets
        .iter()
        .fold([0.0, 0.0], |a, o| [a[0] + o[0] / n, a[1] + o[1] / n]);
    assert!(
        (mean[0].hypot(mean[1]) - 0.80).abs() < 0.15,
        "mean offset {mean:?}"
    );
}

#[test]
#[ignore = "needs SKYTIE_DEMO=/path/to/demo campaign; prints statistics"]
fn demo_campaign_statistics() {
    let Ok(root) = std::env::var("SKYTIE_DEMO") else {
        println!("SKYTIE_DEMO not set");
        return;
    };
    // Optional overrides as TOML, e.g. SKYTIE_TRANSFORM_PARAMS='kaze_threshold_mm = 0.0002'.
    let p: TransformParams =
        toml::from_str(&std::env::var("SKYTIE_TRANSFORM_PARAMS").unwrap_or_default())
            .expect("SKYTIE_TRANSFORM_PARAMS must be TOML with TransformParams fields");
    println!("{p:?}");
    let s = evaluate_campaign(Path::new(&root), &p);
    report("demo", &s);
    assert!(s.accepted > 0);
}

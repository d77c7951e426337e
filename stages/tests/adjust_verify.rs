//! Known-answer tests of the verification (thesis Table 5-13): with exact observations
//! and a purely systematic position error, every MM − aerial offset equals that error; a deteriorated campaign
//! is flagged, an undeteriorated one passes; a segment whose recordings drift with a mean near zero fails on its
//! points, one wrong point does not fail a segment; a segment whose points leave half of it unobserved does not
//! pass; a segment whose verified poses state a σ too large for the tolerance does not pass;
//! `verification.csv` parses back; segments by count and by length.

use skytie_stages::adjustment::synthetic_campaign::{SyntheticCampaign, SyntheticCampaignSpec};
use skytie_stages::adjustment::verify::{
    render_verification_table, verify, verify_with_detail_levels, write_verification_csv,
    VerifyConfig, VerifyStatus, VERIFICATION_CSV_HEADER,
};
use skytie_stages::adjustment::SyntheticBlockSpec;

/// [`campaign`] without deterioration and with 120 control points instead of 30.
fn dense_campaign(seed: u64) -> SyntheticCampaign {
    let mut spec = campaign_spec(0.0, 0.0, 0.5, seed);
    spec.block.control_points = 120;
    spec.generate()
}

fn campaign(systematic_m: f64, random_m: f64, noise_px: f64, seed: u64) -> SyntheticCampaign {
    campaign_spec(systematic_m, random_m, noise_px, seed).generate()
}

fn campaign_spec(
    systematic_m: f64,
    random_m: f64,
    noise_px: f64,
    seed: u64,
) -> SyntheticCampaignSpec {
    SyntheticCampaignSpec {
        block: SyntheticBlockSpec {
            recordings: 60,
            control_points: 30,
            systematic_offset_m: systematic_m,
            random_offset_m: random_m,
            pixel_noise_px: noise_px,
            sigma_px: noise_px.max(0.5),
            seed,
            ..SyntheticBlockSpec::default()
        },
        aerial_noise_px: noise_px,
        single_aerial_every: 5,
        ..SyntheticCampaignSpec::default()
    }
}

#[test]
fn systematic_error_is_recovered_exactly_and_flagged() {
    let c = campaign(0.8, 0.0, 0.0, 3);
    let truth_offset = {
        let r = &c.recordings[0];
        let t = c.truth.true_centers_world[0];
        [r.x - t.x, r.y - t.y, r.z - t.z]
    };
    let config = VerifyConfig::default();
    let v = verify(&c.recordings, &c.pano_size_px, &c.control, &config).unwrap();
    let singles = c.control.iter().filter(|cp| cp.aerial.len() < 2).count();
    assert!(singles >= 5, "{singles} single-image points");
    // Every point is compared: the single-image ones horizontally, at the MM point's height.
    assert_eq!(v.skipped_single_aerial, 0);
    assert_eq!(v.points.len() + v.skipped_mm, c.control.len());
    assert_eq!(
        v.points.iter().filter(|p| !p.aerial_height).count(),
        singles
    );
    assert!(v.points.len() >= 15, "{} points", v.points.len());
    for p in &v.points {
        let axes = if p.aerial_height { 3 } else { 2 };
        for (k, (got, want)) in p.offset_m.iter().zip(&truth_offset).take(axes).enumerate() {
            assert!(
                (got - want).abs() < 1e-6,
                "{}: axis {k} offset {got} vs {want}",
                p.tie_point_id
            );
        }
        if !p.aerial_height {
            assert_eq!((p.offset_m[2], p.variance_m2[2]), (0.0, 0.0));
        }
    }
    assert_eq!(v.segments.len(), 3);
    for s in &v.segments {
        assert_eq!(s.recordings, 20);
        assert_eq!(s.status, VerifyStatus::Fail, "segment {}", s.index);
        assert!((s.offset_2d_m - 0.8).abs() < 1e-6);
        assert!(s.sd_m.iter().all(|&x| x < 1e-6));
        assert!((s.mean_3d_m - 0.8).abs() < 1e-6);
        assert!(s.points_3d < s.points, "segment {}", s.index);
    }
    assert!(!v.passed());
    // Without them, the single-image points are skipped and counted.
    let multi_only = VerifyConfig {
        single_image_points: false,
        ..VerifyConfig::default()
    };
    let m = verify(&c.recordings, &c.pano_size_px, &c.control, &multi_only).unwrap();
    assert_eq!(m.skipped_single_aerial, singles);
    assert_eq!(m.points.len() + singles, v.points.len());
    assert!(m.points.iter().all(|p| p.aerial_height));
    let table = render_verification_table(&v);
    eprintln!("{table}");
    assert!(table.contains("fail") && table.contains("all"));
}

#[test]
fn undeteriorated_campaign_passes_and_deteriorated_one_fails_with_noise() {
    for seed in [1, 2, 3] {
        let good = campaign(0.0, 0.0, 0.5, seed);
        let bad = campaign(0.8, 0.1, 0.5, seed);
        let config = VerifyConfig::default();
        let vg = verify(&good.recordings, &good.pano_size_px, &good.control, &config).unwrap();
        let vb = verify(&bad.recordings, &bad.pano_size_px, &bad.control, &config).unwrap();
        eprintln!(
            "seed {seed}: undeteriorated overall offset {:.3} m ± {:.3} ({}), deteriorated {:.3} m ({})",
            vg.overall.offset_2d_m,
            vg.overall.sigma_mean_m[0].hypot(vg.overall.sigma_mean_m[1]),
            vg.overall.status.label(),
            vb.overall.offset_2d_m,
            vb.overall.status.label()
        );
        assert!(
            vg.passed(),
            "seed {seed}:\n{}",
            render_verification_table(&vg)
        );
        assert!(!vb.passed());
        assert!(vb.segments.iter().all(|s| s.status != VerifyStatus::Pass));
        // The mean offset of the deteriorated campaign is its systematic error within 3 σ of the mean + 10 cm
        // random part / √n.
        assert!((vb.overall.offset_2d_m - 0.8).abs() < 0.1);
    }
}

#[test]
fn segments_by_length_and_csv_round_trip() {
    let c = campaign(0.8, 0.0, 0.0, 5);
    let config = VerifyConfig {
        segment_length_m: Some(100.0),
        min_points: 2,
        ..VerifyConfig::default()
    };
    let v = verify(&c.recordings, &c.pano_size_px, &c.control, &config).unwrap();
    // 60 recordings 5 m apart: 295 m along track → segments [0,100), [100,200), [200,300).
    assert_eq!(v.segments.len(), 3);
    assert_eq!(
        v.segments.iter().map(|s| s.recordings).collect::<Vec<_>>(),
        [20, 20, 20]
    );
    let dir = std::env::temp_dir().join(format!("skytie_verify_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("verification.csv");
    write_verification_csv(&path, &v).unwrap();
    let mut reader = csv::Reader::from_path(&path).unwrap();
    assert_eq!(
        reader.headers().unwrap().iter().collect::<Vec<_>>(),
        VERIFICATION_CSV_HEADER
    );
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), v.segments.len() + 1);
    for (row, s) in rows.iter().zip(v.segments.iter().chain([&v.overall])) {
        assert_eq!(row[1].to_string(), s.first_image_id);
        assert_eq!(row[4].parse::<usize>().unwrap(), s.points);
        for k in 0..3 {
            assert_eq!(row[5 + k].parse::<f64>().unwrap(), s.mean_m[k]);
            assert_eq!(row[8 + k].parse::<f64>().unwrap(), s.sd_m[k]);
            assert_eq!(row[13 + k].parse::<f64>().unwrap(), s.sigma_mean_m[k]);
        }
        assert_eq!(row[16].parse::<usize>().unwrap(), s.points_off);
        assert_eq!(&row[17], s.status.label());
        assert_eq!(row[18].parse::<usize>().unwrap(), s.unobserved_run);
        assert_eq!(&row[19], "", "the recorded poses state no σ");
    }
    assert_eq!(&rows[rows.len() - 1][0], "all");
    std::fs::remove_dir_all(&dir).unwrap();
    // Bad parameters are named.
    let bad = VerifyConfig {
        tolerance_xy_m: 0.0,
        ..VerifyConfig::default()
    };
    let err = verify(&c.recordings, &c.pano_size_px, &c.control, &bad).unwrap_err();
    assert!(err.contains("tolerance_xy_m"), "{err}");
}

/// A GNSS outage: the middle segment's recordings drift 1 m east, then 1 m west, so the segment's mean offset is
/// near zero and proves nothing; its points are each 1 m off, which fails it. Wrong aerial points in an
/// otherwise exact segment do not fail that segment: the points seen from the same recordings outvote them
/// (each point on its own, two of them would).
#[test]
fn a_drifting_segment_fails_on_its_points_and_a_single_wrong_point_does_not() {
    let mut c = campaign(0.0, 0.0, 0.5, 4);
    for (i, r) in c.recordings.iter_mut().enumerate().take(40).skip(20) {
        r.x += if i < 30 { 1.0 } else { -1.0 };
    }
    let config = VerifyConfig::default();
    let v = verify(&c.recordings, &c.pano_size_px, &c.control, &config).unwrap();
    let drift = &v.segments[1];
    eprintln!("{}", render_verification_table(&v));
    assert!(drift.offset_2d_m < 0.5, "mean {}", drift.offset_2d_m);
    assert!(drift.points_off >= 2, "{} points off", drift.points_off);
    assert_eq!(drift.status, VerifyStatus::Fail);
    // The last segment is untouched; the first one's last point is also seen from drifted recordings.
    assert_eq!(v.segments[2].points_off, 0);
    assert!(v.segments[0].points_off <= 1);
    for s in [&v.segments[0], &v.segments[2]] {
        assert_eq!(s.status, VerifyStatus::Pass, "segment {}", s.index);
    }
    // Two aerial points of the last segment 2 m wrong, seen from the same recordings as exact ones (a campaign
    // with four times the control points, so that each recording sees several).
    let mut c = dense_campaign(4);
    for (i, r) in c.recordings.iter_mut().enumerate().take(40).skip(20) {
        r.x += if i < 30 { 1.0 } else { -1.0 };
    }
    let v = verify(&c.recordings, &c.pano_size_px, &c.control, &config).unwrap();
    assert!(
        v.segments[2].points_off <= 1,
        "only a point also seen from recording 39"
    );
    assert_eq!(v.segments[2].status, VerifyStatus::Pass);
    let off_before = v.segments[2].points_off;
    // Two points well inside the segment.
    let ids: Vec<String> = v
        .points
        .iter()
        .filter(|p| p.segment == 2 && p.aerial_height && p.observed_from.iter().all(|&r| r >= 45))
        .take(2)
        .map(|p| p.tie_point_id.clone())
        .collect();
    let mut wrong = c.control.clone();
    for id in &ids {
        let cp = wrong.iter_mut().find(|cp| &cp.tie_point_id == id).unwrap();
        let p = cp.point_world.as_mut().unwrap();
        p[1] += 2.0;
    }
    let each_alone = VerifyConfig {
        min_neighbours: 0,
        ..VerifyConfig::default()
    };
    assert_eq!(ids.len(), 2);
    let alone_before = verify(&c.recordings, &c.pano_size_px, &c.control, &each_alone).unwrap();
    let alone = verify(&c.recordings, &c.pano_size_px, &wrong, &each_alone).unwrap();
    assert_eq!(
        alone.segments[2].points_off,
        alone_before.segments[2].points_off + 2
    );
    assert_eq!(alone.segments[2].status, VerifyStatus::Fail);
    let v = verify(&c.recordings, &c.pano_size_px, &wrong, &config).unwrap();
    assert_eq!(v.segments[2].points_off, off_before);
    assert_eq!(v.segments[2].status, VerifyStatus::Pass);
    // The drifted segment still fails: its points' neighbours are off with them.
    assert_eq!(v.segments[1].status, VerifyStatus::Fail);
}

/// The middle segment's second half drifts 1 m and has no point of its own: its points, all in the good first
/// half, agree with the aerial control, yet they vouch for nothing in the drifted half — the segment is
/// `insufficient`, not `pass`. With every point present it fails on the drifted points, and an exact campaign
/// passes everywhere (its points cover every segment).
#[test]
fn a_segment_whose_points_leave_half_of_it_unobserved_does_not_pass() {
    let mut c = campaign(0.0, 0.0, 0.0, 4);
    let config = VerifyConfig::default();
    let exact = verify(&c.recordings, &c.pano_size_px, &c.control, &config).unwrap();
    eprintln!("{}", render_verification_table(&exact));
    for s in &exact.segments {
        assert_eq!(s.status, VerifyStatus::Pass, "segment {}", s.index);
        assert!(s.unobserved_run * 2 <= s.recordings, "segment {}", s.index);
    }
    for r in c.recordings.iter_mut().take(40).skip(30) {
        r.x += 1.0;
    }
    let all_points = verify(&c.recordings, &c.pano_size_px, &c.control, &config).unwrap();
    assert_eq!(all_points.segments[1].status, VerifyStatus::Fail);
    // Drop every control point seen from a drifted recording (indices 30–39): the points left are exact.
    let drifted: std::collections::HashSet<String> = c.recordings[30..40]
        .iter()
        .map(|r| r.image_id.clone())
        .collect();
    let before = c.control.len();
    c.control
        .retain(|cp| cp.mm.iter().all(|o| !drifted.contains(&o.image_id)));
    assert!(
        before - c.control.len() >= 2,
        "{} points dropped",
        before - c.control.len()
    );
    let v = verify(&c.recordings, &c.pano_size_px, &c.control, &config).unwrap();
    eprintln!("{}", render_verification_table(&v));
    let middle = &v.segments[1];
    assert!(
        middle.points >= config.min_points,
        "{} points",
        middle.points
    );
    assert_eq!(middle.points_off, 0);
    assert!(
        middle.offset_2d_m < config.tolerance_xy_m,
        "mean {}",
        middle.offset_2d_m
    );
    assert!(middle.unobserved_run >= 10, "run {}", middle.unobserved_run);
    assert_eq!(middle.status, VerifyStatus::Insufficient);
}

/// The verification of an adjusted trajectory: the same undeteriorated campaign passes when its poses state a
/// σ of 5 cm, and a segment whose recordings state 0.5 m on half of them (bridged across a drift that the
/// adjustment could not take out) is `insufficient`, not `pass`: its points vouch for the other half only.
#[test]
fn a_segment_whose_stated_sigma_cannot_support_the_tolerance_does_not_pass() {
    let c = dense_campaign(1);
    let config = VerifyConfig::default();
    let n = c.recordings.len();
    let run = |sigma: &[f64]| {
        verify_with_detail_levels(
            &c.recordings,
            &c.pano_size_px,
            &[],
            sigma,
            &c.control,
            &config,
        )
        .unwrap()
    };
    let tight = run(&vec![0.05; n]);
    assert!(tight.passed(), "{}", render_verification_table(&tight));
    for s in &tight.segments {
        assert!((s.stated_sigma_xy_m.unwrap() - 0.05).abs() < 1e-12);
    }
    // Segment 1 (recordings 20–39): half of them at 0.5 m → RMS 0.36 m, ×2 beyond 0.20 m.
    let mut sigma = vec![0.05; n];
    sigma[25..35].fill(0.5);
    let loose = run(&sigma);
    let status: Vec<_> = loose.segments.iter().map(|s| s.status).collect();
    assert_eq!(
        status,
        [
            VerifyStatus::Pass,
            VerifyStatus::Insufficient,
            VerifyStatus::Pass
        ],
        "{}",
        render_verification_table(&loose)
    );
    // Evidence of a failure still fails: the deteriorated campaign fails whatever σ its poses state.
    let bad = campaign(0.8, 0.0, 0.5, 1);
    let vb = verify_with_detail_levels(
        &bad.recordings,
        &bad.pano_size_px,
        &[],
        &vec![0.5; n],
        &bad.control,
        &config,
    )
    .unwrap();
    assert!(vb.segments.iter().all(|s| s.status == VerifyStatus::Fail));
    // One σ per recording or none.
    assert!(verify_with_detail_levels(
        &c.recordings,
        &c.pano_size_px,
        &[],
        &[0.1],
        &c.control,
        &config
    )
    .is_err());
}

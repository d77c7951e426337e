//! Known-answer tests of the error profiles on a hand-made trajectory: a route 100 m east, a right-angle
//! turn, 100 m south; a second route an hour later.

use super::*;
use crate::geometry::FrameCamera;
use nalgebra::Vector3;

fn rec(route: usize, i: usize, x: f64, y: f64, heading_deg: f64) -> Recording {
    Recording {
        sigma_xy_m: Some(1.0),
        sigma_z_m: Some(0.3),
        ..Recording::new(
            &format!("p{route}_{i:03}"),
            3600.0 * route as f64 + i as f64 * 0.625,
            [x, y, 3.4],
            heading_deg,
            2.2,
        )
    }
}

/// Route 0: 21 recordings east then 20 south (5 m apart); route 1: 10 recordings north, 5 km away.
fn truth() -> Tables {
    let mut recordings = Vec::new();
    for i in 0..=20 {
        recordings.push(rec(0, i, 1000.0 + 5.0 * i as f64, 2000.0, 90.0));
    }
    for i in 1..=20 {
        recordings.push(rec(0, 20 + i, 1100.0, 2000.0 - 5.0 * i as f64, 180.0));
    }
    for i in 0..10 {
        recordings.push(rec(1, i, 6000.0, 2000.0 + 5.0 * i as f64, 0.0));
    }
    let nadir = vec![AerialImage::ideal(
        "n0",
        [1050.0, 2000.0, 4471.2],
        [0.05, -0.1, -90.0],
        44_700.0,
        [1600, 1200],
    )];
    Tables {
        recordings,
        nadir,
        oblique: Vec::new(),
    }
}

/// `value` of each recording of `out` minus that of the same recording of `t`.
fn differences<T>(out: &Tables, t: &Tables, value: impl Fn(&Recording, &Recording) -> T) -> Vec<T> {
    out.recordings
        .iter()
        .zip(&t.recordings)
        .map(|(r, t)| value(r, t))
        .collect()
}

fn errors(p: &Profile, seed: u64) -> (Tables, Vec<[f64; 2]>) {
    let t = truth();
    let out = p.apply(seed, &t).tables;
    let e = differences(&out, &t, |r, t| [r.x - t.x, r.y - t.y]);
    (out, e)
}

#[test]
fn names_parse_combine_and_are_refused_with_the_list() {
    let p = Profile::parse("ins + thesis,outage").unwrap();
    assert_eq!(p.name(), "thesis+outage+ins");
    assert_eq!(Profile::parse("none").unwrap().name(), "none");
    assert_eq!(
        Profile::parse("all").unwrap().name(),
        "thesis+outage+ins+vertical+aerial+lens+epoch"
    );
    let e = Profile::parse("thesis+gnss").unwrap_err().to_string();
    assert!(
        e.contains("'gnss'") && e.contains("outage") && e.contains("lens-unknown"),
        "{e}"
    );
    let e = Profile::parse("lens+lens-unknown").unwrap_err().to_string();
    assert!(e.contains("both"), "{e}");
    // Only lens and epoch change the images.
    assert_eq!(
        Profile::parse("thesis+outage+ins+vertical+aerial")
            .unwrap()
            .render_options(),
        Profile::none().render_options()
    );
    let r = Profile::parse("lens-unknown+epoch")
        .unwrap()
        .render_options();
    assert_eq!(r.nadir_corner_distortion_px, 3.0);
    assert!(r.epoch.is_some());
    let mut bad = Profile::parse("outage").unwrap();
    bad.params.outage.peak_m = [2.0, 1.0];
    bad.params.ins.pitch_roll_sigma_deg = f64::NAN;
    let fields: Vec<String> = bad.problems().into_iter().map(|v| v.field).collect();
    assert_eq!(fields, ["outage.peak_m", "ins.pitch_roll_sigma_deg"]);
}

#[test]
fn none_changes_nothing_and_the_same_seed_gives_the_same_tables() {
    let t = truth();
    let a = Profile::none().apply(3, &t);
    assert_eq!(a.tables, t);
    assert!(!a.aerial_changed && a.notes.is_empty());
    let all = Profile::parse("all").unwrap();
    assert_eq!(all.apply(3, &t), all.apply(3, &t));
    assert_ne!(all.apply(3, &t).tables, all.apply(4, &t).tables);
}

#[test]
fn outage_rises_to_its_peak_and_back_and_its_growth_turns_with_the_vehicle() {
    let mut p = Profile::parse("outage").unwrap();
    p.params.outage.random_walk_step_m = 0.0;
    p.params.outage.fix_sigma_m = 0.0;
    p.params.outage.length_m = [200.0, 200.0];
    p.params.outage.max_route_fraction = 1.0;
    let (_, e) = errors(&p, 11);
    let routes = Routes::of(&truth().recordings);
    let size = |v: [f64; 2]| v[0].hypot(v[1]);
    let az = |v: [f64; 2]| v[0].atan2(v[1]).to_degrees();
    let angle_off = |a: f64, b: f64| (a - b).rem_euclid(360.0).min((b - a).rem_euclid(360.0));

    // Route 0 (200 m with a right-angle bend at recording 20): the whole route is the outage.
    let o = p.params.outage.draw(11, 0, routes.length_m[0]);
    assert_eq!((o.start_m, o.length_m), (0.0, 200.0), "the whole route");
    assert!((1.5..=2.0).contains(&o.peak_m));
    // 0 at both ends, the largest size equal to the peak.
    assert!(size(e[0]) < 1e-9 && size(e[40]) < 1e-9);
    let largest = e[..41].iter().map(|&v| size(v)).fold(0.0, f64::max);
    assert!(
        (largest - o.peak_m).abs() < 1e-9,
        "{largest} against {}",
        o.peak_m
    );
    // Near each end the error points about where it grows: `relative_azimuth_deg` from the local driving
    // direction (east before the bend, south after it; the other filter's solution pulls it by a few degrees),
    // so its direction turns with the bend over the outage.
    assert!(
        angle_off(az(e[1]), 90.0 + o.relative_azimuth_deg) < 10.0,
        "{}",
        az(e[1])
    );
    assert!(
        angle_off(az(e[39]), 180.0 + o.relative_azimuth_deg) < 10.0,
        "{}",
        az(e[39])
    );
    let turn = (az(e[39]) - az(e[1])).rem_euclid(360.0);
    assert!((70.0..=90.0).contains(&turn), "turned by {turn}°");
    // Continuous through the bend: no step between consecutive recordings larger than the rate allows
    // (a vector fixed in the vehicle frame would jump by √2 · size ≈ 2.5 m at the corner).
    let largest_step = (1..41)
        .map(|i| size([e[i][0] - e[i - 1][0], e[i][1] - e[i - 1][1]]))
        .fold(0.0, f64::max);
    let rate_bound = o.peak_m * std::f64::consts::PI * 5.0 / 200.0;
    assert!(largest_step < 1.5 * rate_bound, "{largest_step} m in 5 m");

    // Route 1 (45 m straight north): exactly peak · sin²(π t), pointing `relative_azimuth_deg` from north.
    let o1 = p.params.outage.draw(11, 1, routes.length_m[1]);
    assert_eq!((o1.start_m, o1.length_m), (0.0, 45.0));
    for (i, err) in e.iter().enumerate().skip(41) {
        let along = routes.along_m[i];
        assert!(
            (size(*err) - o1.drift_m(along)).abs() < 1e-9,
            "recording {i}"
        );
        if o1.drift_m(along) > 1e-6 {
            assert!(
                angle_off(az(*err), o1.relative_azimuth_deg) < 1e-6,
                "recording {i}"
            );
        }
    }
    assert!(e[41..].iter().any(|&v| size(v) > 0.1));
}

#[test]
fn outage_with_its_noise_stays_near_the_smooth_drift_and_keeps_centimetres_outside() {
    let p = Profile::parse("outage").unwrap();
    let (_, e) = errors(&p, 5);
    let routes = Routes::of(&truth().recordings);
    let o = p.params.outage.draw(5, 0, routes.length_m[0]);
    assert!(o.length_m <= 0.8 * 200.0 + 1e-9 && o.length_m >= 80.0);
    for (i, err) in e.iter().enumerate().take(41) {
        let size = err[0].hypot(err[1]);
        match o.phase(routes.along_m[i]) {
            None => assert!(size < 0.1, "outside the outage: {size} m"),
            Some(_) => assert!((size - o.drift_m(routes.along_m[i])).abs() < 0.5, "{i}"),
        }
    }
    let largest = e[..41].iter().map(|v| v[0].hypot(v[1])).fold(0.0, f64::max);
    assert!(largest > 1.3, "{largest}");
}

#[test]
fn ins_biases_yaw_and_heading_per_route_and_adds_pitch_roll_noise() {
    let mut p = Profile::parse("ins").unwrap();
    p.params.ins.heading_walk_step_deg = 0.0;
    let t = truth();
    let out = p.apply(9, &t).tables;
    for route in 0..2 {
        let bias = p.params.ins.bias_deg(9, route);
        assert!((0.1..=0.5).contains(&bias.abs()), "{bias}");
        for (r, tr) in out.recordings.iter().zip(&t.recordings) {
            if tr.time_s >= 3600.0 * route as f64 && tr.time_s < 3600.0 * (route + 1) as f64 {
                assert!((r.yaw_deg - tr.yaw_deg - bias).abs() < 1e-12);
                let dh = (r.heading_deg - tr.heading_deg + 180.0).rem_euclid(360.0) - 180.0;
                assert!((dh - bias).abs() < 1e-9);
                assert_eq!((r.x, r.y, r.z), (tr.x, tr.y, tr.z));
            }
        }
    }
    let dp = differences(&out, &t, |r, t| r.pitch_deg - t.pitch_deg);
    let rms = (dp.iter().map(|v| v * v).sum::<f64>() / dp.len() as f64).sqrt();
    assert!(rms > 0.01 && rms < 0.04, "pitch noise {rms}°");
    // With the random walk the heading error wanders but stays near the bias.
    let out = Profile::parse("ins").unwrap().apply(9, &t).tables;
    let bias = p.params.ins.bias_deg(9, 0);
    let dy: Vec<f64> = (0..41)
        .map(|i| out.recordings[i].yaw_deg - t.recordings[i].yaw_deg)
        .collect();
    assert!(dy.iter().all(|d| (d - bias).abs() < 0.1) && dy[40] != dy[0]);
}

#[test]
fn vertical_adds_a_height_bias_per_route_and_a_camera_height_error() {
    let mut p = Profile::parse("vertical").unwrap();
    p.params.vertical.z_sigma_m = 0.0;
    p.params.vertical.camera_height_sigma_m = 0.0;
    let t = truth();
    let out = p.apply(2, &t).tables;
    let dz = differences(&out, &t, |r, t| r.z - t.z);
    assert!((0.1..=0.3).contains(&dz[0].abs()) && (0.1..=0.3).contains(&dz[45].abs()));
    assert!(dz[..41].iter().all(|d| *d == dz[0]) && dz[41..].iter().all(|d| *d == dz[45]));
    let dh = out.recordings[7].camera_height_m - t.recordings[7].camera_height_m;
    assert!((0.02..=0.05).contains(&dh.abs()), "{dh}");
    assert!(out
        .recordings
        .iter()
        .zip(&t.recordings)
        .all(|(r, t)| (r.camera_height_m - t.camera_height_m - dh).abs() < 1e-12 && r.x == t.x));
}

#[test]
fn aerial_errors_move_the_ground_footprint_by_centimetres_and_are_recorded() {
    let p = Profile::parse("aerial").unwrap();
    let t = truth();
    let a = p.apply(4, &t);
    assert!(a.aerial_changed);
    assert_eq!(a.tables.recordings, t.recordings);
    let (c_true, c_rec) = (
        FrameCamera::from_aerial(&t.nadir[0]),
        FrameCamera::from_aerial(&a.tables.nadir[0]),
    );
    // A ground point near the principal ray lands within a few aerial pixels (0.10 m) of its true pixel.
    let g = Vector3::new(1040.0, 2010.0, 1.2);
    let (u0, v0) = c_true.project_world(&g).unwrap();
    let (u1, v1) = c_rec.project_world(&g).unwrap();
    let shift_m = (u1 - u0).hypot(v1 - v0) * 0.1;
    assert!(
        shift_m > 0.001 && shift_m < 0.25,
        "ground shift {shift_m} m"
    );
    // The attitude differs by millidegrees.
    let d = (a.tables.nadir[0].omega_deg - t.nadir[0].omega_deg).abs();
    assert!(d > 1e-5 && d < 0.02, "{d}°");
}

#[test]
fn lens_unknown_zeroes_the_tables_and_components_add_up() {
    let mut t = truth();
    t.nadir[0].k1 = 1e-3;
    let a = Profile::parse("lens-unknown").unwrap().apply(1, &t);
    assert_eq!(a.tables.nadir[0].k1, 0.0);
    assert!(a.aerial_changed);
    assert!(!Profile::parse("lens").unwrap().apply(1, &t).aerial_changed);
    // Errors of combined components are the sums of the single components' errors.
    let (_, e_thesis) = errors(&Profile::thesis(), 8);
    let (_, e_outage) = errors(&Profile::parse("outage").unwrap(), 8);
    let (out, e_both) = errors(&Profile::parse("thesis+outage+ins").unwrap(), 8);
    for i in 0..e_both.len() {
        for k in 0..2 {
            assert!((e_both[i][k] - e_thesis[i][k] - e_outage[i][k]).abs() < 1e-9);
        }
    }
    let ins = Profile::parse("ins").unwrap().apply(8, &truth()).tables;
    assert_eq!(
        out.recordings.iter().map(|r| r.yaw_deg).collect::<Vec<_>>(),
        ins.recordings.iter().map(|r| r.yaw_deg).collect::<Vec<_>>()
    );
}

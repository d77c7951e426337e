//! Round trips of the run outputs: `trajectory_adjusted.csv` reads back as recordings,
//! `trajectory.geojson` parses as a FeatureCollection with the expected layers, `tie_points.ply` decodes,
//! `checkpoints.csv` parses back to the errors, and the COLMAP text model's poses reproject every track
//! observation with COLMAP's own camera-model formulas (EQUIRECTANGULAR, PINHOLE/OPENCV).

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
mod support;

use skytie_stages::adjustment::campaign_checkpoints::adjusted_cameras;
use skytie_stages::adjustment::synthetic_campaign::SyntheticCampaign;
use skytie_stages::adjustment::{AdjustConfig, AdjustmentRun, SyntheticBlockSpec, ViewSelection};
use skytie_stages::campaign::{read_recordings_csv, write_recordings_csv};
use skytie_stages::export::{
    checkpoint_rows, write_adjusted_trajectory, write_checkpoint_errors_csv, write_colmap_model,
    write_run_geojson, write_tie_points_ply, CorrectionSeries, CHECKPOINTS_CSV_HEADER,
    PLY_SOURCE_RECORDING,
};
use skytie_stages::geometry::FrameCamera;
use std::collections::HashMap;
use std::path::PathBuf;

fn setup() -> (SyntheticCampaign, AdjustmentRun) {
    let block = SyntheticBlockSpec {
        recordings: 24,
        control_points: 10,
        yaw_error_deg: 0.3,
        seed: 21,
        ..SyntheticBlockSpec::default()
    };
    let config = AdjustConfig {
        aerial_observations: true,
        estimate_yaw: true,
        // A weak yaw prior: exact data then gives the exact answer.
        yaw_prior_sigma_deg: 100.0,
        ..AdjustConfig::default()
    };
    support::adjusted::adjusted_campaign(block, &config)
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("skytie_export_{name}_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn trajectory_csv_geojson_and_ply_round_trip() {
    let (c, r) = setup();
    let dir = temp_dir("traj");
    let path = dir.join("trajectory_adjusted.csv");
    let input = dir.join("recordings.csv");
    write_recordings_csv(&input, &c.recordings).unwrap();
    let series = CorrectionSeries::from_run(&c.recordings, &r).unwrap();
    let counts = write_adjusted_trajectory(&path, &input, &series, &r).unwrap();
    assert_eq!((counts.adjusted, counts.not_read), (c.recordings.len(), 0));
    let (back, problems) = read_recordings_csv(&path);
    assert!(problems.is_empty(), "{problems:?}");
    assert_eq!(back.len(), c.recordings.len());
    for ((b, rec), a) in back.iter().zip(&c.recordings).zip(&r.recordings) {
        assert_eq!(b.image_id, rec.image_id);
        assert_eq!([b.x, b.y, b.z], a.adjusted_world);
        assert_eq!(b.yaw_deg, rec.yaw_deg + a.yaw_correction_deg);
        assert_eq!(b.sigma_z_m, Some(a.sigma_m[2]));
    }
    // The adjusted trajectory is the truth (exact data), the yaw error is recovered.
    for (a, t) in r.recordings.iter().zip(&c.truth.true_centers_world) {
        assert!((Vector3::from(a.adjusted_world) - t).norm() < 1e-4);
    }

    // GeoJSON.
    let comparison = support::adjusted::checkpoint_comparison(
        &c,
        &r,
        ViewSelection::WithinRadius { radius_m: 15.0 },
    );
    let rows = checkpoint_rows(&comparison);
    let gj = dir.join("trajectory.geojson");
    write_run_geojson(
        &gj,
        "EPSG:28992",
        &c.recordings,
        &r,
        &c.checkpoints,
        &rows,
        None,
    )
    .unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&gj).unwrap()).unwrap();
    assert_eq!(v["type"], "FeatureCollection");
    assert_eq!(
        v["crs"]["properties"]["name"],
        "urn:ogc:def:crs:EPSG::28992"
    );
    let features = v["features"].as_array().unwrap();
    let n = c.recordings.len();
    assert_eq!(features.len(), 2 * (n + 1) + c.checkpoints.len());
    let layer_count = |name: &str, geom: &str| {
        features
            .iter()
            .filter(|f| f["properties"]["layer"] == name && f["geometry"]["type"] == geom)
            .count()
    };
    assert_eq!(layer_count("recorded", "Point"), n);
    assert_eq!(layer_count("adjusted", "LineString"), 1);
    assert_eq!(layer_count("checkpoints", "Point"), c.checkpoints.len());
    let first_adjusted = features
        .iter()
        .find(|f| f["properties"]["layer"] == "adjusted")
        .unwrap();
    let coords: Vec<f64> = first_adjusted["geometry"]["coordinates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(coords, r.recordings[0].adjusted_world.to_vec());
    assert!(features
        .iter()
        .filter(|f| f["properties"]["layer"] == "checkpoints")
        .all(|f| f["properties"]["improved"] == true));

    // PLY.
    let ply = dir.join("tie_points.ply");
    write_tie_points_ply(&ply, &r).unwrap();
    let bytes = std::fs::read(&ply).unwrap();
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let header = std::str::from_utf8(&bytes[..end]).unwrap();
    let determined = r.points.iter().filter(|p| p.determined).count();
    assert!(header.contains(&format!("element vertex {}", determined + n)));
    assert_eq!(bytes.len() - end, 31 * (determined + n));
    let vertex = |i: usize| {
        let b = &bytes[end + 31 * i..end + 31 * (i + 1)];
        let f = |k: usize| f64::from_le_bytes(b[8 * k..8 * k + 8].try_into().unwrap());
        (
            [f(0), f(1), f(2)],
            i32::from_le_bytes(b[27..31].try_into().unwrap()),
        )
    };
    let first_point = r.points.iter().find(|p| p.determined).unwrap();
    assert_eq!(vertex(0).0, first_point.position_world);
    assert_eq!(vertex(determined).0, r.recordings[0].adjusted_world);
    assert_eq!(vertex(determined).1, PLY_SOURCE_RECORDING);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn checkpoints_csv_round_trip() {
    let (c, r) = setup();
    let comparison = support::adjusted::checkpoint_comparison(&c, &r, ViewSelection::TwoNearest);
    assert_eq!(comparison.skipped_observations, 0);
    assert!(
        comparison.before.rmse.d2 > 0.5,
        "{:?}",
        comparison.before.rmse
    );
    assert!(
        comparison.after.rmse.d3 < 1e-3,
        "{:?}",
        comparison.after.rmse
    );
    let rows = checkpoint_rows(&comparison);
    let dir = temp_dir("cp");
    let path = dir.join("checkpoints.csv");
    write_checkpoint_errors_csv(&path, &rows).unwrap();
    let records = support::csv_records(&path, &CHECKPOINTS_CSV_HEADER);
    assert_eq!(records.len(), c.checkpoints.len());
    for (rec, row) in records.iter().zip(&rows) {
        assert_eq!(&rec[0], row.point_id);
        let before = row.before.unwrap();
        let after = row.after.unwrap();
        assert_eq!(rec[1].parse::<usize>().unwrap(), 2);
        for k in 0..3 {
            assert_eq!(rec[2 + k].parse::<f64>().unwrap(), before.error_m[k]);
            assert_eq!(rec[8 + k].parse::<f64>().unwrap(), after.error_m[k]);
        }
        assert_eq!(rec[5].parse::<f64>().unwrap(), before.d2());
        assert_eq!(&rec[13], "true");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// COLMAP world→camera rotation from (QW, QX, QY, QZ).
fn rotation(q: [f64; 4]) -> Matrix3<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
        .to_rotation_matrix()
        .into_inner()
}

/// COLMAP's EQUIRECTANGULAR ImgFromCam.
fn equirect(w: f64, h: f64, p: &Vector3<f64>) -> (f64, f64) {
    let theta = p.x.atan2(p.z);
    let phi = (-p.y).atan2(p.x.hypot(p.z));
    (
        (theta / std::f64::consts::TAU + 0.5) * w,
        (0.5 - phi / std::f64::consts::PI) * h,
    )
}

/// COLMAP's PINHOLE / OPENCV ImgFromCam.
fn opencv(params: &[f64], p: &Vector3<f64>) -> (f64, f64) {
    let (x, y) = (p.x / p.z, p.y / p.z);
    let (k1, k2, p1, p2) = if params.len() == 8 {
        (params[4], params[5], params[6], params[7])
    } else {
        (0.0, 0.0, 0.0, 0.0)
    };
    let r2 = x * x + y * y;
    let radial = 1.0 + k1 * r2 + k2 * r2 * r2;
    let xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    let yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    (params[0] * xd + params[2], params[1] * yd + params[3])
}

/// |Δu|, wrapped across the panorama seam for equirectangular images of width `w`.
fn horizontal_difference(du: f64, wrap: bool, w: f64) -> f64 {
    if wrap {
        ((du + w / 2.0).rem_euclid(w) - w / 2.0).abs()
    } else {
        du.abs()
    }
}

fn data_lines(text: &str) -> Vec<&str> {
    text.lines().filter(|l| !l.starts_with('#')).collect()
}

#[test]
fn colmap_model_reprojects_every_observation() {
    let (c, r) = setup();
    let dir = temp_dir("colmap");
    let export = write_colmap_model(
        &dir,
        "EPSG:28992",
        &c.recordings,
        &c.pano_size_px,
        &r,
        &c.nadir,
        &[],
    )
    .unwrap();
    let origin = Vector3::from(export.origin_world);
    let cameras_txt = std::fs::read_to_string(dir.join("cameras.txt")).unwrap();
    assert!(cameras_txt.contains(&format!(
        "world = local + origin ({}, {}, {}) m, CRS EPSG:28992",
        origin.x, origin.y, origin.z
    )));
    let mut cameras: HashMap<usize, (String, Vec<f64>)> = HashMap::new();
    for l in data_lines(&cameras_txt) {
        let f: Vec<&str> = l.split_whitespace().collect();
        let params: Vec<f64> = f[4..].iter().map(|x| x.parse().unwrap()).collect();
        cameras.insert(f[0].parse().unwrap(), (f[1].to_string(), params));
    }
    assert_eq!(cameras.len(), export.cameras);
    assert_eq!(cameras[&1].0, "EQUIRECTANGULAR");
    assert!(cameras.values().any(|c| c.0 == "OPENCV"));
    assert!(cameras.values().any(|c| c.0 == "PINHOLE"));
    let points_txt = std::fs::read_to_string(dir.join("points3D.txt")).unwrap();
    let mut points: HashMap<usize, Vector3<f64>> = HashMap::new();
    let mut track_len = 0;
    for l in data_lines(&points_txt) {
        let f: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
        points.insert(f[0] as usize, Vector3::new(f[1], f[2], f[3]));
        assert!(f[7] < 1e-3, "mean reprojection error {} px", f[7]);
        track_len += (f.len() - 8) / 2;
    }
    assert_eq!(points.len(), export.points);
    let images_txt = std::fs::read_to_string(dir.join("images.txt")).unwrap();
    let lines = data_lines(&images_txt);
    assert_eq!(lines.len(), 2 * export.images);
    let pano_cams = adjusted_cameras(&c.recordings, &c.pano_size_px, &r).unwrap();
    let aerial_cams: Vec<FrameCamera> = c.nadir.iter().map(FrameCamera::from_aerial).collect();
    let mut checked = 0;
    for pair in lines.chunks(2) {
        let f: Vec<&str> = pair[0].split_whitespace().collect();
        let image_id: usize = f[0].parse().unwrap();
        let q: Vec<f64> = f[1..5].iter().map(|x| x.parse().unwrap()).collect();
        assert!(q[0] >= 0.0);
        let t = Vector3::new(
            f[5].parse().unwrap(),
            f[6].parse().unwrap(),
            f[7].parse().unwrap(),
        );
        let rot = rotation([q[0], q[1], q[2], q[3]]);
        let (model, params) = &cameras[&f[8].parse::<usize>().unwrap()];
        let obs: Vec<f64> = pair[1]
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        for o in obs.chunks(3) {
            let x_local = points[&(o[2] as usize)];
            let p_cam = rot * x_local + t;
            let (u, v) = if model == "EQUIRECTANGULAR" {
                equirect(params[0], params[1], &p_cam)
            } else {
                opencv(params, &p_cam)
            };
            // Our own projection with the same pose (convention check, independent of residuals).
            let world = x_local + origin;
            let (ou, ov) = if image_id <= pano_cams.len() {
                pano_cams[image_id - 1].project_world(&world).unwrap()
            } else {
                let name = f[9].trim_start_matches("nadir/");
                let k = c.nadir.iter().position(|a| a.file == name).unwrap();
                aerial_cams[k].project_world(&world).unwrap()
            };
            let is_pano = model == "EQUIRECTANGULAR";
            let du = horizontal_difference(u - ou, is_pano, params[0]);
            assert!(
                du < 1e-6 && (v - ov).abs() < 1e-6,
                "{model} image {image_id}: COLMAP ({u}, {v}) vs ours ({ou}, {ov})"
            );
            // Exact data: the adjusted block reprojects onto the observations.
            let du_obs = horizontal_difference(u - o[0], is_pano, params[0]);
            assert!(
                du_obs < 1e-3 && (v - o[1]).abs() < 1e-3,
                "{model} image {image_id}: projected ({u}, {v}) observed ({}, {})",
                o[0],
                o[1]
            );
            checked += 1;
        }
    }
    assert_eq!(checked, track_len);
    assert!(checked > 100);
    std::fs::remove_dir_all(&dir).unwrap();
}

//! Importers on hand-written files laid out as the vendors document them (tests/fixtures/import), and the
//! camera-model conversions against the vendors' own projection formulas.

use nalgebra::Vector3;
use skytie_stages::campaign::{read_campaign, AerialImage};
use skytie_stages::crs::{Crs, GridNorth, HorizontalTransform};
use skytie_stages::formats::camera_model::{
    CameraModel, MetashapeCalibration, Pix4dInternals, Pix4dLens,
};
use skytie_stages::formats::sbet::{read_sbet, write_sbet, SbetRecord};
use skytie_stages::geometry::FrameCamera;
use skytie_stages::import::{run_import, ImportConfig};
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/import")
}

fn run(config: &str) -> (PathBuf, String, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("[campaign]\nname = \"fixture\"\ncrs = \"EPSG:28992+5709\"\ngeoid_separation_m = 43.25\n{config}");
    // Resolve paths against the fixture folder as ImportConfig::read would.
    std::fs::write(
        dir.path().join("import.toml"),
        text.replace("\"fixtures", &format!("\"{}", fixtures().display())),
    )
    .unwrap();
    let config = ImportConfig::read(&dir.path().join("import.toml")).unwrap();
    let out = dir.path().join("campaign");
    let report = run_import(&config, &out).unwrap();
    (out, report.to_string(), dir)
}

/// The nadir rows of the campaign imported with `config`, whose report must name `problem` (file, line and
/// field of a row that is refused).
fn import_nadir(config: &str, problem: &str) -> (Vec<AerialImage>, tempfile::TempDir) {
    let (out, report, dir) = run(config);
    assert!(report.contains(problem), "{report}");
    let (c, _) = read_campaign(&out).unwrap();
    (c.nadir, dir)
}

fn camera_of(row: &AerialImage) -> FrameCamera {
    FrameCamera::from_aerial(row)
}

/// A camera-frame point (x right, y up, z backwards) seen by a camera at the origin looking down.
fn world_of_cam(cam: &FrameCamera, p_cam: Vector3<f64>) -> Vector3<f64> {
    cam.center_world + cam.rotation_cam_to_world * p_cam
}

#[test]
fn pix4d_files_by_the_documented_model() {
    // The NaN height of DSC0002 is reported with file, line and field, the other rows imported.
    let (nadir, _dir) = import_nadir("[[aerial]]\nkind = \"nadir\"\nformat = \"pix4d\"\norientations = \"fixtures/pix4d_external.txt\"\ninternals = \"fixtures/pix4d_internal.cam\"\nimages = \"fixtures\"\nimage_width_px = 6000\nimage_height_px = 4000\n", "pix4d_external.txt:3: field 'z'");
    assert_eq!(nadir.len(), 2);
    let a = &nadir[0];
    // Pixel 13.2 mm / 6000 px = 2.2 µm: f = 8.8 / 0.0022 = 4000 px; cx = 6.66 / 0.0022; cy from the bottom.
    assert!((a.focal_px - 4000.0).abs() < 1e-9);
    assert!((a.cx_px - 6.66 / 0.0022).abs() < 1e-9);
    assert!((a.cy_px - (4000.0 - 4.29 / 0.0022)).abs() < 1e-9);
    assert_eq!(
        (a.k1, a.k2, a.k3, a.p1, a.p2),
        (-0.01, 0.02, -0.003, 0.0004, -0.0002)
    );
    assert_eq!((a.x, a.y, a.z), (136_010.5, 455_020.25, 620.0));
    assert!((a.omega_deg - 1.5).abs() < 1e-12 && (a.kappa_deg - 91.25).abs() < 1e-12);
    // Pix4D's projection of a camera-frame point, by its own formulas (lower-left origin, y up) ...
    let cam = camera_of(a);
    let p = Vector3::new(40.0, -25.0, -600.0);
    let (x, y) = (p.x / -p.z, p.y / -p.z);
    let r2 = x * x + y * y;
    let radial = 1.0 - 0.01 * r2 + 0.02 * r2 * r2 - 0.003 * r2 * r2 * r2;
    let xd = x * radial + 2.0 * 0.0004 * x * y - 0.0002 * (r2 + 2.0 * x * x);
    let yd = y * radial + 0.0004 * (r2 + 2.0 * y * y) + 2.0 * -0.0002 * x * y;
    let (u_p4d, v_p4d_up) = (4000.0 * xd + 6.66 / 0.0022, 4000.0 * yd + 4.29 / 0.0022);
    // ... equals skytie's projection of the converted camera (v from the top).
    let (u, v) = cam.project_world(&world_of_cam(&cam, p)).unwrap();
    assert!(
        (u - u_p4d).abs() < 1e-8 && (v - (4000.0 - v_p4d_up)).abs() < 1e-8,
        "{u} {v}"
    );
}

#[test]
fn metashape_opk_matrix_must_match_the_angles() {
    // IMG_2's identity matrix contradicts κ = 90°: refused on its line (4), not guessed.
    let (nadir, _dir) = import_nadir("[[aerial]]\nkind = \"nadir\"\nformat = \"metashape-opk\"\norientations = \"fixtures/metashape_opk.txt\"\nimages = \"fixtures\"\n[aerial.camera]\nfocal_px = 4000\ncx_px = 3000\ncy_px = 2000\nwidth_px = 6000\nheight_px = 4000\n", "metashape_opk.txt:4: field 'r11'");
    assert_eq!(nadir.len(), 1);
    assert!((nadir[0].kappa_deg - 90.0).abs() < 1e-12);
}

#[test]
fn metashape_xml_calibration_and_chunk() {
    // Camera B has no transform (not aligned): reported on its line, skipped.
    let (nadir, _dir) = import_nadir("[[aerial]]\nkind = \"nadir\"\nformat = \"metashape-xml\"\norientations = \"fixtures/metashape_cameras.xml\"\nimages = \"fixtures\"\n", "metashape_cameras.xml:28: field 'transform'");
    assert_eq!(nadir.len(), 1);
    let a = &nadir[0];
    // Calibration: cx, cy offsets from the centre; p1/p2 swapped and y flipped; b2 flipped.
    assert_eq!((a.cx_px, a.cy_px), (510.5, 395.75));
    assert_eq!((a.p1, a.p2, a.b1, a.b2), (0.0002, 0.0003, 0.5, 0.25));
    assert_eq!((a.k3, a.k4), (0.002, -0.0001));
    // The chunk is the east-north-up frame at 52.1°N 5.4°E (Bessel); camera A hangs 1000 m above it looking
    // straight down with its image top to true north: ω = φ = 0 and κ = −(grid azimuth of true north).
    let rd = Crs::parse("EPSG:28992").unwrap();
    let gamma = GridNorth::new(&rd)
        .unwrap()
        .true_north_grid_azimuth_deg(52.1, 5.4)
        .unwrap();
    assert!(a.omega_deg.abs() < 1e-6 && a.phi_deg.abs() < 1e-6, "{a:?}");
    assert!(
        (a.kappa_deg + gamma).abs() < 1e-6,
        "{} vs {}",
        a.kappa_deg,
        -gamma
    );
    let (e, n) = HorizontalTransform::from_own_geographic(&rd)
        .apply(52.1, 5.4)
        .unwrap();
    assert!((a.x - e).abs() < 1e-3 && (a.y - n).abs() < 1e-3);
}

#[test]
fn metashape_model_matches_its_formula_and_round_trips() {
    let m = MetashapeCalibration {
        width_px: 1000,
        height_px: 800,
        f: 2000.0,
        cx: 10.5,
        cy: -4.25,
        b1: 0.5,
        b2: -0.25,
        k1: -0.05,
        k2: 0.01,
        k3: 0.002,
        k4: -0.0001,
        p1: 0.0003,
        p2: -0.0002,
    };
    let model = CameraModel::from_metashape(&m);
    assert_eq!(model.to_metashape(), m);
    let mut row = AerialImage {
        file: "a".into(),
        ..AerialImage::ideal("a", [0.0, 0.0, 100.0], [0.0; 3], 0.0, [0, 0])
    };
    model.apply_to(&mut row);
    let cam = FrameCamera::from_aerial(&row);
    for &(px, py) in &[(0.1, 0.05), (-0.2, 0.15), (0.22, -0.18)] {
        // Metashape camera frame: x right, y down, z forward; point (px, py, 1).
        let (x, y) = (px, py);
        let r2 = x * x + y * y;
        let rad = 1.0 + m.k1 * r2 + m.k2 * r2.powi(2) + m.k3 * r2.powi(3) + m.k4 * r2.powi(4);
        let xd = x * rad + m.p1 * (r2 + 2.0 * x * x) + 2.0 * m.p2 * x * y;
        let yd = y * rad + m.p2 * (r2 + 2.0 * y * y) + 2.0 * m.p1 * x * y;
        let u = 500.0 + m.cx + xd * m.f + xd * m.b1 + yd * m.b2;
        let v = 400.0 + m.cy + yd * m.f;
        // skytie camera frame: (x, −y, −1) in camera axes.
        let p_cam = Vector3::new(px, -py, -1.0) * 50.0;
        let (us, vs) = cam.project_world(&world_of_cam(&cam, p_cam)).unwrap();
        assert!(
            (us - u).abs() < 1e-8 && (vs - v).abs() < 1e-8,
            "({us}, {vs}) vs ({u}, {v})"
        );
        // Project → unproject → project: < 1e-6 px.
        let ray = cam.pixel_to_ray_world(us, vs);
        let (u2, v2) = cam.project_world(&(cam.center_world + ray * 77.0)).unwrap();
        assert!((u2 - us).abs() < 1e-6 && (v2 - vs).abs() < 1e-6);
    }
    let p = Pix4dInternals {
        lens: Pix4dLens {
            focal_mm: 8.8,
            px_mm: 6.6,
            py_mm: 4.4,
            r1: -0.01,
            r2: 0.02,
            r3: 0.0,
            t1: 1e-4,
            t2: 0.0,
        },
        pixel_size_mm: 0.0022,
        width_px: 6000,
        height_px: 4000,
    };
    let back = CameraModel::from_pix4d(&p).to_pix4d(0.0022).unwrap();
    assert!((back.lens.focal_mm - 8.8).abs() < 1e-12 && (back.lens.py_mm - 4.4).abs() < 1e-12);
    assert_eq!(model.to_pix4d(0.0046).unwrap_err(), "k4");
}

#[test]
fn sbet_records_and_bad_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sbet.out");
    let rec = |t: f64| SbetRecord {
        time_sow_s: t,
        lat_rad: 52f64.to_radians(),
        lon_rad: 5f64.to_radians(),
        height_m: 45.0,
        heading_rad: 1.0,
        ..SbetRecord::default()
    };
    write_sbet(
        &path,
        &[rec(100.0), rec(100.005), rec(f64::NAN), rec(100.004)],
    )
    .unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes.len(), 4 * 136);
    // Field 0 of record 1 is the little-endian time.
    assert_eq!(f64::from_le_bytes(bytes[..8].try_into().unwrap()), 100.0);
    let (records, problems) = read_sbet(&path);
    assert_eq!(records.len(), 2);
    assert_eq!(
        problems.iter().map(|p| p.row).collect::<Vec<_>>(),
        vec![Some(3), Some(4)]
    );
    std::fs::write(&path, &bytes[..137]).unwrap();
    let (records, problems) = read_sbet(&path);
    assert!(records.is_empty() && problems[0].message.contains("137 bytes"));
}

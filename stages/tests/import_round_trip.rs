//! Export a known campaign into each vendor format (orientations in RD New, the trajectory as an SBET in
//! ETRS89 geographic coordinates with ellipsoidal heights from a geoid model, panorama headings relative to
//! true north), import it back with `skytie import`'s library entry point, and compare: positions ≤ 1 mm,
//! rotations ≤ 0.0001°, interior orientation exact to rounding.

use nalgebra::Matrix3;
use skytie_stages::campaign::{read_campaign, AerialImage, Campaign, CheckPoint, Recording};
use skytie_stages::crs::geoid::GeoidGrid;
use skytie_stages::formats::opk_list::OpkListFormat;
use skytie_stages::geometry::{opk_to_matrix, panorama_rotation};
use skytie_stages::import::config::CampaignSection;
use skytie_stages::import::context::ImportContext;
use skytie_stages::import::export::{
    export_metashape_xml, export_opk_list, export_pix4d, export_sbet_with_events, ExportError,
    TrajectoryExport,
};
use skytie_stages::import::{run_import, ImportConfig};
use std::path::Path;

const RD_E: f64 = 136_000.0;
const RD_N: f64 = 455_000.0;

fn aerial(id: &str, i: usize, oblique: bool, extended: bool) -> AerialImage {
    let f = i as f64;
    AerialImage {
        k1: -0.12,
        k2: 0.03,
        p1: 2e-4,
        p2: -1e-4,
        k3: if extended { 0.004 } else { -0.002 },
        k4: if extended { -0.0005 } else { 0.0 },
        b1: if extended { 0.8 } else { 0.0 },
        b2: if extended { -0.3 } else { 0.0 },
        cx_px: 3_000.25,
        cy_px: 2_001.75,
        file: format!("{id}.tif"),
        ..AerialImage::ideal(
            id,
            [
                RD_E + 310.5 * f + 0.123,
                RD_N - 150.25 * f + 0.456,
                if oblique { 450.0 } else { 1000.0 + f },
            ],
            [
                if oblique { 44.5 } else { 0.8 - 0.3 * f },
                if oblique { 3.25 } else { -0.6 + 0.2 * f },
                30.0 * f - 80.0,
            ],
            10_000.5,
            [6_000, 4_000],
        )
    }
}

fn recording(i: usize) -> Recording {
    let f = i as f64;
    let time = format!("2019-06-14T10:31:{:02}.250Z", 7 + 2 * i);
    let time_s = skytie_stages::campaign::parse_time_s(&time).unwrap();
    let centre = [
        RD_E + 5.0 * f + 0.0123,
        RD_N + 3.0 * f - 0.0456,
        2.345 + 0.01 * f,
    ];
    Recording {
        time,
        yaw_deg: 1.5 - 0.2 * f,
        pitch_deg: 0.3,
        roll_deg: -0.4 + 0.1 * f,
        ..Recording::new(&format!("pano_{i:03}"), time_s, centre, 59.0 + 0.5 * f, 2.4)
    }
}

fn touch_all(dir: &Path, files: impl IntoIterator<Item = String>) {
    std::fs::create_dir_all(dir).unwrap();
    for f in files {
        std::fs::write(dir.join(f), b"image").unwrap();
    }
}

fn angle_between_deg(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    let c = ((a.transpose() * b).trace() - 1.0) / 2.0;
    c.clamp(-1.0, 1.0).acos().to_degrees()
}

/// The poses (position, world frame, m; rotation) of `orig` and `got` by `pose` within 1 mm and 0.0001° of each
/// other; `what` names the row.
fn assert_pose_close<T>(what: &str, orig: &T, got: &T, pose: fn(&T) -> ([f64; 3], Matrix3<f64>)) {
    let ((o, ro), (g, rg)) = (pose(orig), pose(got));
    let d = ((o[0] - g[0]).powi(2) + (o[1] - g[1]).powi(2) + (o[2] - g[2]).powi(2)).sqrt();
    assert!(d <= 1e-3, "{what}: position off by {d} m");
    let a = angle_between_deg(&ro, &rg);
    assert!(a <= 1e-4, "{what}: rotation off by {a}°");
}

fn aerial_pose(a: &AerialImage) -> ([f64; 3], Matrix3<f64>) {
    (
        [a.x, a.y, a.z],
        opk_to_matrix(a.omega_deg, a.phi_deg, a.kappa_deg),
    )
}

fn panorama_pose(r: &Recording) -> ([f64; 3], Matrix3<f64>) {
    (
        [r.x, r.y, r.z],
        panorama_rotation(r.yaw_deg, r.pitch_deg, r.roll_deg),
    )
}

fn assert_aerial_equal(orig: &[AerialImage], got: &[AerialImage], what: &str) {
    assert_eq!(orig.len(), got.len(), "{what}: row count");
    for o in orig {
        let g = got
            .iter()
            .find(|g| g.image_id == o.image_id)
            .unwrap_or_else(|| panic!("{what}: {} missing", o.image_id));
        assert_pose_close(&format!("{what} {}", o.image_id), o, g, aerial_pose);
        for (name, x, y) in [
            ("focal", o.focal_px, g.focal_px),
            ("cx", o.cx_px, g.cx_px),
            ("cy", o.cy_px, g.cy_px),
            ("k1", o.k1, g.k1),
            ("k2", o.k2, g.k2),
            ("k3", o.k3, g.k3),
            ("k4", o.k4, g.k4),
            ("p1", o.p1, g.p1),
            ("p2", o.p2, g.p2),
            ("b1", o.b1, g.b1),
            ("b2", o.b2, g.b2),
        ] {
            assert!(
                (x - y).abs() <= 1e-9 * (1.0 + x.abs()),
                "{what} {}: {name} {x} vs {y}",
                o.image_id
            );
        }
        assert_eq!((o.width_px, o.height_px), (g.width_px, g.height_px));
    }
}

/// A scratch folder holding an (empty) image file for every row, as an import expects.
fn with_images(rows: &[AerialImage]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    touch_all(
        &dir.path().join("images"),
        rows.iter().map(|r| r.file.clone()),
    );
    dir
}

/// The campaign `t` in RD New + NAP, with a constant geoid separation or none.
fn section(geoid_separation_m: Option<f64>) -> CampaignSection {
    CampaignSection {
        name: "t".into(),
        crs: "EPSG:28992+5709".into(),
        geoid_grid: None,
        geoid_separation_m,
        datum_grid: None,
        frame: Default::default(),
    }
}

fn context(geoid_separation_m: f64) -> ImportContext {
    ImportContext::new(&section(Some(geoid_separation_m))).unwrap()
}

fn import(dir: &Path, config: &str) -> Campaign {
    let cfg_path = dir.join("import.toml");
    std::fs::write(&cfg_path, config).unwrap();
    let config = ImportConfig::read(&cfg_path).unwrap();
    let out = dir.join("campaign");
    let report = run_import(&config, &out).unwrap();
    assert_eq!(report.skipped(), 0, "{report}");
    let (campaign, problems) = read_campaign(&out).unwrap();
    // An aerial-only import has no recordings yet; everything else must read back cleanly.
    assert!(
        problems
            .iter()
            .all(|p| p.severity != skytie_stages::campaign::Severity::Error
                || p.file == Path::new("mm/recordings.csv")),
        "{problems:?}"
    );
    campaign
}

const CAMPAIGN: &str =
    "[campaign]\nname = \"round trip\"\ncrs = \"EPSG:28992+5709\"\ngeoid_separation_m = 43.25\n";

/// Four aerial rows `<prefix>0` … `<prefix>3` (see [`aerial`]).
fn four_aerials(prefix: &str, oblique: bool, extended: bool) -> Vec<AerialImage> {
    (0..4)
        .map(|i| aerial(&format!("{prefix}{i}"), i, oblique, extended))
        .collect()
}

/// The campaign of one `[[aerial]]` table of `kind` and `format` in `dir`, its further keys in `keys`.
fn import_aerial(dir: &Path, kind: &str, format: &str, keys: &str) -> Campaign {
    import(
        dir,
        &format!("{CAMPAIGN}[[aerial]]\nkind = \"{kind}\"\nformat = \"{format}\"\n{keys}"),
    )
}

/// `rows` exported by `export` (given the campaign context with a 43.25 m geoid separation, the export CRS
/// EPSG:28992 and a scratch folder holding the rows' image files), then imported back as one `[[aerial]]`
/// table of `kind` and `format` with the further `keys`.
fn export_and_import(
    rows: &[AerialImage],
    export: impl FnOnce(&ImportContext, &str, &Path) -> Result<(), ExportError>,
    kind: &str,
    format: &str,
    keys: &str,
) -> Campaign {
    let dir = with_images(rows);
    export(&context(43.25), "EPSG:28992", dir.path()).unwrap();
    import_aerial(dir.path(), kind, format, keys)
}

#[test]
fn pix4d_round_trip() {
    let rows = four_aerials("n", false, false);
    let export = |ctx: &ImportContext, crs: &str, dir: &Path| {
        export_pix4d(&rows, ctx, crs, 0.0046, dir, "proj")
    };
    let got = export_and_import(&rows, export, "nadir", "pix4d", "orientations = \"proj_calibrated_external_camera_parameters.txt\"\ninternals = \"proj_pix4d_calibrated_internal_camera_parameters.cam\"\nimages = \"images\"\ncrs = \"EPSG:28992+5709\"\nimage_width_px = 6000\nimage_height_px = 4000\n");
    assert_aerial_equal(&rows, &got.nadir, "pix4d");
}

#[test]
fn metashape_xml_round_trip_through_earth_centred_chunk() {
    let rows = four_aerials("o", true, true);
    let got = export_and_import(
        &rows,
        |ctx, crs, dir| export_metashape_xml(&rows, ctx, crs, &dir.join("cameras.xml")),
        "oblique",
        "metashape-xml",
        "orientations = \"cameras.xml\"\nimages = \"images\"\n",
    );
    assert_aerial_equal(&rows, &got.oblique, "metashape-xml");
}

#[test]
fn metashape_opk_and_generic_lists_round_trip() {
    let rows = four_aerials("n", false, true);
    let camera = "[aerial.camera]\nfocal_px = 10000.5\ncx_px = 3000.25\ncy_px = 2001.75\nwidth_px = 6000\nheight_px = 4000\nk1 = -0.12\nk2 = 0.03\nk3 = 0.004\nk4 = -0.0005\np1 = 2e-4\np2 = -1e-4\nb1 = 0.8\nb2 = -0.3\n";
    // Metashape ω-φ-κ export.
    let got = export_and_import(
        &rows,
        |ctx, crs, dir| {
            let format = OpkListFormat::metashape();
            export_opk_list(&rows, ctx, crs, &format, &dir.join("opk.txt"))
        },
        "nadir",
        "metashape-opk",
        &format!("orientations = \"opk.txt\"\nimages = \"images\"\n{camera}"),
    );
    assert_aerial_equal(&rows, &got.nadir, "metashape-opk");
    // A classical AT list: semicolons, no header, gon, yaw-pitch-roll, columns by position.
    let layout = OpkListFormat::at_list();
    let export = |ctx: &ImportContext, crs: &str, dir: &Path| {
        export_opk_list(&rows, ctx, crs, &layout, &dir.join("at.txt"))
    };
    let layout_toml = "[aerial.layout]\ndelimiter = \"semicolon\"\nheader = false\nangle_unit = \"gon\"\nattitude = \"yaw-pitch-roll\"\n[aerial.layout.columns]\nimage = \"1\"\nx = \"2\"\ny = \"3\"\nz = \"4\"\nangles = [\"5\", \"6\", \"7\"]\n";
    let got = export_and_import(
        &rows,
        export,
        "nadir",
        "opk-list",
        &format!("orientations = \"at.txt\"\nimages = \"images\"\n{layout_toml}{camera}"),
    );
    assert_aerial_equal(&rows, &got.nadir, "opk-list");
}

fn assert_recordings_equal(orig: &[Recording], got: &[Recording]) {
    assert_eq!(orig.len(), got.len());
    for o in orig {
        let g = got.iter().find(|g| g.image_id == o.image_id).unwrap();
        assert_pose_close(&format!("{} panorama", o.image_id), o, g, panorama_pose);
        let dh = (o.heading_deg - g.heading_deg + 180.0).rem_euclid(360.0) - 180.0;
        assert!(
            dh.abs() <= 1e-4,
            "{}: heading {} vs {}",
            o.image_id,
            o.heading_deg,
            g.heading_deg
        );
        assert_eq!(o.time, g.time);
        assert_eq!(o.camera_height_m, g.camera_height_m);
    }
}

fn sbet_round_trip(geoid_line: &str, geoid: Option<&GeoidGrid>) {
    let dir = tempfile::tempdir().unwrap();
    let recs: Vec<Recording> = (0..6).map(recording).collect();
    touch_all(
        &dir.path().join("panos"),
        recs.iter().map(|r| r.file.clone()),
    );
    let mut section = section(None);
    if let Some(g) = geoid {
        std::fs::write(dir.path().join("geoid.gtx"), g.to_gtx_bytes()).unwrap();
        section.geoid_grid = Some(dir.path().join("geoid.gtx"));
    } else {
        section.geoid_separation_m = Some(43.25);
    }
    let ctx = ImportContext::new(&section).unwrap();
    let spec = TrajectoryExport {
        crs: "EPSG:4937".into(),
        lever_arm_m: [0.35, -0.12, -1.85],
        leap_seconds: None,
    };
    let week = export_sbet_with_events(
        &recs,
        &ctx,
        &spec,
        &dir.path().join("sbet.out"),
        &dir.path().join("events.csv"),
    )
    .unwrap();
    let config = format!(
        "[campaign]\nname = \"round trip\"\ncrs = \"EPSG:28992+5709\"\n{geoid_line}\n[mm]\ntrajectory = \"sbet.out\"\nformat = \"sbet\"\ncrs = \"EPSG:4937\"\nheights = \"ellipsoidal\"\ngps_week = {week}\nevents = \"events.csv\"\norientation = \"event-columns\"\npano_columns = [\"pano_heading\", \"pano_pitch\", \"pano_roll\"]\npanoramas = \"panos\"\ncamera_height_m = 2.4\nlever_arm_m = [0.35, -0.12, -1.85]\n[mm.event_layout]\ndelimiter = \"comma\"\ntime_column = \"time\"\nimage_column = \"image\"\ntime = {{ system = \"gps-seconds-of-week\", gps_week = {week} }}\n"
    );
    let got = import(dir.path(), &config);
    assert_recordings_equal(&recs, &got.recordings);
}

#[test]
fn sbet_round_trip_with_constant_geoid() {
    sbet_round_trip("geoid_separation_m = 43.25", None);
}

#[test]
fn sbet_round_trip_with_geoid_grid() {
    let grid = GeoidGrid {
        path: "geoid.gtx".into(),
        south_lat_deg: 51.0,
        west_lon_deg: 4.0,
        dlat_deg: 0.5,
        dlon_deg: 0.5,
        rows: 5,
        cols: 5,
        values_m: (0..25).map(|i| 42.0 + 0.1 * i as f32).collect(),
    };
    sbet_round_trip("geoid_grid = \"geoid.gtx\"", Some(&grid));
}

#[test]
fn control_points_import_in_another_crs() {
    let dir = tempfile::tempdir().unwrap();
    // ETRS89 / UTM 31N with ellipsoidal heights → RD New + NAP with a constant separation.
    let ctx = context(43.25);
    let original = CheckPoint {
        point_id: "cp1".into(),
        x: RD_E + 12.5,
        y: RD_N - 7.25,
        z: 1.75,
        sigma_xy_m: Some(0.01),
        sigma_z_m: Some(0.02),
    };
    let poses = skytie_stages::import::export::aerial_poses(
        &[AerialImage {
            x: original.x,
            y: original.y,
            z: original.z,
            ..aerial("p", 0, false, false)
        }],
        &ctx,
        "EPSG:25831",
        "ellipsoidal",
    )
    .unwrap();
    let p = &poses[0];
    std::fs::write(
        dir.path().join("points.csv"),
        format!(
            "id,e,n,h,sxy,sz\ncp1,{},{},{},0.01,0.02\ncp2,abc,1,2,0.01,0.02\n",
            p.a, p.b, p.z
        ),
    )
    .unwrap();
    let cfg_path = dir.path().join("import.toml");
    std::fs::write(&cfg_path, format!("{CAMPAIGN}[control]\npoints = \"points.csv\"\ncrs = \"EPSG:25831\"\nheights = \"ellipsoidal\"\n[control.layout]\ndelimiter = \"comma\"\nid = \"id\"\nx = \"e\"\ny = \"n\"\nz = \"h\"\nsigma_xy = \"sxy\"\nsigma_z = \"sz\"\n")).unwrap();
    let config = ImportConfig::read(&cfg_path).unwrap();
    let report = run_import(&config, &dir.path().join("c")).unwrap();
    // The bad row is skipped and named.
    assert_eq!(report.skipped(), 1, "{report}");
    let text = report.to_string();
    assert!(
        text.contains("points.csv:3") && text.contains("field 'e'"),
        "{text}"
    );
    let (c, _) = read_campaign(&dir.path().join("c")).unwrap();
    let g = &c.checkpoints[0];
    let d = ((g.x - original.x).powi(2) + (g.y - original.y).powi(2) + (g.z - original.z).powi(2))
        .sqrt();
    assert!(d < 1e-3, "{d}");
}

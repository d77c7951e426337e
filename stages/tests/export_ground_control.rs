//! Ground-control exports read back by readers that follow each tool's documented format: OpenSfM's
//! `gcp_list.txt` rules (projection line `WGS84`, `WGS84 UTM <zone>`, a PROJ string or `EPSG:<code>`; then
//! `x y z px py image [extras]`, `#` comments, pixel centres on integers), Metashape's reference CSV
//! (`nxyzXYZ`) and projection list. The fixture lines are the documentation's own examples.

use skytie_stages::adjustment::relative_noise::RelativeSigma;
use skytie_stages::adjustment::{
    AdjustConfig, AdjustmentRun, BlockPoint, BuildCounts, ObservationCounts, PointKind, RunPoint,
};
use skytie_stages::campaign::{AerialImage, AerialKind, Campaign, Recording};
use skytie_stages::correspondence::{AerialControlPoint, AerialObservation, PanoObservation};
use skytie_stages::export::{opensfm_projection, write_ground_control};

/// One parsed `gcp_list.txt` observation: x, y, z, px, py, image, extras.
type GcpLine = (f64, f64, f64, f64, f64, String, Vec<String>);

/// A reader of `gcp_list.txt` as OpenSfM documents it; Err names the line.
fn read_gcp_list(text: &str) -> Result<(String, Vec<GcpLine>), String> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let (_, projection) = lines.next().ok_or("empty file")?;
    let p = projection.trim();
    let known = p == "WGS84"
        || p.to_uppercase().starts_with("WGS84 UTM")
        || p.contains("+proj")
        || p.to_uppercase().starts_with("EPSG:");
    if !known {
        return Err(format!("line 1: unsupported projection '{p}'"));
    }
    let mut out = Vec::new();
    for (i, l) in lines {
        let words: Vec<&str> = l.split_whitespace().collect();
        if words.len() < 6 {
            return Err(format!("line {}: {} fields, need 6", i + 1, words.len()));
        }
        let n = |k: usize| {
            words[k]
                .parse::<f64>()
                .map_err(|e| format!("line {}: field {}: {e}", i + 1, k + 1))
        };
        out.push((
            n(0)?,
            n(1)?,
            n(2)?,
            n(3)?,
            n(4)?,
            words[5].to_string(),
            words[6..].iter().map(|s| s.to_string()).collect(),
        ));
    }
    Ok((p.to_string(), out))
}

#[test]
fn the_reader_accepts_the_documented_examples() {
    // OpenDroneMap's documentation example (UTM 17N by EPSG code), and OpenSfM's UTM form.
    let doc = "EPSG:32617\n\
               # comment lines are allowed\n\
               274914.738 4603349.014 400 3044 2622 IMG_0525.jpg gcp1\n";
    let (p, lines) = read_gcp_list(doc).unwrap();
    assert_eq!(p, "EPSG:32617");
    assert_eq!(lines[0].5, "IMG_0525.jpg");
    assert_eq!(lines[0].6, ["gcp1"]);
    let (_, l) = read_gcp_list("WGS84 UTM 32N\n481367 5782936 100 10 20 a.jpg\n").unwrap();
    assert_eq!(l.len(), 1);
    assert!(read_gcp_list("RD New\n1 2 3 4 5 a.jpg\n").is_err());
}

fn campaign(crs: &str) -> Campaign {
    let rec = |id: &str, file: &str| Recording {
        file: file.into(),
        time: "2020-01-01T00:00:00Z".into(),
        ..Recording::new(id, 1_577_836_800.0, [1.0, 2.0, 3.0], 0.0, 2.5)
    };
    let nadir = |id: &str, file: &str| AerialImage {
        file: file.into(),
        ..AerialImage::ideal(id, [0.0, 0.0, 4000.0], [0.0; 3], 10000.0, [4000, 3000])
    };
    Campaign {
        crs: crs.into(),
        recordings: vec![rec("p1", "pano 1.jpg"), rec("p2", "sub/p2.jpg")],
        nadir: vec![nadir("n1", "n1.tif"), nadir("n2", "n2.tif")],
        ..Campaign::default()
    }
}

fn control() -> Vec<AerialControlPoint> {
    let aerial = |id: &str, u: f64, v: f64| AerialObservation {
        image_id: id.into(),
        kind: AerialKind::Nadir,
        u_px: u,
        v_px: v,
        score: 0.9,
        sigma_px: None,
    };
    vec![
        AerialControlPoint {
            map: None,
            ray_ground: None,
            tie_point_id: "t 1".into(),
            mm: vec![
                PanoObservation {
                    image_id: "p1".into(),
                    u_px: 100.5,
                    v_px: 200.25,
                },
                PanoObservation {
                    image_id: "p2".into(),
                    u_px: 110.0,
                    v_px: 210.0,
                },
            ],
            aerial: vec![aerial("n1", 1000.5, 800.5), aerial("n2", 900.0, 700.0)],
            point_world: Some([85000.125, 445000.5, 1.25]),
            covariance_m2: Some([[0.0004, 0.0, 0.0], [0.0, 0.0009, 0.0], [0.0, 0.0, 0.25]]),
        },
        AerialControlPoint {
            map: None,
            ray_ground: None,
            tie_point_id: "t2".into(),
            mm: vec![],
            aerial: vec![aerial("n1", 1.0, 1.0)],
            point_world: None,
            covariance_m2: None,
        },
    ]
}

#[test]
fn gcp_list_metashape_and_plain_list_read_back() {
    let d = tempfile::tempdir().unwrap();
    let c = campaign("EPSG:28992");
    let pts = control();
    let e = write_ground_control(d.path(), &c, &[("nadir", &pts)], None).unwrap();
    assert_eq!(
        (e.points, e.observations, e.skipped_single_aerial),
        (1, 4, 1)
    );
    assert_eq!(e.gcp_list_skipped, None);

    let text = std::fs::read_to_string(d.path().join("gcp_list.txt")).unwrap();
    let (projection, lines) = read_gcp_list(&text).unwrap();
    assert_eq!(projection, "EPSG:28992");
    // A file name with a space cannot be a white-space separated field: that observation is left out, counted.
    let images: Vec<&str> = lines.iter().map(|l| l.5.as_str()).collect();
    assert_eq!(images, ["sub/p2.jpg", "n1.tif", "n2.tif"]);
    assert_eq!(e.gcp_list_skipped_names, 1);
    let n1 = &lines[1];
    assert_eq!((n1.0, n1.1, n1.2), (85000.125, 445000.5, 1.25));
    // OpenSfM pixel convention: the first pixel's centre is (0, 0).
    assert_eq!((n1.3, n1.4), (1000.0, 800.0));
    assert_eq!(n1.6, ["nadir_t_1"]);

    let mut r = csv::Reader::from_path(d.path().join("metashape_reference.csv")).unwrap();
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 1);
    assert_eq!(
        rows[0].iter().collect::<Vec<_>>(),
        [
            "nadir_t_1",
            "85000.125",
            "445000.5",
            "1.25",
            "0.02",
            "0.03",
            "0.5"
        ]
    );
    let mut r = csv::Reader::from_path(d.path().join("metashape_projections.csv")).unwrap();
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 4);
    assert_eq!(
        rows[0].iter().collect::<Vec<_>>(),
        ["nadir_t_1", "pano 1", "pano 1.jpg", "100.5", "200.25"]
    );
    assert_eq!(&rows[1][1], "p2");

    let mut r = csv::Reader::from_path(d.path().join("control_points.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 1);
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    assert_eq!(&rows[0][col("aerial_observations")], "2");
    assert_eq!(&rows[0][col("panorama_observations")], "2");
    assert_eq!(&rows[0][col("residual_x")], "", "no adjustment given");
}

#[test]
fn an_unknown_crs_skips_gcp_list_with_a_reason() {
    let d = tempfile::tempdir().unwrap();
    let pts = control();
    let e =
        write_ground_control(d.path(), &campaign("local grid"), &[("nadir", &pts)], None).unwrap();
    assert!(e.gcp_list_skipped.unwrap().contains("local grid"));
    assert!(!d.path().join("gcp_list.txt").exists());
    assert!(d.path().join("control_points.csv").exists());
    assert_eq!(opensfm_projection("epsg:25832").unwrap(), "EPSG:25832");
    assert!(opensfm_projection("+proj=utm +zone=32 +ellps=GRS80").is_ok());
}

/// An adjustment that used control point `used`, kept `left_out` as a mere tie point (its checks left the
/// control out) and rejected an aerial observation of `rejected`, all determined.
fn run_with(used: &str, left_out: &str, rejected: &str) -> AdjustmentRun {
    let point = |id: &str, kind: PointKind, at: [f64; 3]| RunPoint {
        point: BlockPoint {
            id: id.into(),
            kind,
            pano: Vec::new(),
            aerial: Vec::new(),
        },
        position_world: at,
        determined: true,
        control_rejected: false,
    };
    AdjustmentRun {
        config: AdjustConfig::default(),
        recordings: Vec::new(),
        points: vec![
            point(used, PointKind::Control, [85000.225, 445000.5, 1.25]),
            point(left_out, PointKind::Tie, [85002.0, 445001.0, 1.0]),
            RunPoint {
                control_rejected: true,
                ..point(rejected, PointKind::Control, [85003.0, 445000.0, 1.0])
            },
        ],
        aerial_images: Vec::new(),
        iterations: 0,
        termination: String::new(),
        observations: ObservationCounts::default(),
        rejected: ObservationCounts::default(),
        rejected_total: 0,
        final_cost: 0.0,
        variance_factor: None,
        redundancy: 0,
        rejection_rounds: 0,
        build: BuildCounts::default(),
        relative_sigma: RelativeSigma::default(),
        yaw_chains: Vec::new(),
    }
}

#[test]
fn control_the_adjustment_left_out_is_listed_but_not_handed_to_other_tools() {
    let mut pts = control();
    for (id, at) in [
        ("t 9", [85001.0, 445000.0, 1.0]),
        ("t 8", [85001.0, 445000.0, 1.0]),
    ] {
        let mut wrong = pts[0].clone();
        wrong.tie_point_id = id.into();
        wrong.point_world = Some(at);
        pts.push(wrong);
    }
    let d = tempfile::tempdir().unwrap();
    let c = campaign("EPSG:28992");
    let run = run_with("t 1", "t 9", "t 8");
    let e = write_ground_control(d.path(), &c, &[("nadir", &pts)], Some(&run)).unwrap();
    assert_eq!(
        (e.points, e.observations, e.left_out_by_adjustment),
        (1, 4, 2)
    );
    let text = std::fs::read_to_string(d.path().join("gcp_list.txt")).unwrap();
    let (_, lines) = read_gcp_list(&text).unwrap();
    assert!(lines.iter().all(|l| l.6 == ["nadir_t_1"]), "{text}");
    let reference = std::fs::read_to_string(d.path().join("metashape_reference.csv")).unwrap();
    assert!(
        !reference.contains("t_9") && !reference.contains("t_8"),
        "{reference}"
    );
    let projections = std::fs::read_to_string(d.path().join("metashape_projections.csv")).unwrap();
    assert!(
        !projections.contains("t_9") && !projections.contains("t_8"),
        "{projections}"
    );

    let mut r = csv::Reader::from_path(d.path().join("control_points.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    let row = |label: &str| rows.iter().find(|r| &r[0] == label).unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!(&row("nadir_t_1")[col("status")], "used");
    assert_eq!(&row("nadir_t_8")[col("status")], "rejected");
    let rx: f64 = row("nadir_t_1")[col("residual_x")].parse().unwrap();
    assert!((rx - 0.1).abs() < 1e-9, "{rx}");
    // The left-out point keeps its residual: how far the adjustment put it from its aerial triangulation.
    assert_eq!(&row("nadir_t_9")[col("status")], "left_out");
    let rx: f64 = row("nadir_t_9")[col("residual_x")].parse().unwrap();
    assert!((rx - 1.0).abs() < 1e-9, "{rx}");
}

#[test]
fn without_an_adjustment_every_control_point_is_handed_on_as_not_adjusted() {
    let d = tempfile::tempdir().unwrap();
    let pts = control();
    let e =
        write_ground_control(d.path(), &campaign("EPSG:28992"), &[("nadir", &pts)], None).unwrap();
    assert_eq!(e.left_out_by_adjustment, 0);
    let mut r = csv::Reader::from_path(d.path().join("control_points.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let status = h.iter().position(|x| x == "status").unwrap();
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert!(rows.iter().all(|r| &r[status] == "not_adjusted"));
}

//! Known-answer tests of campaign reading and checking: a valid campaign written by the writers reads back
//! equal and checks clean; a corpus of broken campaigns reports every problem with its exact file, row and
//! field, all at once, while the good rows are still returned.

use skytie_stages::campaign::{
    check_campaign, read_campaign, read_recordings_csv, write_aerial_cameras_csv,
    write_campaign_toml, write_checkpoints_csv, write_observations_csv, write_recordings_csv,
    write_trajectory_adjusted_csv, AerialImage, Campaign, CampaignError, CheckPoint, Observation,
    Problem, Recording, Severity,
};
use skytie_stages::imaging::io::save_rgb;
use skytie_stages::imaging::RgbImage;
use std::path::Path;
use support::campaign_files::image;

mod support;

fn recording(i: usize, file: &str) -> Recording {
    Recording {
        file: file.into(),
        time: format!("2019-06-14T10:31:{:02}.250Z", 7 + i),
        sigma_xy_m: if i == 1 { Some(0.8) } else { None },
        sigma_z_m: if i == 2 { Some(1.5) } else { None },
        yaw_deg: if i == 3 { 0.35 } else { 0.0 },
        roll_deg: if i == 3 { -0.1 } else { 0.0 },
        ..Recording::new(
            &format!("pano_{i}"),
            1_560_508_267.25 + i as f64,
            [
                155_000.123_456_789 + 5.0 * i as f64,
                463_000.1 + 0.01 * i as f64,
                2.5 + 0.1 * i as f64,
            ],
            89.5,
            2.4,
        )
    }
}

fn aerial(id: &str, file: &str) -> AerialImage {
    AerialImage {
        file: file.into(),
        ..AerialImage::ideal(id, [155_007.5, 463_000.0, 300.0], [0.0; 3], 100.0, [80, 60])
    }
}

/// A small valid campaign written with the writers; returns what was written.
fn write_valid_campaign(root: &Path) -> Campaign {
    let recordings: Vec<Recording> = (0..4)
        .map(|i| {
            recording(
                i,
                &format!("sub/pano_{i}.{}", if i % 2 == 0 { "jpg" } else { "png" }),
            )
        })
        .collect();
    for r in &recordings {
        image(&root.join("mm/panoramas").join(&r.file), 64, 32);
    }
    let nadir = vec![aerial("n0", "n0.png")];
    // Looks north and 45° down from 300 m south of the trajectory: R = Rx(45°), view axis (0, sin45, −cos45).
    let oblique = vec![AerialImage {
        y: 462_700.0,
        omega_deg: 45.0,
        kappa_deg: 0.5,
        k1: -0.05,
        p2: 1e-4,
        sigma_px: 0.7,
        ..aerial("o0", "o0.jpg")
    }];
    image(&root.join("aerial/nadir/n0.png"), 80, 60);
    image(&root.join("aerial/oblique/o0.jpg"), 80, 60);
    let checkpoints = vec![
        CheckPoint {
            point_id: "c1".into(),
            x: 155_001.0,
            y: 463_004.5,
            z: 0.25,
            sigma_xy_m: Some(0.01),
            sigma_z_m: None,
        },
        CheckPoint {
            point_id: "c2".into(),
            x: 155_011.0,
            y: 462_996.0,
            z: 0.5,
            sigma_xy_m: None,
            sigma_z_m: None,
        },
    ];
    let observations = vec![
        Observation {
            point_id: "c1".into(),
            image_id: "pano_0".into(),
            u_px: 33.5,
            v_px: 20.25,
        },
        Observation {
            point_id: "c1".into(),
            image_id: "pano_1".into(),
            u_px: 30.0,
            v_px: 19.0,
        },
        Observation {
            point_id: "c2".into(),
            image_id: "pano_2".into(),
            u_px: 63.9,
            v_px: 32.0,
        },
    ];
    write_campaign_toml(
        &root.join("campaign.toml"),
        "Teststraat",
        "EPSG:28992",
        Default::default(),
    )
    .unwrap();
    write_recordings_csv(&root.join("mm/recordings.csv"), &recordings).unwrap();
    write_aerial_cameras_csv(&root.join("aerial/nadir/cameras.csv"), &nadir).unwrap();
    write_aerial_cameras_csv(&root.join("aerial/oblique/cameras.csv"), &oblique).unwrap();
    write_checkpoints_csv(&root.join("control/checkpoints.csv"), &checkpoints).unwrap();
    write_observations_csv(&root.join("control/observations.csv"), &observations).unwrap();
    Campaign {
        root: root.to_path_buf(),
        name: "Teststraat".into(),
        crs: "EPSG:28992".into(),
        frame: Default::default(),
        recordings,
        nadir,
        oblique,
        checkpoints,
        observations,
        orthophoto: None,
        dtm: None,
    }
}

/// (file, row, field, severity) of each problem, for exact comparison.
fn keys(problems: &[Problem]) -> Vec<(String, Option<usize>, Option<String>, Severity)> {
    problems
        .iter()
        .map(|p| {
            (
                p.file.to_string_lossy().into_owned(),
                p.row,
                p.field.clone(),
                p.severity,
            )
        })
        .collect()
}

fn key(
    file: &str,
    row: usize,
    field: &str,
    severity: Severity,
) -> (String, Option<usize>, Option<String>, Severity) {
    (
        file.to_string(),
        Some(row),
        Some(field.to_string()),
        severity,
    )
}

/// Writes `text` to `root/rel`, creating its folder.
fn write_text(root: &Path, rel: &str, text: &str) {
    let path = root.join(rel);
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).unwrap();
    }
    std::fs::write(path, text).unwrap();
}

/// `p`'s message contains `part` (the problem is shown when not).
fn assert_mentions(p: &Problem, part: &str) {
    assert!(p.message.contains(part), "{p}");
}

fn find<'a>(problems: &'a [Problem], file: &str, row: usize, field: &str) -> &'a Problem {
    problems
        .iter()
        .find(|p| {
            p.file == Path::new(file) && p.row == Some(row) && p.field.as_deref() == Some(field)
        })
        .unwrap_or_else(|| panic!("no problem at {file}:{row} '{field}' in {problems:#?}"))
}

#[test]
fn valid_campaign_round_trips_and_checks_clean() {
    let dir = tempfile::tempdir().unwrap();
    let written = write_valid_campaign(dir.path());
    let (read, problems) = read_campaign(dir.path()).unwrap();
    assert!(problems.is_empty(), "{problems:#?}");
    assert_eq!(read, written);
    let report = check_campaign(dir.path());
    assert!(report.is_clean(), "{}", report.render());
    assert_eq!(
        (
            report.recordings,
            report.nadir,
            report.oblique,
            report.checkpoints,
            report.observations
        ),
        (4, 1, 1, 2, 3)
    );
    assert_eq!(
        report.render(),
        "clean: 4 recordings, 1 nadir and 1 oblique images, 2 check points, 3 observations usable\n"
    );
}

#[test]
fn recordings_are_sorted_by_time_whatever_the_file_order() {
    let dir = tempfile::tempdir().unwrap();
    let mut written = write_valid_campaign(dir.path());
    let mut shuffled = written.recordings.clone();
    shuffled.swap(0, 3);
    shuffled.swap(1, 2);
    write_recordings_csv(&dir.path().join("mm/recordings.csv"), &shuffled).unwrap();
    let (read, problems) = read_campaign(dir.path()).unwrap();
    assert_eq!(read.recordings, written.recordings);
    written.recordings = shuffled;
    // File rows 3 (pano_2 after pano_3), 4 (pano_1 after pano_2) and 5 (pano_0 after pano_1) go back in time.
    assert_eq!(
        keys(&problems),
        [3, 4, 5].map(|row| key("mm/recordings.csv", row, "time", Severity::Warning))
    );
    assert_mentions(&problems[0], "is before the time on row 2");
}

#[test]
fn tolerates_bom_crlf_comments_reordered_and_unknown_columns() {
    let dir = tempfile::tempdir().unwrap();
    let written = write_valid_campaign(dir.path());
    let r = &written.recordings;
    let mut text = String::from("\u{feff}# exported by SomeTool 3.1\r\n#\r\n");
    text.push_str(
        "operator,time,camera_height,heading,z,y,x,file,image_id,sigma_z,yaw,roll,sigma_xy\r\n",
    );
    for (i, rec) in r.iter().enumerate() {
        if i == 2 {
            text.push_str("# the next row was re-driven\r\n\r\n");
        }
        let opt = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
        text.push_str(&format!(
            "ann,{},{},{},{},{},{},{},{},{},{},{},{}\r\n",
            rec.time,
            rec.camera_height_m,
            rec.heading_deg,
            rec.z,
            rec.y,
            rec.x,
            rec.file,
            rec.image_id,
            opt(rec.sigma_z_m),
            rec.yaw_deg,
            rec.roll_deg,
            opt(rec.sigma_xy_m)
        ));
    }
    std::fs::write(dir.path().join("mm/recordings.csv"), text).unwrap();
    let (read, problems) = read_campaign(dir.path()).unwrap();
    assert!(problems.is_empty(), "{problems:#?}");
    assert_eq!(read, written);
    assert!(check_campaign(dir.path()).is_clean());
}

#[test]
fn broken_campaign_reports_every_problem_with_file_row_field() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    let pano = root.join("mm/panoramas");
    for name in [
        "p0.jpg", "p1.jpg", "p2.jpg", "p3.jpg", "p4.jpg", "p5.jpg", "p6.jpg", "p7.jpg", "p8.jpg",
        "p12.jpg",
    ] {
        image(&pano.join(name), 64, 32);
    }
    image(&pano.join("wide.png"), 64, 64);
    save_rgb(
        &pano.join("trunc.jpg"),
        &RgbImage::filled(64, 64, [0.3, 0.4, 0.5]),
        90,
    )
    .unwrap();
    let bytes = std::fs::read(pano.join("trunc.jpg")).unwrap();
    std::fs::write(pano.join("trunc.jpg"), &bytes[..bytes.len() / 3]).unwrap();

    // campaign.toml without crs.
    write_text(root, "campaign.toml", "name = \"broken\"\n");
    let recordings = "\
# exported by SomeTool
# second comment
file,image_id,x,y,z,heading,camera_height,time,operator
p0.jpg,p0,155000,463000,2.5,90,2.5,2019-06-14T10:31:07.000Z,ann
p1.jpg,p1,abc,463000,2.5,90,2.5,2019-06-14T10:31:08Z,ann
# comment between rows
p2.jpg,p2,155010,NaN,2.5,90,2.5,2019-06-14T10:31:09Z,ann
p3.jpg,p3,155015,463000,inf,90,2.5,2019-06-14T10:31:10Z,ann
p4.jpg,p4,155020,463000,2.5,,2.5,2019-06-14T10:31:11Z,ann
p5.jpg,p5,155025,463000,2.5,90,0,2019-06-14T10:31:12Z,ann
p6.jpg,p6,155030,463000,2.5,90,2.5,yesterday,ann
p7.jpg,p7,155035,463000,2.5,90,2.5,2019-06-14T10:31:13Z,ann
p8.jpg,p7,155040,463000,2.5,90,2.5,2019-06-14T10:31:14Z,ann
missing.jpg,p9,155045,463000,2.5,90,2.5,2019-06-14T10:31:15Z,ann
trunc.jpg,p10,155050,463000,2.5,90,2.5,2019-06-14T10:31:16Z,ann
wide.png,p11,155055,463000,2.5,90,2.5,2019-06-14T10:31:17Z,ann
p12.jpg,p12,155060,463000,2.5,90,2.5,2019-06-14T11:31:16.500+01:00,ann
";
    write_text(root, "mm/recordings.csv", recordings);

    let nadir_dir = root.join("aerial/nadir");
    for name in ["n0.png", "n1.png", "n2.png", "n3.png", "n4.png", "n5.png"] {
        image(&nadir_dir.join(name), 80, 60);
    }
    // BOM and CRLF line ends in this file.
    let nadir = "\u{feff}image_id,file,x,y,z,omega,phi,kappa,focal_px,cx,cy,width,height\r\n\
n0,n0.png,155030,463000,300,0,0,0,100,40,30,80,60\r\n\
n1,n1.png,155030,463000,300,95,0,0,100,40,30,80,60\r\n\
n2,n2.png,155030,463000,300,0,0,0,-5,40,30,80,60\r\n\
n3,n3.png,155030,463000,300,0,0,0,100,500,30,80,60\r\n\
n4,n4.png,155030,463000,300,0,0,0,100,40,30,100,60\r\n\
n5,n5.png,255030,463000,300,0,0,0,100,40,30,80,60\r\n";
    write_text(root, "aerial/nadir/cameras.csv", nadir);

    let checkpoints = "point_id,x,y,z\nc1,155001,463005,0.5\nc2,155002,463005,\n";
    write_text(root, "control/checkpoints.csv", checkpoints);
    let observations =
        "point_id,image_id,u,v\nc1,p0,10,10\nc1,pX,10,10\nc1,p12,100,10\nc9,p0,5,5\n";
    write_text(root, "control/observations.csv", observations);

    use Severity::{Error, Warning};
    let read_expected = vec![
        (
            String::from("campaign.toml"),
            None,
            Some(String::from("crs")),
            Error,
        ),
        key("mm/recordings.csv", 5, "x", Error),
        key("mm/recordings.csv", 7, "y", Error),
        key("mm/recordings.csv", 8, "z", Error),
        key("mm/recordings.csv", 9, "heading", Error),
        key("mm/recordings.csv", 10, "camera_height", Error),
        key("mm/recordings.csv", 11, "time", Error),
        key("mm/recordings.csv", 13, "image_id", Error),
        key("mm/recordings.csv", 14, "file", Error),
        key("mm/recordings.csv", 17, "time", Warning),
        key("aerial/nadir/cameras.csv", 3, "omega", Error),
        key("aerial/nadir/cameras.csv", 4, "focal_px", Error),
        key("aerial/nadir/cameras.csv", 5, "cx", Error),
        key("control/checkpoints.csv", 3, "z", Error),
        key("control/observations.csv", 3, "image_id", Error),
        key("control/observations.csv", 5, "point_id", Error),
    ];
    let (campaign, problems) = read_campaign(root).unwrap();
    assert_eq!(keys(&problems), read_expected, "{problems:#?}");

    // Good rows are returned, sorted by time (p12 at 10:31:16.5Z lies between p10 and p11).
    let ids: Vec<&str> = campaign
        .recordings
        .iter()
        .map(|r| r.image_id.as_str())
        .collect();
    assert_eq!(ids, ["p0", "p10", "p12", "p11"]);
    assert_eq!(campaign.recordings[2].time_s, 1_560_508_276.5);
    let nadir_ids: Vec<&str> = campaign.nadir.iter().map(|a| a.image_id.as_str()).collect();
    assert_eq!(nadir_ids, ["n0", "n4", "n5"]);
    assert_eq!(campaign.checkpoints.len(), 1);
    assert_eq!(campaign.observations.len(), 2);
    assert_eq!(campaign.name, "broken");
    assert_eq!(campaign.crs, "");

    // Messages name the value and say what to do.
    let shown = |file: &str, row: usize, field: &str| find(&problems, file, row, field).to_string();
    assert_eq!(
        shown("mm/recordings.csv", 5, "x"),
        "mm/recordings.csv:5: field 'x': 'abc' is not a number — write a decimal number with '.' as decimal mark"
    );
    assert!(shown("mm/recordings.csv", 7, "y").contains("'NaN' is not a finite number"));
    assert!(shown("mm/recordings.csv", 8, "z").contains("'inf' is not a finite number"));
    assert!(shown("mm/recordings.csv", 9, "heading").contains("is empty"));
    assert!(shown("mm/recordings.csv", 11, "time").contains("'yesterday' is not an ISO 8601 time"));
    assert!(shown("mm/recordings.csv", 13, "image_id").contains("'p7' is also used on row 12"));
    assert!(
        shown("mm/recordings.csv", 14, "file").contains("mm/panoramas/missing.jpg does not exist")
    );
    assert!(shown("mm/recordings.csv", 17, "time").contains("is before the time on row 16"));
    assert!(shown("control/observations.csv", 3, "image_id").contains("'pX'"));

    let report = check_campaign(root);
    let mut check_expected = read_expected.clone();
    check_expected.insert(9, key("mm/recordings.csv", 15, "file", Error));
    check_expected.insert(10, key("mm/recordings.csv", 16, "file", Error));
    check_expected.insert(15, key("aerial/nadir/cameras.csv", 6, "file", Error));
    check_expected.insert(16, key("aerial/nadir/cameras.csv", 7, "image_id", Warning));
    check_expected.insert(19, key("control/observations.csv", 4, "u", Error));
    assert_eq!(
        keys(&report.problems),
        check_expected,
        "{}",
        report.render()
    );
    let shown =
        |file: &str, row: usize, field: &str| find(&report.problems, file, row, field).to_string();
    assert!(shown("mm/recordings.csv", 15, "file")
        .contains("mm/panoramas/trunc.jpg is a truncated JPEG file"));
    assert!(shown("mm/recordings.csv", 16, "file").contains("64×64 px, not 2:1"));
    assert!(shown("aerial/nadir/cameras.csv", 6, "file")
        .contains("is 80×60 px but its row says width 100, height 60"));
    assert!(shown("aerial/nadir/cameras.csv", 7, "image_id")
        .contains("'n5' sees none of the 2 recording positions"));
    assert!(shown("control/observations.csv", 4, "u").contains("u must be < 64"));
    assert_eq!(
        (
            report.recordings,
            report.nadir,
            report.checkpoints,
            report.observations
        ),
        // The truncated and the 1:1 panorama, the wrongly sized nadir frame and the observation outside its
        // panorama are not usable.
        (2, 2, 1, 1)
    );
    assert!(!report.is_clean());
    let rendered = report.render();
    assert!(
        rendered.starts_with("campaign.toml (1 error, 0 warnings)\n  campaign.toml: field 'crs': "),
        "{rendered}"
    );
    assert!(
        rendered.contains("\nmm/recordings.csv (10 errors, 1 warning)\n"),
        "{rendered}"
    );
    assert!(rendered.ends_with(
        "19 errors, 2 warnings: 2 recordings, 2 nadir and 0 oblique images, 1 check points, 1 observations usable\n"
    ));
}

#[test]
fn missing_required_column_skips_the_file_and_names_the_header_row() {
    let dir = tempfile::tempdir().unwrap();
    write_valid_campaign(dir.path());
    let path = dir.path().join("mm/recordings.csv");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace(",heading,", ",bearing,");
    std::fs::write(&path, format!("# a comment line\n{text}")).unwrap();
    let (campaign, problems) = read_campaign(dir.path()).unwrap();
    assert!(campaign.recordings.is_empty());
    // Observations now refer to panoramas that are not usable.
    assert_eq!(
        keys(&problems),
        [
            key("mm/recordings.csv", 2, "heading", Severity::Error),
            key("control/observations.csv", 2, "image_id", Severity::Error),
            key("control/observations.csv", 3, "image_id", Severity::Error),
            key("control/observations.csv", 4, "image_id", Severity::Error),
        ]
    );
    assert!(problems[0]
        .to_string()
        .starts_with("mm/recordings.csv:2: field 'heading': required column is missing"));
}

#[test]
fn missing_campaign_toml_is_reported_and_the_rest_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let written = write_valid_campaign(dir.path());
    std::fs::remove_file(dir.path().join("campaign.toml")).unwrap();
    let (campaign, problems) = read_campaign(dir.path()).unwrap();
    assert_eq!(
        keys(&problems),
        [(String::from("campaign.toml"), None, None, Severity::Error)]
    );
    assert_eq!(problems[0].message, "does not exist");
    assert_eq!(campaign.recordings, written.recordings);
    assert_eq!(campaign.name, "");
}

#[test]
fn folder_without_campaign_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    assert!(matches!(
        read_campaign(dir.path()),
        Err(CampaignError::NotACampaign(_))
    ));
    let missing = dir.path().join("nope");
    assert!(matches!(
        read_campaign(&missing),
        Err(CampaignError::Unreadable { .. })
    ));
    let report = check_campaign(dir.path());
    assert_eq!(report.problems.len(), 1);
    assert!(report.problems[0].message.contains("not a campaign folder"));
    assert_eq!(report.recordings, 0);
}

#[test]
fn trajectory_adjusted_round_trips_through_the_reader() {
    let dir = tempfile::tempdir().unwrap();
    let rows: Vec<(Recording, [f64; 3])> = (0..3)
        .map(|i| {
            let mut r = recording(i, &format!("pano_{i}.jpg"));
            r.sigma_xy_m = None;
            r.sigma_z_m = None;
            (r, [0.012 + i as f64 * 1e-3, 0.013, 0.031])
        })
        .collect();
    let path = dir.path().join("out/trajectory_adjusted.csv");
    write_trajectory_adjusted_csv(&path, &rows).unwrap();
    let header = std::fs::read_to_string(&path)
        .unwrap()
        .lines()
        .next()
        .unwrap()
        .to_string();
    assert_eq!(
        header,
        "image_id,file,time,x,y,z,heading,camera_height,sigma_x,sigma_y,sigma_z"
    );
    let (read, problems) = read_recordings_csv(&path);
    assert!(problems.is_empty(), "{problems:#?}");
    // sigma_x, sigma_y are unknown columns to the reader; sigma_z is the documented optional column.
    let expected: Vec<Recording> = rows
        .iter()
        .map(|(r, s)| Recording {
            sigma_z_m: Some(s[2]),
            ..r.clone()
        })
        .collect();
    assert_eq!(read, expected);
}

#[test]
fn more_broken_cases_toml_types_cross_file_ids_cell_counts_encoding() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    write_valid_campaign(root);
    std::fs::write(
        root.join("campaign.toml"),
        "# campaign\nname = \"x\"\ncrs = 28992\n",
    )
    .unwrap();
    // The oblique image reuses the nadir id.
    let oblique = root.join("aerial/oblique/cameras.csv");
    let text = std::fs::read_to_string(&oblique)
        .unwrap()
        .replace("o0,", "n0,");
    std::fs::write(&oblique, text).unwrap();
    // Row 3: one cell too many (unquoted comma); row 4: not UTF-8. Observations row 6: c1 again in pano_0.
    let rec = root.join("mm/recordings.csv");
    let mut bytes = std::fs::read(&rec).unwrap();
    let lines: Vec<&[u8]> = bytes.split(|&b| b == b'\n').collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        out.extend_from_slice(line);
        if i == 2 {
            out.extend_from_slice(b",surplus");
        }
        if i == 3 {
            out.extend_from_slice(b",\xff");
        }
        if i + 1 < lines.len() {
            out.push(b'\n');
        }
    }
    bytes = out;
    std::fs::write(&rec, &bytes).unwrap();
    let obs = root.join("control/observations.csv");
    let mut text = std::fs::read_to_string(&obs).unwrap();
    text.push_str("# remeasured\nc1,pano_0,33.0,20.0\n");
    std::fs::write(&obs, text).unwrap();

    let (campaign, problems) = read_campaign(root).unwrap();
    let expected = vec![
        (
            String::from("campaign.toml"),
            None,
            Some(String::from("crs")),
            Severity::Error,
        ),
        (
            String::from("mm/recordings.csv"),
            Some(3),
            None,
            Severity::Error,
        ),
        (
            String::from("mm/recordings.csv"),
            Some(4),
            None,
            Severity::Error,
        ),
        key("aerial/oblique/cameras.csv", 2, "image_id", Severity::Error),
        key("control/observations.csv", 3, "image_id", Severity::Error),
        key("control/observations.csv", 4, "image_id", Severity::Error),
        key("control/observations.csv", 6, "point_id", Severity::Error),
    ];
    assert_eq!(keys(&problems), expected, "{problems:#?}");
    assert_mentions(&problems[0], "is of type integer, not a string");
    assert_mentions(&problems[1], "has 14 cells but the header has 13 columns");
    assert_mentions(&problems[2], "not valid UTF-8");
    assert_mentions(
        &problems[3],
        "'n0' is also used on aerial/nadir/cameras.csv:2",
    );
    assert_mentions(&problems[6], "'c1' in image 'pano_0' is also used on row 2");
    let ids: Vec<&str> = campaign
        .recordings
        .iter()
        .map(|r| r.image_id.as_str())
        .collect();
    assert_eq!(ids, ["pano_0", "pano_3"]);
    assert!(campaign.nadir.is_empty() && campaign.oblique.is_empty());
    // pano_1 and pano_2 were unusable; of the two pano_0 measurements of c1 neither is kept.
    assert_eq!(campaign.observations.len(), 0);

    std::fs::write(
        root.join("campaign.toml"),
        "name = \"x\"\n\ncrs = \"EPSG:28992\n",
    )
    .unwrap();
    let (_, problems) = read_campaign(root).unwrap();
    assert_eq!(
        (problems[0].file.to_str(), problems[0].row),
        (Some("campaign.toml"), Some(3))
    );
    assert!(
        problems[0].message.starts_with("is not valid TOML"),
        "{}",
        problems[0]
    );
}

#[test]
fn check_is_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    write_valid_campaign(dir.path());
    std::fs::write(dir.path().join("mm/panoramas/sub/pano_1.png"), b"not a png").unwrap();
    std::fs::write(dir.path().join("aerial/nadir/n0.png"), b"").unwrap();
    let first = check_campaign(dir.path());
    // The unusable pano_1 also takes its observation (control/observations.csv row 3) with it.
    assert_eq!(first.error_count(), 3, "{}", first.render());
    for _ in 0..3 {
        assert_eq!(check_campaign(dir.path()), first);
    }
}

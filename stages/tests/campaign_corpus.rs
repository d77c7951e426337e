//! The malformed-input corpus: one small valid campaign (6 panoramas, 2 nadir and 1 oblique frame, 2 check
//! points, 3 observations) is damaged in one way per case — CSV columns, cells, ranges, plausibility, paths,
//! image files, campaign.toml — and `check_campaign` (the validation the run applies too) must report exactly
//! the expected errors, each naming file, row and field with a message that says what is wrong, while the
//! other items stay usable. Cases the format allows (BOM, CRLF, extra columns, unknown TOML keys, a PNG named
//! .jpg) must pass without errors.

use skytie_stages::campaign::{
    check_campaign, write_aerial_cameras_csv, write_campaign_toml, write_checkpoints_csv,
    write_observations_csv, write_recordings_csv, AerialImage, CheckPoint, Observation,
    ProblemKind, Recording, Severity,
};
use std::path::Path;
use support::campaign_files::image;

mod support;

const REC: &str = "mm/recordings.csv";
const NADIR: &str = "aerial/nadir/cameras.csv";
const OBL: &str = "aerial/oblique/cameras.csv";
const CP: &str = "control/checkpoints.csv";
const OBS: &str = "control/observations.csv";

fn aerial(id: &str, file: &str, y: f64, omega_deg: f64) -> AerialImage {
    AerialImage {
        file: file.into(),
        ..AerialImage::ideal(
            id,
            [155_012.5, y, 300.0],
            [omega_deg, 0.0, 0.0],
            100.0,
            [80, 60],
        )
    }
}

/// The valid campaign every case starts from. Recordings on rows 2–7 (5 m, 1 s apart), nadir n0/n1 on rows
/// 2/3, oblique o0 on row 2, check points c1/c2 on rows 2/3, observations on rows 2–4.
fn write_base(root: &Path) {
    let recordings: Vec<Recording> = (0..6)
        .map(|i| Recording {
            time: format!("2019-06-14T10:31:{:02}.000Z", 10 + i),
            ..Recording::new(
                &format!("pano_{i}"),
                1_560_508_270.0 + i as f64,
                [155_000.0 + 5.0 * i as f64, 463_000.0, 2.5],
                90.0,
                2.4,
            )
        })
        .collect();
    for r in &recordings {
        image(&root.join("mm/panoramas").join(&r.file), 64, 32);
    }
    let nadir = vec![
        aerial("n0", "n0.png", 463_000.0, 0.0),
        aerial("n1", "n1.png", 463_001.0, 0.0),
    ];
    let oblique = vec![aerial("o0", "o0.jpg", 462_700.0, 45.0)];
    for f in [
        "aerial/nadir/n0.png",
        "aerial/nadir/n1.png",
        "aerial/oblique/o0.jpg",
    ] {
        image(&root.join(f), 80, 60);
    }
    let cp = |id: &str, x: f64| CheckPoint {
        point_id: id.into(),
        x,
        y: 463_004.0,
        z: 0.3,
        sigma_xy_m: None,
        sigma_z_m: None,
    };
    let obs = |p: &str, i: &str| Observation {
        point_id: p.into(),
        image_id: i.into(),
        u_px: 30.0,
        v_px: 20.0,
    };
    write_campaign_toml(
        &root.join("campaign.toml"),
        "Corpus",
        "EPSG:28992",
        Default::default(),
    )
    .unwrap();
    write_recordings_csv(&root.join(REC), &recordings).unwrap();
    write_aerial_cameras_csv(&root.join(NADIR), &nadir).unwrap();
    write_aerial_cameras_csv(&root.join(OBL), &oblique).unwrap();
    write_checkpoints_csv(&root.join(CP), &[cp("c1", 155_002.0), cp("c2", 155_020.0)]).unwrap();
    write_observations_csv(
        &root.join(OBS),
        &[
            obs("c1", "pano_0"),
            obs("c1", "pano_1"),
            obs("c2", "pano_4"),
        ],
    )
    .unwrap();
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

/// Replace the cell of `column` on line `row` (1-based) of the CSV `rel`.
fn set_cell(root: &Path, rel: &str, row: usize, column: &str, value: &str) {
    let path = root.join(rel);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let col = header
        .iter()
        .position(|h| *h == column)
        .unwrap_or_else(|| panic!("{column} in {rel}"));
    let mut cells: Vec<String> = lines[row - 1].split(',').map(str::to_string).collect();
    cells[col] = value.to_string();
    lines[row - 1] = cells.join(",");
    std::fs::write(path, lines.join("\n") + "\n").unwrap();
}

/// Edit the text of `rel` with `f`.
fn edit(root: &Path, rel: &str, f: impl Fn(String) -> String) {
    let path = root.join(rel);
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(path, f(text)).unwrap();
}

fn truncate(root: &Path, rel: &str, keep: f64) {
    let path = root.join(rel);
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..(bytes.len() as f64 * keep) as usize]).unwrap();
}

/// A PNG whose IHDR (with a valid CRC) claims 100000 × 100000 px.
fn absurd_png(path: &Path) {
    image(path, 4, 4);
    let mut b = std::fs::read(path).unwrap();
    b[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    b[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    let mut h = crc32fast::Hasher::new();
    h.update(&b[12..29]);
    b[29..33].copy_from_slice(&h.finalize().to_be_bytes());
    std::fs::write(path, b).unwrap();
}

type Damage = Box<dyn Fn(&Path)>;
/// (file, row, field, part of the message) of one expected error.
type Expect = (
    &'static str,
    Option<usize>,
    Option<&'static str>,
    &'static str,
);

struct Case {
    name: &'static str,
    damage: Damage,
    errors: Vec<Expect>,
}

fn case(name: &'static str, damage: impl Fn(&Path) + 'static, errors: Vec<Expect>) -> Case {
    Case {
        name,
        damage: Box::new(damage),
        errors,
    }
}

fn cell(rel: &'static str, row: usize, col: &'static str, value: &'static str) -> impl Fn(&Path) {
    move |r: &Path| set_cell(r, rel, row, col, value)
}

/// A case that sets the cell (file, row, column) `at` to `value` and expects one error, on that cell, whose
/// message contains `message`.
fn cell_case(
    name: &'static str,
    at: (&'static str, usize, &'static str),
    value: &'static str,
    message: &'static str,
) -> Case {
    let (rel, row, column) = at;
    case(
        name,
        cell(rel, row, column, value),
        vec![(rel, Some(row), Some(column), message)],
    )
}

fn csv_cases() -> Vec<Case> {
    vec![
        case(
            "missing column x",
            |r| edit(r, REC, |t| t.replacen(",x,", ",", 1).replace(",155", ",")),
            vec![(REC, Some(1), Some("x"), "required column is missing")],
        ),
        case(
            "renamed column heading",
            |r| edit(r, REC, |t| t.replacen("heading", "hdg", 1)),
            vec![(REC, Some(1), Some("heading"), "required column is missing")],
        ),
        case(
            "missing column time",
            |r| edit(r, REC, |t| t.replacen(",time", ",when", 1)),
            vec![(REC, Some(1), Some("time"), "required column is missing")],
        ),
        case(
            "duplicate column",
            |r| {
                edit(r, CP, |t| {
                    t.replacen("point_id,x", "point_id,x,x", 1)
                        .replace("c1,", "c1,1,")
                        .replace("c2,", "c2,1,")
                })
            },
            vec![(CP, Some(1), Some("x"), "column appears twice")],
        ),
        cell_case(
            "x not a number",
            (REC, 3, "x"),
            "abc",
            "'abc' is not a number",
        ),
        cell_case(
            "y NaN",
            (REC, 3, "y"),
            "NaN",
            "'NaN' is not a finite number",
        ),
        cell_case(
            "z inf",
            (REC, 4, "z"),
            "inf",
            "'inf' is not a finite number",
        ),
        cell_case("heading empty", (REC, 5, "heading"), "", "is empty"),
        cell_case(
            "heading 720",
            (REC, 5, "heading"),
            "720",
            "720° is outside -180°…360°",
        ),
        cell_case(
            "x 1e30",
            (REC, 6, "x"),
            "1e30",
            "is not a projected coordinate",
        ),
        cell_case("z 1e30", (REC, 6, "z"), "1e30", "is not a height"),
        cell_case(
            "camera height 0",
            (REC, 2, "camera_height"),
            "0",
            "is not above the road",
        ),
        cell_case(
            "time not ISO",
            (REC, 7, "time"),
            "yesterday",
            "'yesterday' is not an ISO 8601 time",
        ),
        case(
            "sigma 1e-30",
            |r| edit(r, REC, |t| add_column(&t, "sigma_xy", "1e-30")),
            vec![(REC, Some(2), Some("sigma_xy"), "outside the plausible"); 6],
        ),
        case(
            "sigma_z negative",
            |r| edit(r, REC, |t| add_column(&t, "sigma_z", "-1")),
            vec![(REC, Some(2), Some("sigma_z"), "is not a standard deviation"); 6],
        ),
        case(
            "pitch 120",
            |r| edit(r, REC, |t| add_column(&t, "pitch", "120")),
            vec![(REC, Some(2), Some("pitch"), "beyond ±90°"); 6],
        ),
        case(
            "yaw 400",
            |r| edit(r, REC, |t| add_column(&t, "yaw", "400")),
            vec![(REC, Some(2), Some("yaw"), "400° is outside"); 6],
        ),
        case(
            "duplicate image_id",
            cell(REC, 4, "image_id", "pano_1"),
            vec![
                (
                    REC,
                    Some(4),
                    Some("image_id"),
                    "'pano_1' is also used on row 3",
                ),
                (
                    OBS,
                    Some(3),
                    Some("image_id"),
                    "'pano_1' is not a usable panorama",
                ),
            ],
        ),
        case(
            "extra cell",
            |r| {
                edit(r, REC, |t| {
                    t.replacen(
                        "2019-06-14T10:31:12.000Z",
                        "2019-06-14T10:31:12.000Z,surplus",
                        1,
                    )
                })
            },
            vec![(
                REC,
                Some(4),
                None,
                "has 9 cells but the header has 8 columns",
            )],
        ),
        case(
            "missing cell",
            |r| edit(r, REC, |t| t.replacen(",2019-06-14T10:31:12.000Z", "", 1)),
            vec![(
                REC,
                Some(4),
                None,
                "has 7 cells but the header has 8 columns",
            )],
        ),
        case(
            "non-UTF-8",
            |r| {
                let p = r.join(REC);
                let mut b = std::fs::read(&p).unwrap();
                let i = b.windows(6).position(|w| w == b"pano_3").unwrap();
                b[i] = 0xFF;
                std::fs::write(p, b).unwrap();
            },
            vec![(REC, Some(5), None, "is not valid UTF-8")],
        ),
        case(
            "empty recordings.csv",
            |r| std::fs::write(r.join(REC), "").unwrap(),
            vec![(REC, None, None, "is empty (no header row)")],
        ),
        cell_case(
            "50 km off",
            (REC, 4, "x"),
            "205010",
            "m from the middle of the campaign, while 95 % of the recordings lie within",
        ),
        case(
            "jump away from both neighbours",
            cell(REC, 4, "y", "463300"),
            vec![(
                REC,
                Some(4),
                Some("x"),
                "position jumps away from both neighbours",
            )],
        ),
        cell_case(
            "unknown point in observation",
            (OBS, 2, "point_id"),
            "c9",
            "'c9' is not a usable point",
        ),
        cell_case(
            "unknown panorama in observation",
            (OBS, 2, "image_id"),
            "pano_9",
            "'pano_9' is not a usable panorama",
        ),
        cell_case(
            "negative u",
            (OBS, 3, "u"),
            "-4",
            "-4 px lies outside the panorama",
        ),
        cell_case(
            "u beyond the panorama",
            (OBS, 3, "u"),
            "64",
            "u must be < 64",
        ),
        cell_case(
            "v beyond the panorama",
            (OBS, 4, "v"),
            "33",
            "v must be ≤ 32",
        ),
        case(
            "duplicate observation",
            cell(OBS, 3, "image_id", "pano_0"),
            vec![(OBS, Some(3), Some("point_id"), "is also used on row 2")],
        ),
        case(
            "duplicate point_id",
            cell(CP, 3, "point_id", "c1"),
            vec![
                (CP, Some(3), Some("point_id"), "'c1' is also used on row 2"),
                (OBS, Some(2), Some("point_id"), "'c1' is not a usable point"),
                (OBS, Some(3), Some("point_id"), "'c1' is not a usable point"),
                (OBS, Some(4), Some("point_id"), "'c2' is not a usable point"),
            ],
        ),
        case(
            "check point x abc",
            cell(CP, 3, "x", "abc"),
            vec![
                (CP, Some(3), Some("x"), "'abc' is not a number"),
                (OBS, Some(4), Some("point_id"), "'c2' is not a usable point"),
            ],
        ),
        case(
            "check point 100 km away",
            cell(CP, 3, "y", "563004"),
            vec![
                (CP, Some(3), Some("x"), "from the middle of the campaign"),
                (OBS, Some(4), Some("point_id"), "'c2' is not a usable point"),
            ],
        ),
        case(
            "check point sigma 0",
            |r| edit(r, CP, |t| add_column(&t, "sigma_z", "0")),
            vec![
                (CP, Some(2), Some("sigma_z"), "is not a standard deviation"),
                (CP, Some(3), Some("sigma_z"), "is not a standard deviation"),
                (OBS, Some(2), Some("point_id"), "not a usable point"),
                (OBS, Some(3), Some("point_id"), "not a usable point"),
                (OBS, Some(4), Some("point_id"), "not a usable point"),
            ],
        ),
        case(
            "observations without check points",
            |r| std::fs::remove_file(r.join(CP)).unwrap(),
            vec![(
                CP,
                None,
                None,
                "does not exist, so control/observations.csv cannot be used",
            )],
        ),
        cell_case(
            "focal 1e-9",
            (NADIR, 2, "focal_px"),
            "1e-9",
            "field of view",
        ),
        cell_case(
            "focal negative",
            (NADIR, 2, "focal_px"),
            "-5",
            "is not a principal distance",
        ),
        cell_case("focal 1e9", (NADIR, 3, "focal_px"), "1e9", "field of view"),
        cell_case("omega 95", (NADIR, 2, "omega"), "95", "beyond ±90°"),
        cell_case(
            "kappa 1000",
            (NADIR, 2, "kappa"),
            "1000",
            "1000° is outside",
        ),
        cell_case(
            "width abc",
            (NADIR, 2, "width"),
            "abc",
            "is not a whole number of pixels",
        ),
        case(
            "width 3",
            cell(OBL, 2, "width", "3"),
            vec![
                (
                    OBL,
                    Some(2),
                    Some("width"),
                    "3 px is not a frame image size",
                ),
                (
                    OBL,
                    Some(2),
                    Some("cx"),
                    "principal point 40 px lies outside",
                ),
            ],
        ),
        cell_case(
            "cx outside",
            (NADIR, 3, "cx"),
            "500",
            "principal point 500 px lies outside",
        ),
        case(
            "sigma_px 1e-9",
            |r| edit(r, NADIR, |t| add_column(&t, "sigma_px", "1e-9")),
            vec![
                (NADIR, Some(2), Some("sigma_px"), "outside the plausible"),
                (NADIR, Some(3), Some("sigma_px"), "outside the plausible"),
            ],
        ),
        cell_case("aerial z 1e30", (OBL, 2, "z"), "1e30", "is not a height"),
        cell_case(
            "aerial id used twice",
            (OBL, 2, "image_id"),
            "n0",
            "'n0' is also used on aerial/nadir/cameras.csv:2",
        ),
        case(
            "cameras.csv missing",
            |r| std::fs::remove_file(r.join(OBL)).unwrap(),
            vec![(
                OBL,
                None,
                None,
                "does not exist although aerial/oblique/ does",
            )],
        ),
    ]
}

/// `text` (a CSV) with a column `name` = `value` on every row.
fn add_column(text: &str, name: &str, value: &str) -> String {
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        if line.starts_with('#') || line.is_empty() {
            out.push_str(line);
        } else if i == 0 || out.is_empty() {
            out.push_str(&format!("{line},{name}"));
        } else {
            out.push_str(&format!("{line},{value}"));
        }
        out.push('\n');
    }
    out
}

fn path_and_image_cases() -> Vec<Case> {
    vec![
        case(
            "path with ..",
            cell(REC, 3, "file", "../../campaign.toml"),
            vec![
                (
                    REC,
                    Some(3),
                    Some("file"),
                    "leads out of its folder with '..'",
                ),
                (OBS, Some(3), Some("image_id"), "not a usable panorama"),
            ],
        ),
        case(
            "absolute path",
            cell(REC, 3, "file", "/etc/hostname"),
            vec![
                (REC, Some(3), Some("file"), "is an absolute path"),
                (OBS, Some(3), Some("image_id"), "not a usable panorama"),
            ],
        ),
        case(
            "symlink out of the campaign",
            |r| {
                let outside = r.parent().unwrap().join(format!(
                    "{}-outside.jpg",
                    r.file_name().unwrap().to_string_lossy()
                ));
                std::fs::copy(r.join("mm/panoramas/pano_2.jpg"), &outside).unwrap();
                std::fs::remove_file(r.join("mm/panoramas/pano_2.jpg")).unwrap();
                std::os::unix::fs::symlink(&outside, r.join("mm/panoramas/pano_2.jpg")).unwrap();
            },
            vec![(
                REC,
                Some(4),
                Some("file"),
                "is a link to a file outside the campaign folder",
            )],
        ),
        case(
            "two recordings share an image",
            cell(REC, 6, "file", "pano_3.jpg"),
            vec![
                (
                    REC,
                    Some(6),
                    Some("file"),
                    "the image is also used on row 5; both rows skipped",
                ),
                (OBS, Some(4), Some("image_id"), "not a usable panorama"),
            ],
        ),
        case(
            "image file missing",
            |r| std::fs::remove_file(r.join("mm/panoramas/pano_5.jpg")).unwrap(),
            vec![(
                REC,
                Some(7),
                Some("file"),
                "mm/panoramas/pano_5.jpg does not exist",
            )],
        ),
        case(
            "zero-byte panorama",
            |r| std::fs::write(r.join("mm/panoramas/pano_5.jpg"), b"").unwrap(),
            vec![(
                REC,
                Some(7),
                Some("file"),
                "mm/panoramas/pano_5.jpg is empty (0 bytes)",
            )],
        ),
        case(
            "JPEG truncated to 10 %",
            |r| truncate(r, "mm/panoramas/pano_0.jpg", 0.1),
            vec![
                (
                    REC,
                    Some(2),
                    Some("file"),
                    "mm/panoramas/pano_0.jpg is a truncated JPEG file",
                ),
                (
                    OBS,
                    Some(2),
                    Some("image_id"),
                    "panorama 'pano_0' is not usable",
                ),
            ],
        ),
        case(
            "JPEG truncated to 90 %",
            |r| truncate(r, "mm/panoramas/pano_5.jpg", 0.9),
            vec![(REC, Some(7), Some("file"), "is a truncated JPEG file")],
        ),
        case(
            "PNG truncated",
            |r| truncate(r, "aerial/nadir/n1.png", 0.7),
            vec![(
                NADIR,
                Some(3),
                Some("file"),
                "aerial/nadir/n1.png is a truncated PNG file",
            )],
        ),
        case(
            "text named .jpg",
            |r| std::fs::write(r.join("mm/panoramas/pano_5.jpg"), b"hello, not an image").unwrap(),
            vec![(
                REC,
                Some(7),
                Some("file"),
                "is not a JPEG, PNG or TIFF file (it starts with bytes 68 65 6C 6C)",
            )],
        ),
        case(
            "BMP named .png",
            |r| {
                std::fs::write(
                    r.join("aerial/nadir/n0.png"),
                    b"BM\x36\x00\x00\x00\x00\x00\x00\x00",
                )
                .unwrap()
            },
            vec![(
                NADIR,
                Some(2),
                Some("file"),
                "is not a JPEG, PNG or TIFF file",
            )],
        ),
        case(
            "panorama not 2:1",
            |r| image(&r.join("mm/panoramas/pano_5.jpg"), 64, 64),
            vec![(REC, Some(7), Some("file"), "is 64×64 px, not 2:1")],
        ),
        case(
            "nadir frame of the wrong size",
            |r| image(&r.join("aerial/nadir/n1.png"), 100, 60),
            vec![(
                NADIR,
                Some(3),
                Some("file"),
                "is 100×60 px but its row says width 80, height 60",
            )],
        ),
        case(
            "absurd header dimensions",
            |r| absurd_png(&r.join("aerial/nadir/n0.png")),
            vec![(
                NADIR,
                Some(2),
                Some("file"),
                "whose header claims 100000×100000 px",
            )],
        ),
        case(
            "truncated TIFF",
            |r| {
                let p = r.join("mm/panoramas/pano_5.jpg");
                std::fs::remove_file(&p).unwrap();
                let t = r.join("mm/panoramas/pano_5.tif");
                image(&t, 64, 32);
                truncate(r, "mm/panoramas/pano_5.tif", 0.5);
                set_cell(r, REC, 7, "file", "pano_5.tif");
            },
            vec![(REC, Some(7), Some("file"), "is a truncated TIFF file")],
        ),
        case(
            "JPEG without image data",
            |r| {
                std::fs::write(r.join("mm/panoramas/pano_5.jpg"), [0xFF, 0xD8, 0xFF, 0xD9]).unwrap()
            },
            vec![(REC, Some(7), Some("file"), "no frame header")],
        ),
        case(
            "campaign.toml invalid",
            |r| {
                std::fs::write(
                    r.join("campaign.toml"),
                    "name = \"x\"\ncrs = \"EPSG:28992\n",
                )
                .unwrap()
            },
            vec![("campaign.toml", Some(2), None, "is not valid TOML")],
        ),
        case(
            "campaign.toml wrong type",
            |r| {
                std::fs::write(r.join("campaign.toml"), "name = 5\ncrs = \"EPSG:28992\"\n").unwrap()
            },
            vec![(
                "campaign.toml",
                None,
                Some("name"),
                "is of type integer, not a string",
            )],
        ),
        case(
            "campaign.toml missing crs",
            |r| std::fs::write(r.join("campaign.toml"), "name = \"x\"\n").unwrap(),
            vec![(
                "campaign.toml",
                None,
                Some("crs"),
                "required key is missing",
            )],
        ),
        case(
            "campaign.toml empty crs",
            |r| std::fs::write(r.join("campaign.toml"), "name = \"x\"\ncrs = \" \"\n").unwrap(),
            vec![("campaign.toml", None, Some("crs"), "is empty")],
        ),
        case(
            "campaign.toml unknown frame",
            |r| {
                let toml = "name = \"x\"\ncrs = \"EPSG:28992\"\nframe = \"polar\"\n";
                std::fs::write(r.join("campaign.toml"), toml).unwrap()
            },
            vec![(
                "campaign.toml",
                None,
                Some("frame"),
                "is not a coordinate frame skytie knows",
            )],
        ),
        case(
            "campaign.toml missing",
            |r| std::fs::remove_file(r.join("campaign.toml")).unwrap(),
            vec![("campaign.toml", None, None, "does not exist")],
        ),
    ]
}

/// Inputs the format allows: no error.
fn accepted_cases() -> Vec<Case> {
    vec![
        case(
            "BOM and CRLF",
            |r| edit(r, REC, |t| format!("\u{feff}{}", t.replace('\n', "\r\n"))),
            vec![],
        ),
        case(
            "extra column and comments",
            |r| {
                edit(r, NADIR, |t| {
                    format!("# exported\n{}", add_column(&t, "operator", "ann"))
                })
            },
            vec![],
        ),
        case(
            "reordered columns",
            |r| {
                edit(r, CP, |t| {
                    t.lines()
                        .map(|l| {
                            let c: Vec<&str> = l.split(',').collect();
                            format!("{},{},{},{}", c[3], c[2], c[1], c[0])
                        })
                        .collect::<Vec<_>>()
                        .join("\n")
                })
            },
            vec![],
        ),
        case(
            "unknown campaign.toml key",
            |r| edit(r, "campaign.toml", |t| format!("{t}operator = \"ann\"\n")),
            vec![],
        ),
        case(
            "PNG named .jpg",
            |r| {
                let p = r.join("mm/panoramas/pano_2.jpg");
                let img = image::open(&p).unwrap();
                img.save_with_format(&p, image::ImageFormat::Png).unwrap();
            },
            vec![],
        ),
    ]
}

#[test]
fn every_malformed_input_is_named_with_file_row_field_and_the_rest_stays_usable() {
    let tmp = tempfile::tempdir().unwrap();
    let base = tmp.path().join("base");
    write_base(&base);
    let clean = check_campaign(&base);
    assert!(clean.is_clean(), "{}", clean.render());
    let cases: Vec<Case> = csv_cases()
        .into_iter()
        .chain(path_and_image_cases())
        .chain(accepted_cases())
        .collect();
    let damaged = cases.iter().filter(|c| !c.errors.is_empty()).count();
    assert!(damaged >= 60, "{damaged} malformed cases");
    let mut failures = Vec::new();
    for (i, c) in cases.iter().enumerate() {
        let root = tmp.path().join(format!("case{i:02}"));
        copy_dir(&base, &root);
        (c.damage)(&root);
        let report = check_campaign(&root);
        // Observations of a panorama (or point) whose row the case damaged are rejected with it: a
        // consequence, reported as a reference error in control/observations.csv that names the file of the
        // damaged row. Those are checked here; the case's own errors are compared exactly below.
        let damaged_files: Vec<&str> = c.errors.iter().map(|e| e.0).collect();
        let is_consequence = |p: &&skytie_stages::campaign::Problem| {
            p.kind == ProblemKind::Reference
                && p.file == Path::new(OBS)
                && !damaged_files.contains(&OBS)
                && damaged_files
                    .iter()
                    .any(|f| *f != OBS && p.message.contains(*f))
        };
        let errors: Vec<_> = report
            .problems
            .iter()
            .filter(|p| p.severity == Severity::Error && !is_consequence(p))
            .collect();
        let mut expected: Vec<Expect> = c.errors.clone();
        // Cases that add a column to every row expect one error per data row.
        for (k, e) in expected.iter_mut().enumerate() {
            if c.errors.iter().filter(|x| **x == *e).count() > 1 {
                e.1 = e.1.map(|r| r + k);
            }
        }
        let matches = errors.len() == expected.len()
            && expected.iter().zip(&errors).all(|(e, p)| {
                p.file == Path::new(e.0)
                    && p.row == e.1
                    && p.field.as_deref() == e.2
                    && p.message.contains(e.3)
                    && !p.hint.is_empty()
            });
        if !matches {
            failures.push(format!(
                "case '{}':\n  expected {expected:?}\n  got:\n{}",
                c.name,
                report.render()
            ));
        }
        // The rest of the campaign stays usable: at least 5 of the 6 recordings in every case but those that
        // take a whole table away.
        let whole_table =
            c.errors.iter().any(|e| e.1.is_none() || e.1 == Some(1)) || c.errors.len() >= 6;
        if !whole_table && report.recordings < 4 {
            failures.push(format!(
                "case '{}': only {} recordings usable",
                c.name, report.recordings
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases differ:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

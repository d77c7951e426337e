//! The oblique `skytie tool`s on the real binary with known answers: `agast` finds the corners of a synthetic
//! rectangle, `daisy` writes one row per point with the library's descriptor, `mi-register` recovers a known
//! sub-pixel shift of a gamma-changed copy within 0.2 px, `perspective` renders the requested azimuth of a
//! hand-made campaign's panorama at the requested size, and bad input exits 2 naming the file.

#[path = "support/tool_cli.rs"]
mod tool_cli;

use skytie_stages::features::daisy::{describe_points, DaisyParams};
use skytie_stages::imaging::io::{load_gray, load_rgb, save_gray};
use skytie_stages::imaging::resample::{warp_affine, Interpolation};
use skytie_stages::imaging::GrayImage;
use tool_cli::{bright_rectangle, csv_rows, s, stripe_campaign, texture, tool, tool_ok};

#[test]
fn agast_finds_the_corners_of_a_rectangle() {
    let dir = tempfile::tempdir().unwrap();
    let img = bright_rectangle(0.1);
    let (png, out) = (dir.path().join("rect.png"), dir.path().join("corners.csv"));
    save_gray(&png, &img).unwrap();
    let stdout = tool_ok(&["agast", s(&png), "--threshold", "20", "--out", s(&out)]);
    assert!(stdout.starts_with("4 corners"), "{stdout}");
    let rows = csv_rows(&out, "x,y,score");
    let found: Vec<[f64; 3]> = rows
        .iter()
        .map(|r| {
            assert_eq!(r.len(), 3, "{r:?}");
            [
                r[0].parse().unwrap(),
                r[1].parse().unwrap(),
                r[2].parse().unwrap(),
            ]
        })
        .collect();
    assert_eq!(found.len(), 4, "{found:?}");
    for corner in [[25.0, 20.0], [55.0, 20.0], [25.0, 40.0], [55.0, 40.0]] {
        let near = found
            .iter()
            .filter(|f| (f[0] - corner[0]).hypot(f[1] - corner[1]) <= 1.0)
            .count();
        assert_eq!(near, 1, "corner {corner:?}: found {found:?}");
    }
    // Score: the contrast in 0..255 grey levels (0.7·255 = 178.5, the 8-bit file holds 204 − 26 = 178).
    assert!(
        found.iter().all(|f| (f[2] - 178.0).abs() < 1.0),
        "{found:?}"
    );
    // A threshold above the contrast finds nothing.
    tool_ok(&["agast", s(&png), "--threshold", "200", "--out", s(&out)]);
    assert!(csv_rows(&out, "x,y,score").is_empty());
}

#[test]
fn daisy_writes_one_row_per_point_with_the_library_descriptor() {
    let dir = tempfile::tempdir().unwrap();
    let img = texture(90, 70, 2.0, 7);
    let (png, pts, out) = (
        dir.path().join("tex.png"),
        dir.path().join("points.csv"),
        dir.path().join("desc.csv"),
    );
    save_gray(&png, &img).unwrap();
    // Two points inside, one within the 15-px radius of the border; extra columns are ignored.
    std::fs::write(&pts, "score,x,y\n1,40.5,30.5\n2,60.25,35.75\n3,5.5,30.5\n").unwrap();
    let stdout = tool_ok(&["daisy", s(&png), "--points", s(&pts), "--out", s(&out)]);
    assert!(stdout.starts_with("3 points (1 too close"), "{stdout}");
    let rows = csv_rows(&out, "x,y,inside,d0,d1,");
    assert_eq!(rows.len(), 3);
    assert!(rows.iter().all(|r| r.len() == 3 + 200), "row widths");
    assert_eq!(
        rows.iter().map(|r| r[2].as_str()).collect::<Vec<_>>(),
        ["1", "1", "0"]
    );
    assert!(rows[2][3..].iter().all(|v| v.is_empty()));
    // The values are the library's on the same (8-bit) pixels.
    let want = describe_points(
        &load_gray(&png).unwrap(),
        &[(40.5, 30.5), (60.25, 35.75)],
        &DaisyParams::default(),
    );
    for (row, want) in rows.iter().zip(&want) {
        let want = want.as_ref().expect("inside");
        let got: Vec<f32> = row[3..].iter().map(|v| v.parse().unwrap()).collect();
        assert_eq!(&got, want);
        // Partial normalisation: every histogram of 8 has unit length.
        for h in got.chunks(8) {
            let n = h.iter().map(|v| v * v).sum::<f32>().sqrt();
            assert!((n - 1.0).abs() < 1e-4, "histogram norm {n}");
        }
    }
}

#[test]
fn mi_register_recovers_a_subpixel_shift_of_a_gamma_changed_copy() {
    let dir = tempfile::tempdir().unwrap();
    let fixed = texture(96, 96, 2.0, 11);
    let fixed_png = dir.path().join("fixed.png");
    save_gray(&fixed_png, &fixed).unwrap();
    for (k, d) in [[0.6, -0.3], [-1.35, 0.8], [2.25, 1.45]]
        .into_iter()
        .enumerate()
    {
        // moving(u) = fixed(u − d): the fixed content moved by d, then gamma 0.6.
        let mut moving = warp_affine(
            &fixed,
            [1.0, 0.0, -d[0], 0.0, 1.0, -d[1]],
            96,
            96,
            Interpolation::Bicubic,
            0.5,
        );
        moving.data.iter_mut().for_each(|v| *v = v.powf(0.6));
        let moving_png = dir.path().join(format!("moving{k}.png"));
        save_gray(&moving_png, &moving).unwrap();
        let stdout = tool_ok(&[
            "mi-register",
            s(&fixed_png),
            s(&moving_png),
            "--bins",
            "50",
            "--seed",
            "3",
        ]);
        let v: Vec<&str> = stdout.split_whitespace().collect();
        assert_eq!(v.len(), 4, "one line 'dx dy mi iterations': {stdout}");
        let (dx, dy, mi): (f64, f64, f64) = (
            v[0].parse().unwrap(),
            v[1].parse().unwrap(),
            v[2].parse().unwrap(),
        );
        let iterations: usize = v[3].parse().unwrap();
        let err = (dx - d[0]).hypot(dy - d[1]);
        assert!(
            err <= 0.2,
            "shift {d:?}: found ({dx}, {dy}), error {err} px"
        );
        assert!(mi > 0.5, "MI {mi}");
        assert!((1..=200).contains(&iterations), "{iterations}");
    }
    // Sampled metric and a scan start: still within 0.2 px, and deterministic for the seed.
    let moving_png = dir.path().join("moving2.png");
    let args = [
        "mi-register",
        s(&fixed_png),
        s(&moving_png),
        "--samples",
        "3000",
        "--seed",
        "5",
        "--scan-step-px",
        "2",
    ];
    let first = tool_ok(&args);
    assert_eq!(first, tool_ok(&args));
    let v: Vec<f64> = first
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert!((v[0] - 2.25).hypot(v[1] - 1.45) <= 0.2, "{first}");
}

#[test]
fn perspective_renders_the_requested_azimuth_at_the_requested_width() {
    let dir = tempfile::tempdir().unwrap();
    let camp = stripe_campaign(dir.path(), 30.0);
    let out = dir.path().join("view.png");
    let view = |extra: &[&str]| {
        let mut args = vec![
            "perspective",
            "--campaign",
            s(&camp),
            "--recording",
            "r1",
            "--pitch-deg",
            "30",
            "--fov-deg",
            "60",
            "--width",
            "64",
            "--out",
            s(&out),
        ];
        args.extend_from_slice(extra);
        let stdout = tool_ok(&args);
        assert!(stdout.contains("64×64 px"), "{stdout}");
        let img = load_rgb(&out).unwrap();
        assert_eq!((img.width, img.height), (64, 64));
        img
    };
    // Looking east: the stripe's meridian is the view's vertical centre line (roll 0).
    let east = view(&["--yaw-deg", "90"]);
    for row in [8, 32, 56] {
        assert!(
            east.get(31, row)[0] > 0.9 && east.get(32, row)[2] < 0.1,
            "row {row}"
        );
        for col in [4, 59] {
            let p = east.get(col, row);
            assert!(p[0] < 0.1 && p[2] > 0.3, "({col}, {row}): {p:?}");
        }
    }
    // The same direction relative to the heading (30° + 60°), and the opposite direction shows no stripe.
    let relative = view(&["--yaw-deg", "60", "--from-heading"]);
    assert_eq!(relative.data, east.data);
    let west = view(&["--yaw-deg", "-90"]);
    assert!(west.data.chunks(3).all(|p| p[0] < 0.1));
}

#[test]
fn bad_input_exits_2_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("tex.png");
    save_gray(&png, &texture(64, 64, 2.0, 3)).unwrap();
    let missing = dir.path().join("missing.png");
    let out = dir.path().join("out.csv");

    let (code, _, err) = tool(&["agast", s(&missing), "--out", s(&out)]);
    assert_eq!(code, 2);
    assert!(err.contains(s(&missing)) && err.contains("exists"), "{err}");

    let (code, _, err) = tool(&["mi-register", s(&png), s(&missing)]);
    assert_eq!(code, 2);
    assert!(err.contains(s(&missing)), "{err}");

    let flat = dir.path().join("flat.png");
    save_gray(&flat, &GrayImage::filled(64, 64, 0.5)).unwrap();
    let (code, _, err) = tool(&["mi-register", s(&png), s(&flat)]);
    assert_eq!(code, 2);
    assert!(err.contains(s(&flat)) && err.contains("constant"), "{err}");

    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "x,y\n30.5,30.5\n31.5,north\n").unwrap();
    let (code, _, err) = tool(&["daisy", s(&png), "--points", s(&bad), "--out", s(&out)]);
    assert_eq!(code, 2);
    assert!(
        err.contains(s(&bad)) && err.contains("line 3") && err.contains("'north'"),
        "{err}"
    );
    assert!(!out.exists(), "no output on error");

    std::fs::write(&bad, "u,v\n30.5,30.5\n").unwrap();
    let (code, _, err) = tool(&["daisy", s(&png), "--points", s(&bad), "--out", s(&out)]);
    assert_eq!(code, 2);
    assert!(
        err.contains(s(&bad)) && err.contains("no column 'x'"),
        "{err}"
    );

    let (code, _, err) = tool(&["daisy", s(&png), "--points", s(&missing), "--out", s(&out)]);
    assert_eq!(code, 2);
    assert!(err.contains(s(&missing)), "{err}");

    let camp = stripe_campaign(dir.path(), 0.0);
    let view = dir.path().join("v.png");
    let perspective_of = |recording: &str| {
        let (code, _, err) = tool(&[
            "perspective",
            "--campaign",
            s(&camp),
            "--recording",
            recording,
            "--yaw-deg",
            "0",
            "--out",
            s(&view),
        ]);
        assert_eq!(code, 2);
        err
    };
    let err = perspective_of("r9");
    assert!(
        err.contains("mm/recordings.csv") && err.contains("'r9'"),
        "{err}"
    );
    std::fs::remove_file(camp.join("mm/panoramas/r1.png")).unwrap();
    let err = perspective_of("r1");
    assert!(err.contains("r1.png"), "{err}");
}

//! The nadir `skytie tool`s (thesis ch. 3) on the real binary with known answers: `ortho` shows a
//! panorama's east stripe east of the foot point (and on top when the image is turned to face east), `kaze` finds
//! the same keypoints on an integer-shifted copy, `forstner` locates a rectangle's corners, `wallis` brings two
//! halves of very different contrast to the target statistics, `phasecorr` recovers a sub-pixel shift, `ncc`
//! finds a cropped template and refuses a constant one.

#[path = "support/tool_cli.rs"]
mod tool_cli;

use skytie_stages::imaging::io::{load_gray, save_gray};
use skytie_stages::imaging::resample::{warp_affine, Interpolation};
use skytie_stages::imaging::{gaussian_blur, GrayImage};
use tool_cli::{bright_rectangle, csv_rows, s, stripe_campaign, texture, tool, tool_ok};

/// `w × h` crop of `img` with its top-left corner at (`x0`, `y0`).
fn crop(img: &GrayImage, x0: usize, y0: usize, w: usize, h: usize) -> GrayImage {
    let data = (0..h)
        .flat_map(|r| img.data[(y0 + r) * img.width + x0..][..w].iter().copied())
        .collect();
    GrayImage::from_vec(w, h, data).unwrap()
}

/// Mean and standard deviation of `img` over the pixels of rows `rows` and columns `cols`.
fn stats(
    img: &GrayImage,
    rows: std::ops::Range<usize>,
    cols: std::ops::Range<usize>,
) -> (f64, f64) {
    let values: Vec<f64> = rows
        .flat_map(|r| cols.clone().map(move |c| (c, r)))
        .map(|(c, r)| img.get(c, r) as f64)
        .collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}

/// The numbers a tool printed on one line.
fn numbers(stdout: &str) -> Vec<f64> {
    stdout
        .split_whitespace()
        .map(|t| {
            t.parse()
                .unwrap_or_else(|_| panic!("not a number: {t:?} in {stdout:?}"))
        })
        .collect()
}

#[test]
fn ortho_shows_the_east_stripe_east_of_the_foot_point() {
    let dir = tempfile::tempdir().unwrap();
    // Red stripe at azimuth 90° ± 4° on dark blue; camera 2.5 m above the ground.
    let camp = stripe_campaign(dir.path(), 0.0);
    let out = dir.path().join("ortho.png");
    let ortho = |rotate_deg: &str| {
        let stdout = tool_ok(&[
            "ortho",
            "--campaign",
            s(&camp),
            "--recording",
            "r1",
            "--gsd",
            "0.1",
            "--rotate-deg",
            rotate_deg,
            "--out",
            s(&out),
        ]);
        // 30 m diagonal at 0.1 m: 212 px square; the foot point is 2.5 m below the camera.
        assert!(
            stdout.contains("212×212 px") && stdout.contains("500000.000 5400000.000 100.000"),
            "{stdout}"
        );
        load_gray(&out).unwrap()
    };
    // North up: 8.4 m east of the foot point (col 190, centre row 106) the stripe is ±0.59 m = ±5.9 px wide.
    let north_up = ortho("0");
    let (stripe, ground) = (0.2, 0.02..0.1);
    for row in 104..=108 {
        assert!(north_up.get(190, row) > stripe, "east, row {row}");
    }
    for (col, row) in [(190, 95), (190, 117), (20, 106), (106, 20), (106, 192)] {
        let v = north_up.get(col, row);
        assert!(ground.contains(&v), "({col}, {row}) = {v}: not the stripe");
    }
    // Up = east: the stripe now runs from the centre to the top edge.
    let east_up = ortho("90");
    for col in 104..=108 {
        assert!(east_up.get(col, 22) > stripe, "top, col {col}");
    }
    for (col, row) in [(190, 106), (20, 106), (106, 192)] {
        let v = east_up.get(col, row);
        assert!(ground.contains(&v), "({col}, {row}) = {v}: not the stripe");
    }
}

#[test]
fn kaze_finds_the_same_keypoints_on_an_integer_shifted_copy() {
    let dir = tempfile::tempdir().unwrap();
    // B shows A's content moved by (7, 5) px: a keypoint at (x, y) in A belongs at (x + 7, y + 5) in B.
    let big = texture(200, 160, 2.0, 11);
    let (a_png, b_png) = (dir.path().join("a.png"), dir.path().join("b.png"));
    save_gray(&a_png, &crop(&big, 20, 20, 160, 120)).unwrap();
    save_gray(&b_png, &crop(&big, 13, 15, 160, 120)).unwrap();
    let run = |png: &std::path::Path, name: &str| {
        let csv = dir.path().join(name);
        let stdout = tool_ok(&[
            "kaze",
            s(png),
            "--threshold",
            "0.001",
            "--octaves",
            "1",
            "--upright",
            "--extended",
            "--descriptors",
            "--out",
            s(&csv),
        ]);
        assert!(stdout.contains("keypoints"), "{stdout}");
        let header = std::fs::read_to_string(&csv).unwrap();
        let header = header.lines().next().unwrap().to_string();
        assert!(
            header.ends_with(",d127") && !header.contains("d128"),
            "{header}"
        );
        csv_rows(&csv, "x,y,size,response")
            .into_iter()
            .map(|r| {
                assert_eq!(r.len(), 4 + 128);
                (r[0].parse::<f64>().unwrap(), r[1].parse::<f64>().unwrap())
            })
            .collect::<Vec<_>>()
    };
    let (a, b) = (run(&a_png, "a.csv"), run(&b_png, "b.csv"));
    // A's keypoints whose shifted place lies well inside B (away from both images' borders).
    let inside: Vec<_> = a
        .iter()
        .map(|&(x, y)| (x + 7.0, y + 5.0))
        .filter(|&(x, y)| (25.0..135.0).contains(&x) && (25.0..95.0).contains(&y))
        .collect();
    assert!(inside.len() >= 20, "{} keypoints inside", inside.len());
    let found = inside
        .iter()
        .filter(|&&(x, y)| b.iter().any(|&(u, v)| (u - x).hypot(v - y) <= 1.0))
        .count();
    assert!(
        found * 10 >= inside.len() * 9,
        "{found} of {} keypoints repeated",
        inside.len()
    );
}

#[test]
fn forstner_locates_the_corners_of_a_rectangle() {
    let dir = tempfile::tempdir().unwrap();
    let img = bright_rectangle(0.2);
    let png = dir.path().join("rect.png");
    save_gray(&png, &gaussian_blur(&img, 1.0)).unwrap();
    let csv = dir.path().join("corners.csv");
    tool_ok(&["forstner", s(&png), "--out", s(&csv)]);
    let corners: Vec<(f64, f64)> = csv_rows(&csv, "x,y,weight,roundness")
        .iter()
        .map(|r| (r[0].parse().unwrap(), r[1].parse().unwrap()))
        .collect();
    for (x, y) in [(25.0, 20.0), (55.0, 20.0), (25.0, 40.0), (55.0, 40.0)] {
        let nearest = corners
            .iter()
            .map(|&(u, v)| (u - x).hypot(v - y))
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest <= 0.25,
            "corner ({x}, {y}): nearest at {nearest:.3} px"
        );
    }
}

#[test]
fn wallis_brings_low_and_high_contrast_halves_to_the_target_statistics() {
    let dir = tempfile::tempdir().unwrap();
    // The texture (0.1..0.9) scaled by 0.125 around 0.3 in the left half, by 0.75 around 0.6 in the right.
    let tex = texture(160, 80, 2.0, 5);
    let mut img = tex.clone();
    for r in 0..80 {
        for c in 0..160 {
            let t = tex.get(c, r) - 0.5;
            img.set(
                c,
                r,
                if c < 80 {
                    0.3 + 0.125 * t
                } else {
                    0.6 + 0.75 * t
                },
            );
        }
    }
    let (png, out) = (dir.path().join("in.png"), dir.path().join("wallis.png"));
    save_gray(&png, &img).unwrap();
    tool_ok(&["wallis", s(&png), "--out", s(&out)]);
    let filtered = load_gray(&out).unwrap();
    assert_eq!((filtered.width, filtered.height), (160, 80));
    // Defaults (Wallis 1976; Baltsavias 1991): target mean m_f = 127/255, std s_f = 40/255, contrast constant c = 0.94,
    // brightness b = 1. A region of std s_g comes out with std s_f·c·s_g / (c·s_g + (1 − c)·s_f) (the gain is
    // capped, so a very flat region stays below s_f) and the target mean. Measured away from the seam and border.
    let (m_f, s_f, c) = (127.0 / 255.0, 40.0 / 255.0, 0.94);
    let (mut in_std, mut out_std) = (Vec::new(), Vec::new());
    for (half, cols) in [("left", 15..65), ("right", 95..145)] {
        let (_, s_g) = stats(&img, 15..65, cols.clone());
        in_std.push(s_g);
        let (mean, std) = stats(&filtered, 15..65, cols);
        let want = s_f * c * s_g / (c * s_g + (1.0 - c) * s_f);
        assert!((mean - m_f).abs() < 0.03, "{half}: mean {mean}");
        assert!(
            (std / want - 1.0).abs() < 0.2,
            "{half}: std {std}, formula {want}"
        );
        out_std.push(std);
    }
    // A 5:1 contrast difference (the halves were scaled by 0.125 and 0.75) shrinks to less than 2:1.
    assert!(in_std[1] > 5.0 * in_std[0], "{in_std:?}");
    assert!(out_std[1] < 2.0 * out_std[0], "{out_std:?}");
}

#[test]
fn phasecorr_recovers_a_subpixel_shift() {
    let dir = tempfile::tempdir().unwrap();
    let big = texture(128, 128, 2.0, 9);
    // moving(x) = reference(x − t), t = (2.3, −1.6): sample the big texture at x − t + offset.
    let (tx, ty) = (2.3, -1.6);
    let reference = warp_affine(
        &big,
        [1.0, 0.0, 32.0, 0.0, 1.0, 32.0],
        64,
        64,
        Interpolation::Bicubic,
        0.0,
    );
    let moving = warp_affine(
        &big,
        [1.0, 0.0, 32.0 - tx, 0.0, 1.0, 32.0 - ty],
        64,
        64,
        Interpolation::Bicubic,
        0.0,
    );
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    save_gray(&a, &reference).unwrap();
    save_gray(&b, &moving).unwrap();
    let v = numbers(&tool_ok(&["phasecorr", s(&a), s(&b)]));
    assert_eq!(v.len(), 3, "dx dy peak: {v:?}");
    assert!(
        (v[0] - tx).hypot(v[1] - ty) <= 0.1,
        "found ({}, {}), applied ({tx}, {ty})",
        v[0],
        v[1]
    );
    assert!(v[2] > 0.3, "peak {}", v[2]);
}

#[test]
fn ncc_finds_a_cropped_template_and_refuses_a_constant_one() {
    let dir = tempfile::tempdir().unwrap();
    let img = texture(100, 80, 2.0, 21);
    let (image_png, template_png) = (dir.path().join("image.png"), dir.path().join("tpl.png"));
    save_gray(&image_png, &img).unwrap();
    // 24 × 20 template from top-left (37, 21): its centre is at (49, 31).
    save_gray(&template_png, &crop(&img, 37, 21, 24, 20)).unwrap();
    let v = numbers(&tool_ok(&["ncc", s(&template_png), s(&image_png)]));
    assert_eq!(v.len(), 3, "x y score: {v:?}");
    assert!(
        (v[0] - 49.0).abs() < 0.05 && (v[1] - 31.0).abs() < 0.05,
        "{v:?}"
    );
    assert!(v[2] > 0.999, "score {}", v[2]);

    let flat = dir.path().join("flat.png");
    save_gray(&flat, &GrayImage::filled(24, 20, 0.5)).unwrap();
    let (code, _, err) = tool(&["ncc", s(&flat), s(&image_png)]);
    assert_eq!(code, 2);
    assert!(err.contains(s(&flat)) && err.contains("constant"), "{err}");
}

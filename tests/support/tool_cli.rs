//! Shared helpers of the tests that drive `skytie tool …` (tools_nadir, tools_oblique): the command and its
//! output, CSV rows, a band-limited test texture, a bright rectangle and a one-recording stripe campaign.
#![allow(dead_code)]

use skytie_stages::imaging::io::save_rgb;
use skytie_stages::imaging::{GrayImage, RgbImage};
use skytie_stages::synth::test_texture::band_limited_noise;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Exit code, stdout, stderr of `skytie tool ARGS…`.
pub fn tool(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_skytie"))
        .arg("tool")
        .args(args)
        .output()
        .expect("start skytie");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

pub fn tool_ok(args: &[&str]) -> String {
    let (code, stdout, stderr) = tool(args);
    assert_eq!(code, 0, "skytie tool {args:?} failed: {stdout}{stderr}");
    stdout
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Data rows of a CSV (header checked against `header_prefix`), split into fields.
pub fn csv_rows(path: &Path, header_prefix: &str) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().expect("a header row");
    assert!(
        header.starts_with(header_prefix),
        "header {header:?} of {}",
        path.display()
    );
    lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// Band-limited noise in [0.1, 0.9]: uniform noise blurred with σ = `sigma_px`, stretched.
pub fn texture(w: usize, h: usize, sigma_px: f32, seed: u64) -> GrayImage {
    let mut img = band_limited_noise(w, h, sigma_px, seed);
    img.data.iter_mut().for_each(|v| *v = 0.1 + 0.8 * *v);
    img
}

/// An 80×60 image of `background` grey with pixels 25..=54 × 20..=39 at 0.8: a rectangle whose corners are
/// (25, 20), (55, 20), (25, 40), (55, 40).
pub fn bright_rectangle(background: f32) -> GrayImage {
    let mut img = GrayImage::filled(80, 60, background);
    for r in 20..40 {
        for c in 25..55 {
            img.set(c, r, 0.8);
        }
    }
    img
}

/// A one-recording campaign in `dir/camp` (returned) whose 360×180 panorama is dark blue except for a red
/// stripe at azimuth 90° ± 4° (east; equirectangular columns u = W·(A + 180°)/360°).
pub fn stripe_campaign(dir: &Path, heading_deg: f64) -> PathBuf {
    let root = dir.join("camp");
    std::fs::create_dir_all(root.join("mm/panoramas")).unwrap();
    std::fs::write(
        root.join("mm/recordings.csv"),
        format!(
            "image_id,file,time,x,y,z,heading,camera_height\n\
             r1,r1.png,2019-06-14T10:31:07Z,500000.0,5400000.0,102.5,{heading_deg},2.5\n"
        ),
    )
    .unwrap();
    let mut pano = RgbImage::filled(360, 180, [0.0, 0.0, 0.4]);
    for r in 0..180 {
        for c in 266..274 {
            pano.set(c, r, [1.0, 0.0, 0.0]);
        }
    }
    save_rgb(&root.join("mm/panoramas/r1.png"), &pano, 95).unwrap();
    root
}

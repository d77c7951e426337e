//! Parameters mean the same on the ground whatever the sensor size: the tiny synthetic campaign and a copy with
//! its images upsampled 4× (each grey pixel skytie reads repeated 4 × 4 times, written as grey PNG so the copy
//! adds no JPEG re-encoding and no colour round trip) and every pixel coordinate and size of its tables scaled
//! by 4 (aerial `focal_px`, `cx`, `cy`, `width`, `height`; observed `u`, `v` of check points; not `sigma_px`,
//! which is a precision in pixels of the resolution an image is measured at) run through the shipped tiny chain
//! (`workflows/tiny.toml`, with the refinement's peak threshold lowered so that the tiny campaign yields aerial
//! control) with no parameter changed between the two, and are compared:
//! - nadir chain: the vehicle box found in the panoramas (within 1 mm), MM tie points and their share that is
//!   correct against the truth, the initial transforms tried and accepted, the tie points located in the
//!   aerial frames and their graded inlier ratio (± 0.02), the aerial control points (positions within 1 mm);
//! - oblique chain: the graded inlier ratio before and after the consensus (± 0.02);
//! - the adjusted positions of every recording (within 1 cm, `trajectory_adjusted.csv`);
//! - the verification of the recorded and of the adjusted trajectory: mean horizontal offset and its σ
//!   (within 1 mm).
//!
//! The scaled copy is written from the first campaign by the test (not re-rendered). With the aerial frames
//! upsampled, and with every image upsampled, everything must be the same (`docs/real-size-images.md`).

#[path = "support/cli.rs"]
mod cli;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Linear upsampling factor of the copy.
const FACTOR: u32 = 4;
/// CSV columns that hold pixel coordinates and sizes (scaled by [`FACTOR`]).
const PIXEL_COLUMNS: [&str; 7] = ["focal_px", "cx", "cy", "width", "height", "u", "v"];

/// Writes the 4× copy of the image `src` as an 8-bit grey PNG at `dst`: the grey values skytie reads from
/// `src` (the luma plane of a colour JPEG), each repeated 4 × 4 times. Grey, because a colour copy would take
/// the luma through YCbCr → RGB → grey and change some values by rounding, which is no matter of image size.
fn upsample_image(src: &Path, dst: &Path) {
    let grey = skytie_stages::imaging::io::load_gray(src)
        .unwrap_or_else(|e| panic!("{}: {e}", src.display()));
    let f = FACTOR as usize;
    let (w, h) = (grey.width * f, grey.height * f);
    let samples: Vec<u8> = (0..w * h)
        .map(|i| (grey.get(i % w / f, i / w / f) * 255.0).round() as u8)
        .collect();
    image::GrayImage::from_raw(w as u32, h as u32, samples)
        .expect("w × h samples")
        .save_with_format(dst, image::ImageFormat::Png)
        .unwrap_or_else(|e| panic!("{}: {e}", dst.display()));
}

/// `name` with its extension replaced by `png`.
fn png_name(name: &str) -> String {
    match name.rsplit_once('.') {
        Some((stem, _)) => format!("{stem}.png"),
        None => format!("{name}.png"),
    }
}

/// Which images of the campaign the copy upsamples.
#[derive(Clone, Copy, PartialEq)]
enum Upsample {
    /// Panoramas, nadir and oblique frames.
    All,
    /// The nadir and oblique frames only (panoramas as they are).
    AerialOnly,
}

impl Upsample {
    /// Whether the file `rel` (relative to the campaign) belongs to the upsampled images or their tables:
    /// `aerial/…` and `truth/aerial_*.csv` are aerial, everything else (panoramas, `mm/recordings.csv`, check
    /// point observations, `truth/recordings.csv`) belongs to the panoramas.
    fn scales(self, rel: &Path) -> bool {
        let aerial = rel.starts_with("aerial")
            || rel
                .file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("aerial_"));
        self == Upsample::All || aerial
    }
}

/// The CSV `text` with its pixel columns scaled and its `file` column renamed to the PNG copies.
fn scale_csv(text: &str) -> String {
    let mut header: Option<Vec<String>> = None;
    let mut out = String::new();
    for line in text.lines() {
        if line.starts_with('#') || line.trim().is_empty() {
            out.push_str(line);
        } else if let Some(cols) = &header {
            let fields: Vec<String> = line
                .split(',')
                .zip(cols)
                .map(|(v, c)| {
                    if c == "file" {
                        png_name(v)
                    } else if PIXEL_COLUMNS.contains(&c.as_str()) {
                        let x: f64 = v.trim().parse().unwrap_or_else(|_| panic!("{c} = {v}"));
                        format!("{}", x * f64::from(FACTOR))
                    } else {
                        v.to_string()
                    }
                })
                .collect();
            out.push_str(&fields.join(","));
        } else {
            header = Some(line.split(',').map(|c| c.trim().to_string()).collect());
            out.push_str(line);
        }
        out.push('\n');
    }
    out
}

/// Copies the campaign folder `root`/`rel` to `dst`/`rel`: the images `what` selects upsampled 4× as PNG and
/// their CSV tables scaled, every other file as it is.
fn scaled_copy(root: &Path, dst: &Path, rel: &Path, what: Upsample) {
    std::fs::create_dir_all(dst.join(rel)).unwrap();
    for e in std::fs::read_dir(root.join(rel)).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let rel_p = rel.join(&name);
        let ext = p.extension().map(|x| x.to_string_lossy().to_lowercase());
        let to = dst.join(rel);
        match ext.as_deref() {
            _ if p.is_dir() => scaled_copy(root, dst, &rel_p, what),
            Some("jpg" | "jpeg" | "png" | "tif" | "tiff") if what.scales(&rel_p) => {
                upsample_image(&p, &to.join(png_name(&name)))
            }
            Some("csv") if what.scales(&rel_p) => std::fs::write(
                to.join(&name),
                scale_csv(&std::fs::read_to_string(&p).unwrap()),
            )
            .unwrap(),
            _ => {
                std::fs::copy(&p, to.join(&name)).unwrap();
            }
        }
    }
}

/// The shipped tiny chain (`workflows/tiny.toml`) with the refinement's peak threshold at 0.5, so that tiny's
/// 1024-px panoramas yield aerial control and the adjustment corrects the trajectory (see `pipeline_tiny.rs`).
fn write_workflow(work: &Path) -> PathBuf {
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("workflows/tiny.toml");
    let mut text = std::fs::read_to_string(shipped).unwrap();
    text.push_str("\n[refine]\nmin_peak = 0.5\n");
    let wf = work.join("tiny-control.toml");
    std::fs::write(&wf, text).unwrap();
    wf
}

/// Runs the chain of [`write_workflow`] on `campaign`; returns its metrics and its output folder.
fn run_chain(campaign: &Path, work: &Path, tag: &str) -> (serde_json::Value, PathBuf) {
    let wf = write_workflow(work);
    let out = work.join(format!("out-{tag}"));
    cli::run_finished(
        cli::skytie()
            .arg("run")
            .arg(&wf)
            .arg("--campaign")
            .arg(campaign)
            .arg("--cache")
            .arg(work.join(format!("cache-{tag}")))
            .arg("--out")
            .arg(&out)
            .arg("--quiet"),
    );
    let m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("metrics.json")).unwrap()).unwrap();
    (m, out)
}

/// `id → (x, y, z)` of the CSV `path` (rows keyed by column `id_col`); empty when the file is missing.
fn positions(path: &Path, id_col: &str) -> BTreeMap<String, [f64; 3]> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return BTreeMap::new();
    };
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let (id, x, y, z) = (col(id_col), col("x"), col("y"), col("z"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let num = |i: usize| f[i].parse::<f64>().unwrap();
            (f[id].to_string(), [num(x), num(y), num(z)])
        })
        .collect()
}

/// Differences between two sets of points larger than `tolerance_m` (and missing or extra points).
fn position_problems(
    what: &str,
    a: &BTreeMap<String, [f64; 3]>,
    b: &BTreeMap<String, [f64; 3]>,
    tolerance_m: f64,
) -> Vec<String> {
    let mut problems = Vec::new();
    if a.is_empty() || a.len() != b.len() {
        problems.push(format!("{what}: {} vs {} points", a.len(), b.len()));
    }
    for (id, p) in a {
        let Some(q) = b.get(id) else { continue };
        let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
        println!("{what} {id}: {d:.4} m apart");
        if d > tolerance_m {
            problems.push(format!("{what} {id}: {p:?} vs {q:?} ({d:.4} m apart)"));
        }
    }
    problems
}

fn num(m: &serde_json::Value, path: &[&str]) -> Option<f64> {
    path.iter().try_fold(m, |v, k| v.get(k))?.as_f64()
}

/// The metrics at `path` of both runs: missing, or more than `tolerance` apart.
fn value_problems(
    m1: &serde_json::Value,
    m4: &serde_json::Value,
    path: &[&str],
    tolerance: f64,
) -> Vec<String> {
    let (a, b) = (num(m1, path), num(m4, path));
    println!("{path:?}: {a:?} vs {b:?}");
    match (a, b) {
        (Some(a), Some(b)) if (a - b).abs() <= tolerance => Vec::new(),
        _ => vec![format!("{path:?}: {a:?} vs {b:?}")],
    }
}

/// Differences of the nadir registration: the vehicle box within 1 mm, counts within 5 % (at least 1),
/// ratios within 0.02.
fn nadir_problems(m1: &serde_json::Value, m4: &serde_json::Value) -> Vec<String> {
    let mut problems = Vec::new();
    for key in ["front_m", "rear_m", "half_width_m"] {
        problems.extend(value_problems(m1, m4, &["vehicle", key], 0.001));
    }
    for key in [
        "mm_tie_points",
        "transforms_tried",
        "transforms_accepted",
        "tie_points",
        "control_points",
    ] {
        let (a, b) = (num(m1, &["nadir", key]), num(m4, &["nadir", key]));
        let (a, b) = (a.unwrap_or_else(|| panic!("nadir.{key}: {m1}")), b.unwrap());
        println!("nadir.{key}: {a} vs {b}");
        if (a - b).abs() > (0.05 * a).max(1.0) {
            problems.push(format!("nadir.{key}: {a} vs {b}"));
        }
    }
    let correct = |m: &serde_json::Value| {
        num(m, &["nadir", "mm_tie_points_correct"]).unwrap()
            / num(m, &["nadir", "mm_tie_points_graded"]).unwrap()
    };
    if (correct(m1) - correct(m4)).abs() > 0.02 {
        problems.push(format!(
            "share of correct MM tie points: {} vs {}",
            correct(m1),
            correct(m4)
        ));
    }
    problems.extend(ratio_problems(m1, m4, &["nadir", "inlier_ratio"]));
    problems
}

/// `path` of both metrics: missing, or more than 0.02 apart.
fn ratio_problems(m1: &serde_json::Value, m4: &serde_json::Value, path: &[&str]) -> Vec<String> {
    value_problems(m1, m4, path, 0.02)
}

/// Differences of the verifications (recorded and adjusted trajectory): the overall mean horizontal offset
/// and its σ per axis, within 1 mm.
fn verify_problems(m1: &serde_json::Value, m4: &serde_json::Value) -> Vec<String> {
    let mut problems = Vec::new();
    for table in ["verify", "verify_adjusted"] {
        problems.extend(value_problems(
            m1,
            m4,
            &[table, "overall", "offset_2d_m"],
            0.001,
        ));
        for axis in 0..3 {
            let sigma = |m: &serde_json::Value| m[table]["overall"]["sigma_mean_m"][axis].as_f64();
            let (a, b) = (sigma(m1), sigma(m4));
            println!("{table}.overall.sigma_mean_m[{axis}]: {a:?} vs {b:?}");
            if !matches!((a, b), (Some(a), Some(b)) if (a - b).abs() <= 0.001) {
                problems.push(format!(
                    "{table}.overall.sigma_mean_m[{axis}]: {a:?} vs {b:?}"
                ));
            }
        }
    }
    problems
}

/// What differs between the chain on the tiny campaign and on its copy with `what` upsampled.
#[derive(Default)]
struct Differences {
    /// Nadir registration (module doc) and the aerial control points' positions (within 1 mm).
    nadir: Vec<String>,
    /// Oblique inlier ratios before and after the consensus.
    oblique: Vec<String>,
    /// Adjusted positions (within 1 cm).
    adjusted: Vec<String>,
    /// Verifications of the recorded and the adjusted trajectory.
    verify: Vec<String>,
}

fn compare_with_upsampled(what: Upsample) -> Differences {
    let work = tempfile::tempdir().unwrap();
    let base = work.path().join("base");
    cli::synth_tiny(&base, 1, &[]);
    let big = work.path().join("big");
    scaled_copy(&base, &big, Path::new(""), what);
    let (m1, out1) = run_chain(&base, work.path(), "base");
    let (m4, out4) = run_chain(&big, work.path(), "big");
    for m in [&m1, &m4] {
        assert_eq!(m["engine"]["nodes_failed"].as_u64(), Some(0), "{m}");
    }
    let mut d = Differences {
        nadir: nadir_problems(&m1, &m4),
        ..Differences::default()
    };
    let control = |out: &Path| positions(&out.join("ground_control/control_points.csv"), "label");
    d.nadir.extend(position_problems(
        "control point",
        &control(&out1),
        &control(&out4),
        0.001,
    ));
    for path in [
        &["oblique", "inlier_ratio"][..],
        &["oblique", "inlier_ratio_after_consensus"][..],
    ] {
        d.oblique.extend(ratio_problems(&m1, &m4, path));
    }
    let adjusted = |out: &Path| positions(&out.join("trajectory_adjusted.csv"), "image_id");
    d.adjusted = position_problems("adjusted", &adjusted(&out1), &adjusted(&out4), 0.01);
    d.verify = verify_problems(&m1, &m4);
    d
}

/// Every difference, one per line.
fn report(parts: &[&Vec<String>]) -> String {
    parts
        .iter()
        .flat_map(|p| p.iter())
        .cloned()
        .collect::<Vec<_>>()
        .join("\n")
}

/// The whole comparison with `what` upsampled must find no difference.
fn assert_same_everywhere(what: Upsample) {
    let d = compare_with_upsampled(what);
    let all = report(&[&d.nadir, &d.oblique, &d.adjusted, &d.verify]);
    assert!(all.is_empty(), "{all}");
}

/// The aerial frames read at their registration level: nadir frames 4× finer (2.5 cm instead of 10 cm) give
/// the same MM tie points, initial transforms, located tie points, graded inlier ratio and aerial control
/// points (positions within 1 mm).
#[test]
fn aerial_frames_upsampled_4x_give_the_same_nadir_registration() {
    let d = compare_with_upsampled(Upsample::AerialOnly);
    assert!(d.nadir.is_empty(), "{}", report(&[&d.nadir]));
}

/// The whole comparison with only the aerial frames upsampled: also the oblique chain (the patches are made at
/// the oblique frame's level of the original's resolution, its detail level, even where that is coarser than
/// `registration_resolution_m`), the adjusted trajectory (control points are as precise as the pixels of
/// the level they were located at: `sigma_px` of that level) and the verifications.
#[test]
fn aerial_frames_upsampled_4x_give_the_same_adjusted_trajectory() {
    assert_same_everywhere(Upsample::AerialOnly);
}

/// Every image upsampled 4×. The panoramas are read at their detail level wherever a finer level would be
/// chosen (the vehicle detection, the ortho images, the sparse cloud's views, the façade patches), and their
/// observations are weighted by `pano_sigma_px` pixels of that level (adjustment and verification), so the
/// vehicle box, MM tie points, initial transforms, located tie points, control points, oblique inlier ratios,
/// adjusted positions and verifications are the original's.
#[test]
fn a_campaign_upsampled_4x_registers_like_the_original() {
    assert_same_everywhere(Upsample::All);
}

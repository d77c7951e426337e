//! Parameters mean the same on the ground whatever the sensor size: the tiny synthetic campaign and the same
//! campaign with every image upsampled 4× (panoramas, nadir and oblique frames; bilinear, pixel centres kept
//! in place) and every pixel quantity of its tables scaled by 4 (aerial `focal_px`, `cx`, `cy`, `width`,
//! `height`, `sigma_px`; observed `u`, `v` of check points) run through the shipped full chain
//! (`workflows/tiny.toml`, with the refinement's peak threshold lowered so that the tiny campaign yields aerial
//! control) with no parameter changed between the two, and must give the same registrations:
//! - nadir chain: MM tie points and their share that is correct against the truth, the initial transforms
//!   tried and accepted, and the inlier ratio of the nadir registration (± 0.02);
//! - oblique chain: the consensus inlier ratio (± 0.02) when the chain yields correspondences;
//! - the adjusted positions of every recording (within 1 cm, `trajectory_adjusted.csv`).
//!
//! The scaled copy is written from the first campaign by this test (not re-rendered); the files are PNG so the
//! copy carries no JPEG re-encoding of its own.

#[path = "support/cli.rs"]
mod cli;

use image::imageops::FilterType;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Linear upsampling factor of the copy.
const FACTOR: u32 = 4;
/// CSV columns that hold pixel quantities (scaled by [`FACTOR`]).
const PIXEL_COLUMNS: [&str; 8] = [
    "focal_px", "cx", "cy", "width", "height", "sigma_px", "u", "v",
];

/// Writes the 4× copy of the image `src` as PNG at `dst`.
fn upsample_image(src: &Path, dst: &Path) {
    let img = image::open(src).unwrap_or_else(|e| panic!("{}: {e}", src.display()));
    let (w, h) = (img.width() * FACTOR, img.height() * FACTOR);
    img.resize_exact(w, h, FilterType::Nearest)
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

/// Runs the chain of [`write_workflow`] on `campaign`; returns its metrics and adjusted positions by image id.
fn run_chain(
    campaign: &Path,
    work: &Path,
    tag: &str,
) -> (serde_json::Value, BTreeMap<String, [f64; 3]>) {
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
    (m, adjusted_positions(&out.join("trajectory_adjusted.csv")))
}

/// `image_id → (x, y, z)` of an adjusted trajectory.
fn adjusted_positions(path: &Path) -> BTreeMap<String, [f64; 3]> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return BTreeMap::new();
    };
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let (id, x, y, z) = (col("image_id"), col("x"), col("y"), col("z"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let num = |i: usize| f[i].parse::<f64>().unwrap();
            (f[id].to_string(), [num(x), num(y), num(z)])
        })
        .collect()
}

fn num(m: &serde_json::Value, path: &[&str]) -> Option<f64> {
    path.iter().try_fold(m, |v, k| v.get(k))?.as_f64()
}

/// Runs the chain on the tiny campaign and on its copy with `what` upsampled, and compares the registrations
/// (module doc); panics with every difference found.
fn compare_with_upsampled(what: Upsample) {
    let work = tempfile::tempdir().unwrap();
    let work = Box::leak(Box::new(work));
    println!("WORK {}", work.path().display());
    let base = work.path().join("base");
    cli::run_ok(
        cli::skytie()
            .args(["synth", "--preset", "tiny", "--seed", "1", "--out"])
            .arg(&base),
    );
    let big = work.path().join("big");
    scaled_copy(&base, &big, Path::new(""), what);
    let (m1, pos1) = run_chain(&base, work.path(), "base");
    let (m4, pos4) = run_chain(&big, work.path(), "big");
    for m in [&m1, &m4] {
        assert_eq!(m["engine"]["nodes_failed"].as_u64(), Some(0), "{m}");
    }
    let mut problems = Vec::new();

    // The nadir chain: counts within 5 % (at least 1), ratios within 0.02.
    for key in [
        "mm_tie_points",
        "transforms_tried",
        "transforms_accepted",
        "tie_points",
        "control_points",
    ] {
        let (a, b) = (num(&m1, &["nadir", key]), num(&m4, &["nadir", key]));
        let (a, b) = (a.unwrap_or_else(|| panic!("nadir.{key}: {m1}")), b.unwrap());
        println!("nadir.{key}: {a} vs {b}");
        if (a - b).abs() > (0.05 * a).max(1.0) {
            problems.push(format!("nadir.{key}: {a} vs {b}"));
        }
    }
    for path in [
        &["nadir", "inlier_ratio"][..],
        &["oblique", "inlier_ratio"][..],
        &["oblique", "inlier_ratio_after_consensus"][..],
    ] {
        let (a, b) = (num(&m1, path), num(&m4, path));
        println!("{path:?}: {a:?} vs {b:?}");
        match (a, b) {
            (Some(a), Some(b)) if (a - b).abs() <= 0.02 => {}
            _ => problems.push(format!("{path:?}: {a:?} vs {b:?}")),
        }
    }
    let correct = |m: &serde_json::Value| {
        num(m, &["nadir", "mm_tie_points_correct"]).unwrap()
            / num(m, &["nadir", "mm_tie_points_graded"]).unwrap()
    };
    if (correct(&m1) - correct(&m4)).abs() > 0.02 {
        problems.push(format!(
            "share of correct MM tie points: {} vs {}",
            correct(&m1),
            correct(&m4)
        ));
    }

    // The adjusted trajectory.
    if pos1.is_empty() || pos1.len() != pos4.len() {
        problems.push(format!(
            "adjusted trajectories of {} and {} recordings (the run did not correct the trajectory?)",
            pos1.len(),
            pos4.len()
        ));
    }
    for (id, a) in &pos1 {
        let Some(b) = pos4.get(id) else { continue };
        let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        println!("{id}: adjusted positions {d:.4} m apart");
        if d > 0.01 {
            problems.push(format!("{id}: adjusted {a:?} vs {b:?} ({d:.4} m apart)"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn aerial_frames_upsampled_4x_register_like_the_original() {
    compare_with_upsampled(Upsample::AerialOnly);
}

#[test]
fn a_campaign_upsampled_4x_registers_like_the_original() {
    compare_with_upsampled(Upsample::All);
}

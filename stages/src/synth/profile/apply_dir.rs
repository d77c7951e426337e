//! A profile applied to an error-free campaign folder rendered by the generator: reads the true tables, writes
//! a new campaign folder with the recorded tables of the profile, `truth/README.md` and (when the aerial poses
//! or lens parameters were changed) `truth/aerial_{nadir,oblique}.csv`, and hard-links every other file (the
//! images, check points, `truth/recordings.csv`, `truth/scene.toml`), so that campaigns of one scene with
//! different table-only profiles share their image bytes. Where a hard link is impossible the file is copied.

use super::readme::readme;
use super::{Profile, Tables};
use crate::campaign::write as cw;
use crate::campaign::{read_aerial_csv, read_recordings_csv, AerialImage, Severity};
use crate::crs::CoordinateFrame;
use crate::synth::SynthError;
use std::path::Path;

/// The files a profile writes itself (never linked from the rendered folder).
const WRITTEN: [&str; 7] = [
    "campaign.toml",
    "mm/recordings.csv",
    "aerial/nadir/cameras.csv",
    "aerial/oblique/cameras.csv",
    "truth/README.md",
    "truth/aerial_nadir.csv",
    "truth/aerial_oblique.csv",
];

/// Every file below `root` as a path relative to it with `/`, sorted.
fn relative_files(root: &Path) -> Result<Vec<String>, SynthError> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) -> Result<(), SynthError> {
        for entry in std::fs::read_dir(dir).map_err(|e| SynthError::io(dir, e))? {
            let path = entry.map_err(|e| SynthError::io(dir, e))?.path();
            if path.is_dir() {
                walk(root, &path, out)?;
            } else if let Ok(rel) = path.strip_prefix(root) {
                let parts: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                out.push(parts.join("/"));
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(root, root, &mut out)?;
    out.sort();
    Ok(out)
}

/// The aerial table `rel` of the rendered folder (empty when the folder has none); any error is fatal.
fn read_true_aerial(rendered: &Path, rel: &str) -> Result<Vec<AerialImage>, SynthError> {
    let path = rendered.join(rel);
    if !path.is_file() {
        return Ok(Vec::new());
    }
    let (rows, problems) = read_aerial_csv(&path);
    match problems.iter().find(|p| p.severity == Severity::Error) {
        Some(p) => Err(SynthError::io(&path, p)),
        None => Ok(rows),
    }
}

/// The true tables of a rendered folder.
fn read_truth(rendered: &Path) -> Result<Tables, SynthError> {
    let path = rendered.join("truth/recordings.csv");
    if !path.is_file() {
        return Err(SynthError::io(
            &path,
            "missing: a profile is applied to a folder rendered by skytie's generator (with truth/)",
        ));
    }
    let (recordings, problems) = read_recordings_csv(&path);
    if let Some(p) = problems.iter().find(|p| p.severity == Severity::Error) {
        return Err(SynthError::io(&path, p));
    }
    Ok(Tables {
        recordings,
        nadir: read_true_aerial(rendered, "aerial/nadir/cameras.csv")?,
        oblique: read_true_aerial(rendered, "aerial/oblique/cameras.csv")?,
    })
}

/// The `crs` and `frame` of the rendered folder's `campaign.toml`.
fn read_crs(rendered: &Path) -> Result<(String, CoordinateFrame), SynthError> {
    let path = rendered.join("campaign.toml");
    let text = std::fs::read_to_string(&path).map_err(|e| SynthError::io(&path, e))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| SynthError::io(&path, e))?;
    let crs = table
        .get("crs")
        .and_then(|v| v.as_str())
        .unwrap_or_default()
        .to_string();
    let frame = match table.get("frame").and_then(|v| v.as_str()) {
        Some("cartesian") => CoordinateFrame::Cartesian,
        _ => CoordinateFrame::Projected,
    };
    Ok((crs, frame))
}

/// Hard-link (else copy) `from` to `to`, creating `to`'s folder.
fn link_or_copy(from: &Path, to: &Path) -> Result<(), SynthError> {
    if let Some(dir) = to.parent() {
        std::fs::create_dir_all(dir).map_err(|e| SynthError::io(dir, e))?;
    }
    if std::fs::hard_link(from, to).is_err() {
        std::fs::copy(from, to).map_err(|e| SynthError::io(to, e))?;
    }
    Ok(())
}

/// Write campaign `name` with `profile`'s errors for `seed` into the empty or missing folder `out`, from the
/// error-free campaign folder `rendered` (its truth tables, images and control).
pub fn apply_profile_dir(
    rendered: &Path,
    profile: &Profile,
    seed: u64,
    name: &str,
    out: &Path,
) -> Result<(), SynthError> {
    let truth = read_truth(rendered)?;
    let (crs, frame) = read_crs(rendered)?;
    let applied = profile.apply(seed, &truth);
    for rel in relative_files(rendered)? {
        if !WRITTEN.contains(&rel.as_str()) {
            link_or_copy(&rendered.join(&rel), &out.join(&rel))?;
        }
    }
    let write = |rel: &str, f: &dyn Fn(&Path) -> std::io::Result<()>| {
        let path = out.join(rel);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| SynthError::io(dir, e))?;
        }
        f(&path).map_err(|e| SynthError::io(&path, e))
    };
    let t = &applied.tables;
    write("campaign.toml", &|p| {
        cw::write_campaign_toml(p, name, &crs, frame)
    })?;
    crate::synth::orthophoto::carry_tables(
        &rendered.join("campaign.toml"),
        &out.join("campaign.toml"),
    )?;
    write("mm/recordings.csv", &|p| {
        cw::write_recordings_csv(p, &t.recordings)
    })?;
    for (rel, rows, truth_rel, true_rows) in [
        (
            "aerial/nadir/cameras.csv",
            &t.nadir,
            "truth/aerial_nadir.csv",
            &truth.nadir,
        ),
        (
            "aerial/oblique/cameras.csv",
            &t.oblique,
            "truth/aerial_oblique.csv",
            &truth.oblique,
        ),
    ] {
        if rendered.join(rel).is_file() {
            write(rel, &|p| cw::write_aerial_cameras_csv(p, rows))?;
            if applied.aerial_changed {
                write(truth_rel, &|p| cw::write_aerial_cameras_csv(p, true_rows))?;
            }
        }
    }
    let text = readme(name, seed, profile, &applied);
    write("truth/README.md", &|p| {
        crate::fsutil::atomic_write(p, text.as_bytes())
    })?;
    Ok(())
}

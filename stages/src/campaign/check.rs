//! `skytie check`: everything [`read_campaign`](super::read_campaign) validates, plus what needs the image
//! files or the geometry: every image is decoded (in parallel, results in a fixed order), panoramas must be
//! 2:1, aerial images must have the size their row states, observations must lie inside their panorama,
//! and every aerial image should see at least one recording position.

use super::model::Campaign;
use super::problem::{Problem, Severity};
use super::read::{
    read_sourced, sort_problems, CampaignError, NADIR, OBLIQUE, OBSERVATIONS, PANORAMAS, RECORDINGS,
};
use crate::geometry::FrameCamera;
use crate::imaging::io::load_gray;
use nalgebra::Vector3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Outcome of [`check_campaign`]: all problems (grouped by file, rows ascending) and the usable item counts.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CheckReport {
    pub problems: Vec<Problem>,
    pub recordings: usize,
    pub nadir: usize,
    pub oblique: usize,
    pub checkpoints: usize,
    pub observations: usize,
}

impl CheckReport {
    /// No errors and no warnings.
    pub fn is_clean(&self) -> bool {
        self.problems.is_empty()
    }

    pub fn error_count(&self) -> usize {
        self.problems
            .iter()
            .filter(|p| p.severity == Severity::Error)
            .count()
    }

    pub fn warning_count(&self) -> usize {
        self.problems
            .iter()
            .filter(|p| p.severity == Severity::Warning)
            .count()
    }

    /// Human-readable report: problems grouped by file, then a summary line.
    pub fn render(&self) -> String {
        let mut out = String::new();
        let mut current: Option<&Path> = None;
        for p in &self.problems {
            if current != Some(p.file.as_path()) {
                current = Some(p.file.as_path());
                let in_file = self.problems.iter().filter(|q| q.file == p.file);
                let (e, w) =
                    in_file.fold(
                        (0, 0),
                        |(e, w), q| if q.is_error() { (e + 1, w) } else { (e, w + 1) },
                    );
                out.push_str(&format!(
                    "{} ({})\n",
                    p.file.to_string_lossy().replace('\\', "/"),
                    counts(e, w)
                ));
            }
            out.push_str(&format!("  {p}\n"));
        }
        let verdict = if self.is_clean() {
            "clean".to_string()
        } else {
            counts(self.error_count(), self.warning_count())
        };
        out.push_str(&format!(
            "{verdict}: {} recordings, {} nadir and {} oblique images, {} check points, {} observations usable\n",
            self.recordings, self.nadir, self.oblique, self.checkpoints, self.observations
        ));
        out
    }
}

fn counts(errors: usize, warnings: usize) -> String {
    let plural = |n: usize, word: &str| format!("{n} {word}{}", if n == 1 { "" } else { "s" });
    format!(
        "{}, {}",
        plural(errors, "error"),
        plural(warnings, "warning")
    )
}

/// One image file to decode, and what its row says about it.
struct ImageJob {
    csv: &'static str,
    row: usize,
    /// Relative to the campaign root (for messages).
    rel_path: PathBuf,
    expected_size_px: Option<(u32, u32)>,
}

/// Check the campaign in `root` completely (reads every image; never panics on user data).
pub fn check_campaign(root: &Path) -> CheckReport {
    let (sourced, mut problems) = match read_sourced(root) {
        Ok(r) => r,
        Err(e) => {
            let (message, hint) = match &e {
                CampaignError::NotACampaign(_) => (
                    "is not a campaign folder: neither campaign.toml nor mm/recordings.csv exists"
                        .to_string(),
                    "point skytie at the folder that holds campaign.toml and mm/",
                ),
                CampaignError::Unreadable { source, .. } => (
                    format!("cannot be read ({source})"),
                    "check that the folder exists and is readable",
                ),
            };
            return CheckReport {
                problems: vec![Problem::error(root, None, None, message, hint)],
                recordings: 0,
                nadir: 0,
                oblique: 0,
                checkpoints: 0,
                observations: 0,
            };
        }
    };
    let c = &sourced.campaign;
    let mut jobs = Vec::with_capacity(c.recordings.len() + c.nadir.len() + c.oblique.len());
    for (r, &row) in c.recordings.iter().zip(&sourced.recording_rows) {
        jobs.push(ImageJob {
            csv: RECORDINGS,
            row,
            rel_path: Path::new(PANORAMAS).join(&r.file),
            expected_size_px: None,
        });
    }
    for (csv, images, rows) in [
        (NADIR, &c.nadir, &sourced.nadir_rows),
        (OBLIQUE, &c.oblique, &sourced.oblique_rows),
    ] {
        let dir = Path::new(csv).parent().unwrap_or(Path::new(""));
        for (a, &row) in images.iter().zip(rows) {
            let expected = Some((a.width_px, a.height_px));
            jobs.push(ImageJob {
                csv,
                row,
                rel_path: dir.join(&a.file),
                expected_size_px: expected,
            });
        }
    }
    let results: Vec<(Option<(u32, u32)>, Option<Problem>)> = jobs
        .par_iter()
        .map(|job| inspect_image(root, job))
        .collect();
    let mut panorama_size_px: HashMap<&str, (u32, u32)> = HashMap::new();
    for (i, (size, problem)) in results.into_iter().enumerate() {
        problems.extend(problem);
        if let (Some(r), Some(size)) = (c.recordings.get(i), size) {
            panorama_size_px.insert(r.image_id.as_str(), size);
        }
    }
    check_observation_bounds(
        c,
        &sourced.observation_rows,
        &panorama_size_px,
        &mut problems,
    );
    check_aerial_coverage(c, &sourced.nadir_rows, &sourced.oblique_rows, &mut problems);
    sort_problems(&mut problems);
    CheckReport {
        problems,
        recordings: c.recordings.len(),
        nadir: c.nadir.len(),
        oblique: c.oblique.len(),
        checkpoints: c.checkpoints.len(),
        observations: c.observations.len(),
    }
}

/// Decode one image; its size if it decodes, and the problem with it if any.
fn inspect_image(root: &Path, job: &ImageJob) -> (Option<(u32, u32)>, Option<Problem>) {
    let shown = job.rel_path.to_string_lossy().replace('\\', "/");
    let problem = |message: String, hint: &str| {
        Some(Problem::error(
            job.csv,
            Some(job.row),
            Some("file"),
            message,
            hint,
        ))
    };
    let image = match load_gray(&root.join(&job.rel_path)) {
        Ok(img) => img,
        Err(e) => {
            let message = format!("{shown} {}", e.message);
            return (
                None,
                problem(message, "replace it with a complete JPEG, PNG or TIFF file"),
            );
        }
    };
    let (w, h) = (image.width as u32, image.height as u32);
    let issue = match job.expected_size_px {
        None if w != 2 * h => problem(
            format!("{shown} is {w}×{h} px, not 2:1 (equirectangular panoramas have width = 2 × height)"),
            "export the full 360°×180° equirectangular panorama",
        ),
        Some((ew, eh)) if (ew, eh) != (w, h) => problem(
            format!("{shown} is {w}×{h} px but its row says width {ew}, height {eh}"),
            "correct the width/height columns (and the interior orientation) or use the original image",
        ),
        _ => None,
    };
    (Some((w, h)), issue)
}

/// u ∈ [0, W), v ∈ [0, H] for observations in panoramas whose size is known.
fn check_observation_bounds(
    c: &Campaign,
    rows: &[usize],
    panorama_size_px: &HashMap<&str, (u32, u32)>,
    problems: &mut Vec<Problem>,
) {
    for (o, &row) in c.observations.iter().zip(rows) {
        let Some(&(w, h)) = panorama_size_px.get(o.image_id.as_str()) else {
            continue;
        };
        let (w, h) = (f64::from(w), f64::from(h));
        if o.u_px >= w {
            let message = format!(
                "{} px lies outside panorama '{}' (u must be < {w})",
                o.u_px, o.image_id
            );
            problems.push(Problem::error(
                OBSERVATIONS,
                Some(row),
                Some("u"),
                message,
                "measure u in continuous pixel coordinates of that panorama",
            ));
        }
        if o.v_px > h {
            let message = format!(
                "{} px lies outside panorama '{}' (v must be ≤ {h})",
                o.v_px, o.image_id
            );
            problems.push(Problem::error(
                OBSERVATIONS,
                Some(row),
                Some("v"),
                message,
                "measure v in continuous pixel coordinates of that panorama",
            ));
        }
    }
}

/// Warn about aerial images in which no recording position projects inside the image.
fn check_aerial_coverage(
    c: &Campaign,
    nadir_rows: &[usize],
    oblique_rows: &[usize],
    problems: &mut Vec<Problem>,
) {
    if c.recordings.is_empty() {
        return;
    }
    let positions: Vec<Vector3<f64>> = c
        .recordings
        .iter()
        .map(|r| Vector3::new(r.x, r.y, r.z))
        .collect();
    for (csv, images, rows) in [
        (NADIR, &c.nadir, nadir_rows),
        (OBLIQUE, &c.oblique, oblique_rows),
    ] {
        for (a, &row) in images.iter().zip(rows) {
            let camera = FrameCamera::from_aerial(a);
            let sees_any = positions.iter().any(|p| {
                camera
                    .project_world(p)
                    .is_some_and(|(u, v)| camera.contains(u, v))
            });
            if !sees_any {
                problems.push(Problem::warning(
                    csv,
                    Some(row),
                    Some("image_id"),
                    format!(
                        "'{}' sees none of the {} recording positions",
                        a.image_id,
                        positions.len()
                    ),
                    "check its x, y, z and ω-φ-κ (degrees), or leave the image out",
                ));
            }
        }
    }
}

//! The image part of the one validation `skytie check` and `skytie run` share: every image a row names is
//! probed by content ([`crate::imaging::probe`]: format, size, structural scan for truncation), and the row is
//! rejected when the file is not a usable image, a panorama is not 2:1, or an aerial image does not have the
//! size its row states. Observations in rejected or too-small panoramas are rejected with them.
//!
//! Who probes is the caller's business (`check` in parallel, the run as cached per-image nodes); this module
//! turns the outcomes into problems and the usable campaign.

use super::model::Campaign;
use super::problem::{Problem, ProblemKind};
use super::read::{SourcedCampaign, NADIR, OBLIQUE, OBSERVATIONS, PANORAMAS, RECORDINGS};
use crate::geometry::FrameCamera;
use crate::imaging::probe::{ImageHeader, ProbeError};
use nalgebra::Vector3;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// What a row says an image must be.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ImageRole {
    /// Equirectangular panorama: width = 2 × height.
    Panorama,
    /// Aerial frame of the stated size.
    Aerial { width: u32, height: u32 },
}

/// One image file to probe, and the row naming it.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ImageJob {
    /// The CSV naming the image (relative to the campaign root).
    pub csv: String,
    pub row: usize,
    /// Relative to the campaign root.
    pub rel_path: PathBuf,
    pub role: ImageRole,
}

/// The result of probing one image.
pub type ProbeOutcome = Result<ImageHeader, ProbeError>;

/// The images of every usable row, in a fixed order: recordings, nadir, oblique (each in campaign order).
pub fn image_jobs(s: &SourcedCampaign) -> Vec<ImageJob> {
    let c = &s.campaign;
    let mut jobs = Vec::with_capacity(c.recordings.len() + c.nadir.len() + c.oblique.len());
    for (r, &row) in c.recordings.iter().zip(&s.rows.recordings) {
        jobs.push(ImageJob {
            csv: RECORDINGS.into(),
            row,
            rel_path: Path::new(PANORAMAS).join(&r.file),
            role: ImageRole::Panorama,
        });
    }
    for (csv, images, rows) in [
        (NADIR, &c.nadir, &s.rows.nadir),
        (OBLIQUE, &c.oblique, &s.rows.oblique),
    ] {
        let dir = Path::new(csv).parent().unwrap_or(Path::new(""));
        for (a, &row) in images.iter().zip(rows) {
            jobs.push(ImageJob {
                csv: csv.into(),
                row,
                rel_path: dir.join(&a.file),
                role: ImageRole::Aerial {
                    width: a.width_px,
                    height: a.height_px,
                },
            });
        }
    }
    jobs
}

/// The problems of one probed image: an error when it is unusable, a warning when its name's extension says
/// another format than its content (it is read as what it is).
pub fn image_problems(job: &ImageJob, outcome: &ProbeOutcome) -> Vec<Problem> {
    let shown = job.rel_path.to_string_lossy().replace('\\', "/");
    let error = |kind: ProblemKind, message: String, hint: &str| {
        Problem::error(job.csv.as_str(), Some(job.row), Some("file"), message, hint).with_kind(kind)
    };
    let h = match outcome {
        Ok(h) => h,
        Err(e) => {
            let kind = match e {
                ProbeError::Unreadable(_) => ProblemKind::ImageMissing,
                ProbeError::UnknownFormat(_) | ProbeError::Unsupported { .. } => {
                    ProblemKind::ImageFormat
                }
                ProbeError::AbsurdSize { .. } => ProblemKind::ImageSize,
                ProbeError::Empty | ProbeError::Truncated { .. } | ProbeError::Corrupt { .. } => {
                    ProblemKind::ImageDamaged
                }
                ProbeError::Undecodable { .. } => ProblemKind::ImageDecode,
            };
            return vec![error(kind, format!("{shown} {e}"), e.hint())];
        }
    };
    let (w, h_px) = (h.width, h.height);
    let mut out = Vec::new();
    match job.role {
        ImageRole::Panorama if u64::from(w) != 2 * u64::from(h_px) => out.push(error(
            ProblemKind::ImageSize,
            format!("{shown} is {w}×{h_px} px, not 2:1 (equirectangular panoramas have width = 2 × height)"),
            "export the full 360°×180° equirectangular panorama",
        )),
        ImageRole::Aerial { width, height } if (width, height) != (w, h_px) => out.push(error(
            ProblemKind::ImageSize,
            format!("{shown} is {w}×{h_px} px but its row says width {width}, height {height}"),
            "correct the width/height columns (and the interior orientation) or use the original image",
        )),
        _ => {}
    }
    if !h.format.matches_extension(&job.rel_path) {
        out.push(
            Problem::warning(
                job.csv.as_str(),
                Some(job.row),
                Some("file"),
                format!(
                    "{shown} is a {} file although its name says otherwise; it is read as {}",
                    h.format, h.format
                ),
                format!(
                    "rename it to the extension of a {} file to avoid confusion",
                    h.format
                ),
            )
            .with_kind(ProblemKind::ImageFormat),
        );
    }
    out
}

/// Apply the probe `outcomes` (parallel to `jobs`) to the campaign: rows with an unusable image are removed,
/// then observations outside their panorama or in a removed one, and aerial images that see no recording
/// are warned about. Problems are appended to `problems`.
pub fn apply_image_checks(
    mut s: SourcedCampaign,
    jobs: &[ImageJob],
    outcomes: &[ProbeOutcome],
    problems: &mut Vec<Problem>,
) -> SourcedCampaign {
    let mut rejected: HashSet<(&str, usize)> = HashSet::new();
    let mut panorama_px: HashMap<usize, (u32, u32)> = HashMap::new();
    for (job, outcome) in jobs.iter().zip(outcomes) {
        let found = image_problems(job, outcome);
        if found.iter().any(Problem::is_error) {
            rejected.insert((job.csv.as_str(), job.row));
        } else if let (ImageRole::Panorama, Ok(h)) = (job.role, outcome) {
            panorama_px.insert(job.row, (h.width, h.height));
        }
        problems.extend(found);
    }
    let c = &mut s.campaign;
    let removed_panoramas: HashMap<String, usize> = c
        .recordings
        .iter()
        .zip(&s.rows.recordings)
        .filter(|(_, &row)| rejected.contains(&(RECORDINGS, row)))
        .map(|(r, &row)| (r.image_id.clone(), row))
        .collect();
    retain_rows(&mut c.recordings, &mut s.rows.recordings, |_, row| {
        !rejected.contains(&(RECORDINGS, row))
    });
    retain_rows(&mut c.nadir, &mut s.rows.nadir, |_, row| {
        !rejected.contains(&(NADIR, row))
    });
    retain_rows(&mut c.oblique, &mut s.rows.oblique, |_, row| {
        !rejected.contains(&(OBLIQUE, row))
    });
    let size_of: HashMap<&str, (u32, u32)> = c
        .recordings
        .iter()
        .zip(&s.rows.recordings)
        .filter_map(|(r, row)| panorama_px.get(row).map(|&px| (r.image_id.as_str(), px)))
        .collect();
    let bad = observation_problems(c, &s.rows.observations, &size_of, &removed_panoramas);
    let bad_rows: HashSet<usize> = bad.iter().filter_map(|p| p.row).collect();
    problems.extend(bad);
    retain_rows(&mut c.observations, &mut s.rows.observations, |_, row| {
        !bad_rows.contains(&row)
    });
    aerial_coverage(&s, problems);
    s
}

/// Keep the items (and their rows) for which `keep(item, row)` holds.
fn retain_rows<T>(items: &mut Vec<T>, rows: &mut Vec<usize>, keep: impl Fn(&T, usize) -> bool) {
    let kept: Vec<(T, usize)> = std::mem::take(items)
        .into_iter()
        .zip(std::mem::take(rows))
        .filter(|(t, r)| keep(t, *r))
        .collect();
    (*items, *rows) = kept.into_iter().unzip();
}

/// u ∈ [0, W), v ∈ [0, H] for observations in panoramas of known size; observations in removed panoramas.
fn observation_problems(
    c: &Campaign,
    rows: &[usize],
    size_of: &HashMap<&str, (u32, u32)>,
    removed: &HashMap<String, usize>,
) -> Vec<Problem> {
    let mut out = Vec::new();
    for (o, &row) in c.observations.iter().zip(rows) {
        if let Some(pano_row) = removed.get(&o.image_id) {
            out.push(
                Problem::error(
                    OBSERVATIONS,
                    Some(row),
                    Some("image_id"),
                    format!("panorama '{}' is not usable (its image on mm/recordings.csv:{pano_row} is rejected)", o.image_id),
                    "fix the panorama's image; this observation is used again then",
                )
                .with_kind(ProblemKind::Reference),
            );
            continue;
        }
        let Some(&(w, h)) = size_of.get(o.image_id.as_str()) else {
            continue;
        };
        let (w, h) = (f64::from(w), f64::from(h));
        for (field, value, ok, bound) in [
            ("u", o.u_px, o.u_px < w, format!("u must be < {w}")),
            ("v", o.v_px, o.v_px <= h, format!("v must be ≤ {h}")),
        ] {
            if !ok {
                out.push(Problem::error(
                    OBSERVATIONS,
                    Some(row),
                    Some(field),
                    format!(
                        "{value} px lies outside panorama '{}' ({bound})",
                        o.image_id
                    ),
                    format!("measure {field} in continuous pixel coordinates of that panorama"),
                ));
            }
        }
    }
    out
}

/// Warn about aerial images in which no recording position projects inside the image.
fn aerial_coverage(s: &SourcedCampaign, problems: &mut Vec<Problem>) {
    let c = &s.campaign;
    if c.recordings.is_empty() {
        return;
    }
    let positions: Vec<Vector3<f64>> = c
        .recordings
        .iter()
        .map(|r| Vector3::new(r.x, r.y, r.z))
        .collect();
    for (csv, images, rows) in [
        (NADIR, &c.nadir, &s.rows.nadir),
        (OBLIQUE, &c.oblique, &s.rows.oblique),
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

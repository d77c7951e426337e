//! Running an import: every source converted, images linked (or copied) into the campaign layout, the
//! campaign files and `import_report.txt` written into a partial folder that is renamed into place only
//! when complete, so an interrupted import never leaves a half campaign behind.

use super::aerial::import_aerial;
use super::config::{AerialKindName, CampaignSection, ImportConfig, MmSource, TrajectoryFormat};
use super::context::ImportContext;
use super::control::import_control;
use super::mm::import_mm;
use super::panorama_tags::import_panorama_tags;
use super::report::ImportReport;
use crate::campaign::source::{
    write_campaign_toml_with_source, ProvenanceFormat, SourceSection, TrajectoryProvenance,
};
use crate::campaign::{self as cw, AerialImage, Problem};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// An import that produced no campaign.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{0}")]
    Config(Problem),
    #[error("{}: already exists and is not empty — choose a new output folder (an import never overwrites a campaign)", .0.display())]
    OutputExists(PathBuf),
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> ImportError + '_ {
    move |source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Import `config` into the new campaign folder `out`.
pub fn run_import(config: &ImportConfig, out: &Path) -> Result<ImportReport, ImportError> {
    if out.exists() && std::fs::read_dir(out).map_err(io(out))?.next().is_some() {
        return Err(ImportError::OutputExists(out.to_path_buf()));
    }
    let ctx = ImportContext::new(&config.campaign).map_err(ImportError::Config)?;
    if config.mm.is_some() && config.panorama_tags.is_some() {
        return Err(ImportError::Config(Problem::error(
            "import configuration",
            None,
            Some("panorama_tags"),
            "both [mm] and [panorama_tags] are given",
            "take the panorama poses from a trajectory ([mm]) or from the images' tags ([panorama_tags]), not both",
        )));
    }
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let partial = out.with_file_name(format!(".{name}.partial"));
    if partial.exists() {
        std::fs::remove_dir_all(&partial).map_err(io(&partial))?;
    }
    let mut report = ImportReport::default();
    let mut ids: HashSet<String> = HashSet::new();
    for (kind, folder) in [
        (AerialKindName::Nadir, "aerial/nadir"),
        (AerialKindName::Oblique, "aerial/oblique"),
    ] {
        let mut rows: Vec<AerialImage> = Vec::new();
        let mut any = false;
        for src in config.aerial.iter().filter(|a| a.kind == kind) {
            any = true;
            let (new_rows, mut r) = import_aerial(src, &ctx);
            let dir = partial.join(folder);
            std::fs::create_dir_all(&dir).map_err(io(&dir))?;
            for row in new_rows {
                if !ids.insert(row.image_id.clone()) {
                    r.problems.push(Problem::error(
                        &src.orientations,
                        None,
                        Some("image"),
                        format!("image id '{}' was already imported; skipped", row.image_id),
                        "give every image a unique file name",
                    ));
                    r.converted -= 1;
                    continue;
                }
                link_or_copy(&src.images.join(&row.file), &dir.join(&row.file))?;
                rows.push(row);
            }
            report.sources.push(r);
        }
        if any {
            let path = partial.join(folder).join("cameras.csv");
            cw::write_aerial_cameras_csv(&path, &rows).map_err(io(&path))?;
        }
    }
    let mut panorama_ids = HashSet::new();
    if let Some(tags) = &config.panorama_tags {
        let (recordings, r) = import_panorama_tags(tags, &ctx);
        let dir = partial.join("mm/panoramas");
        for rec in &recordings {
            panorama_ids.insert(rec.image_id.clone());
            link_or_copy(&tags.panoramas.join(&rec.file), &dir.join(&rec.file))?;
        }
        let path = partial.join("mm/recordings.csv");
        cw::write_recordings_csv(&path, &recordings).map_err(io(&path))?;
        report.sources.push(r);
    }
    if let Some(mm) = &config.mm {
        let (mut recordings, mut r) = import_mm(mm, &ctx);
        let dir = partial.join("mm/panoramas");
        std::fs::create_dir_all(&dir).map_err(io(&dir))?;
        recordings.retain(|rec| {
            let fresh = panorama_ids.insert(rec.image_id.clone());
            if !fresh {
                r.problems.push(Problem::error(
                    &mm.events,
                    None,
                    Some("image"),
                    format!(
                        "panorama '{}' has more than one event; later ones skipped",
                        rec.image_id
                    ),
                    "give each panorama one event",
                ));
            }
            fresh
        });
        r.converted = recordings.len();
        for rec in &recordings {
            link_or_copy(&mm.panoramas.join(&rec.file), &dir.join(&rec.file))?;
        }
        recordings.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        let path = partial.join("mm/recordings.csv");
        cw::write_recordings_csv(&path, &recordings).map_err(io(&path))?;
        report.sources.push(r);
    }
    let source = match &config.mm {
        // A trajectory the import could not read (reported above) is not recorded.
        Some(mm)
            if mm.format == TrajectoryFormat::Sbet
                && mm.gps_week.is_some()
                && mm.trajectory.is_file() =>
        {
            SourceSection {
                trajectory: Some(keep_sbet(mm, &config.campaign, &partial)?),
            }
        }
        _ => SourceSection::default(),
    };
    if let Some(control) = &config.control {
        let (points, observations, reports) = import_control(control, &ctx, &panorama_ids);
        let dir = partial.join("control");
        std::fs::create_dir_all(&dir).map_err(io(&dir))?;
        let path = dir.join("checkpoints.csv");
        cw::write_checkpoints_csv(&path, &points).map_err(io(&path))?;
        if control.measurements.is_some() {
            let path = dir.join("observations.csv");
            cw::write_observations_csv(&path, &observations).map_err(io(&path))?;
        }
        report.sources.extend(reports);
    }
    let toml = partial.join("campaign.toml");
    let c = &config.campaign;
    write_campaign_toml_with_source(&toml, &c.name, &c.crs, c.frame, &source).map_err(io(&toml))?;
    let text = report_text(&report, &ctx);
    let path = partial.join("import_report.txt");
    crate::fsutil::atomic_write(&path, text.as_bytes()).map_err(io(&path))?;
    if out.exists() {
        std::fs::remove_dir(out).map_err(io(out))?;
    }
    std::fs::rename(&partial, out).map_err(io(out))?;
    Ok(report)
}

fn report_text(report: &ImportReport, ctx: &ImportContext) -> String {
    let geoid = ctx
        .geoid
        .as_ref()
        .map_or("none".to_string(), |g| g.describe());
    format!(
        "skytie import report\ncampaign CRS: {} ({}); geoid model: {geoid}\n{report}skipped in total: {}\n",
        ctx.campaign_crs.text,
        ctx.campaign_crs.vertical,
        report.skipped()
    )
}

/// Hard-link `from` to `to` (same file system), else copy it.
fn link_or_copy(from: &Path, to: &Path) -> Result<(), ImportError> {
    if let Some(parent) = to.parent() {
        std::fs::create_dir_all(parent).map_err(io(parent))?;
    }
    if std::fs::hard_link(from, to).is_ok() {
        return Ok(());
    }
    std::fs::copy(from, to).map(|_| ()).map_err(io(from))
}

/// Copy (or link) the SBET and the geoid grid into `mm/trajectory/` of the campaign being assembled in
/// `partial` and describe them for `[source.trajectory]`, so a run can write the corrected trajectory back.
fn keep_sbet(
    mm: &MmSource,
    campaign: &CampaignSection,
    partial: &Path,
) -> Result<TrajectoryProvenance, ImportError> {
    let keep = |from: &Path| -> Result<PathBuf, ImportError> {
        let name = from.file_name().map_or_else(
            || std::ffi::OsString::from("trajectory"),
            |n| n.to_os_string(),
        );
        let rel = Path::new("mm/trajectory").join(name);
        link_or_copy(from, &partial.join(&rel))?;
        Ok(rel)
    };
    Ok(TrajectoryProvenance {
        format: ProvenanceFormat::Sbet,
        file: keep(&mm.trajectory)?,
        crs: mm.crs.clone(),
        heights: mm.heights.clone(),
        gps_week: mm.gps_week.unwrap_or_default(),
        leap_seconds: mm.leap_seconds,
        lever_arm_m: mm.lever_arm_m,
        boresight_deg: mm.boresight_deg,
        geoid_grid: campaign.geoid_grid.as_deref().map(keep).transpose()?,
        geoid_separation_m: campaign.geoid_separation_m,
    })
}

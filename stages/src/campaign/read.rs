//! Reading a whole campaign folder (campaign-format.md) with validation: every bad row is skipped with a
//! [`Problem`] naming file, row and field, the rest is returned. Images are not decoded (see `check`), only
//! their existence is checked.

use super::model::{AerialImage, Campaign, Recording};
use super::orthophoto::read_orthophoto_tables;
use super::plausibility::{check_checkpoints, check_trajectory, shared_images, ImageUse};
use super::problem::{Problem, ProblemKind};
use super::read_aerial::read_aerial_rows;
use super::read_control::{read_checkpoint_rows, read_observation_rows};
use super::read_recordings::{read_recording_rows, sort_by_time};
use super::unique::{keep_unique, Sourced};
use crate::crs::{CoordinateFrame, MapFrameSpec};
use crate::params::StageId;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId::new("load", "3");

/// The folder holds nothing usable as a campaign.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    #[error("{}: not a campaign folder (neither campaign.toml nor mm/recordings.csv exists) — point skytie at the folder that holds campaign.toml and mm/", .0.display())]
    NotACampaign(PathBuf),
    #[error("{}: cannot read the campaign folder ({source}) — check that it exists and is readable", path.display())]
    Unreadable {
        path: PathBuf,
        source: std::io::Error,
    },
}

pub(crate) const TOML: &str = "campaign.toml";
pub(crate) const RECORDINGS: &str = "mm/recordings.csv";
pub(crate) const PANORAMAS: &str = "mm/panoramas";
pub(crate) const NADIR: &str = "aerial/nadir/cameras.csv";
pub(crate) const OBLIQUE: &str = "aerial/oblique/cameras.csv";
pub(crate) const CHECKPOINTS: &str = "control/checkpoints.csv";
pub(crate) const OBSERVATIONS: &str = "control/observations.csv";

/// The 1-based row (editor line) each item of a [`Campaign`] came from, parallel to its vectors.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SourceRows {
    pub recordings: Vec<usize>,
    pub nadir: Vec<usize>,
    pub oblique: Vec<usize>,
    pub checkpoints: Vec<usize>,
    pub observations: Vec<usize>,
}

/// The campaign plus the row each item came from (for checks that report on rows later).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SourcedCampaign {
    pub campaign: Campaign,
    pub rows: SourceRows,
}

/// Read and validate the campaign in `root`. `Err` only when nothing usable exists; otherwise the valid rows
/// (recordings sorted by time) and every problem found, in file order.
pub fn read_campaign(root: &Path) -> Result<(Campaign, Vec<Problem>), CampaignError> {
    read_sourced(root).map(|(s, problems)| (s.campaign, problems))
}

/// [`read_campaign`] keeping each item's row: the first step of the one validation `skytie check` and the
/// run share (the images are checked by [`super::images`]).
pub fn read_sourced(root: &Path) -> Result<(SourcedCampaign, Vec<Problem>), CampaignError> {
    std::fs::read_dir(root).map_err(|source| CampaignError::Unreadable {
        path: root.to_path_buf(),
        source,
    })?;
    if !root.join(TOML).is_file() && !root.join(RECORDINGS).is_file() {
        return Err(CampaignError::NotACampaign(root.to_path_buf()));
    }
    let mut problems = Vec::new();
    let (name, crs, parsed) = read_toml(root, &mut problems);
    let frame = match &parsed {
        Some((_, table)) => read_frame(table, &mut problems),
        None => CoordinateFrame::default(),
    };
    if !crs.is_empty() {
        if let (_, Some(note)) = MapFrameSpec::for_campaign(frame, &crs, None) {
            problems.push(Problem::warning(
                TOML,
                None,
                Some("crs"),
                note,
                "name a projected CRS as EPSG:<code>, or declare frame = \"cartesian\"",
            ));
        }
    }
    let (orthophoto, dtm) = match &parsed {
        Some((text, table)) => read_orthophoto_tables(root, text, table, &crs, &mut problems),
        None => (None, None),
    };
    // `[source]` only matters for the corrected SBET of a run: a bad one is a warning.
    if let Err(p) = crate::campaign::source::read_source(root) {
        problems.push(p);
    }
    // `[outputs]` names a second CRS for the run's files: one that cannot be used is reported before any work.
    let outputs = crate::crs::OutputsSection::read(root)
        .and_then(|s| crate::crs::SecondCrs::new(&crs, &s, root).map(|_| ()));
    if let Err(message) = outputs {
        problems.push(Problem::error(
            TOML,
            None,
            Some("outputs"),
            message,
            "fix or remove the [outputs] table (docs/outputs.md, \"Outputs in a second CRS\"); the run writes \
             its files in the campaign CRS only",
        ));
    }

    let mut recordings = if root.join(RECORDINGS).is_file() {
        read_recording_rows(
            root,
            Path::new(RECORDINGS),
            Some(Path::new(PANORAMAS)),
            &mut problems,
        )
    } else {
        problems.push(
            Problem::error(
                RECORDINGS,
                None,
                None,
                "does not exist",
                "put one row per panorama into mm/recordings.csv",
            )
            .with_kind(ProblemKind::Missing),
        );
        Vec::new()
    };
    sort_by_time(&mut recordings);
    let recordings = check_trajectory(recordings, &mut problems);

    let mut aerial = Vec::new();
    for rel in [NADIR, OBLIQUE] {
        let folder = Path::new(rel).parent().unwrap_or(Path::new(""));
        if root.join(rel).is_file() {
            aerial.extend(
                read_aerial_rows(root, Path::new(rel), true, &mut problems)
                    .into_iter()
                    .map(|r| (rel, r)),
            );
        } else if root.join(folder).is_dir() {
            problems.push(
                Problem::error(
                    rel,
                    None,
                    None,
                    format!("does not exist although {}/ does", folder.display()),
                    "add cameras.csv describing the images, or remove the folder",
                )
                .with_kind(ProblemKind::Missing),
            );
        }
    }
    // Image ids must be unique across nadir and oblique (stages address aerial images by id).
    let aerial: Vec<Sourced<(&str, AerialImage)>> = aerial
        .into_iter()
        .map(|(rel, r)| Sourced {
            item: (rel, r.item),
            file: r.file,
            row: r.row,
        })
        .collect();
    let aerial = keep_unique(
        aerial,
        |(_, a)| a.image_id.clone(),
        "image_id",
        "give every aerial image its own image_id (nadir and oblique together)",
        &mut problems,
    );
    let (mut nadir, mut oblique) = (Vec::new(), Vec::new());
    for r in aerial {
        let (rel, item) = r.item;
        let target = if rel == NADIR {
            &mut nadir
        } else {
            &mut oblique
        };
        target.push(Sourced {
            item,
            file: r.file,
            row: r.row,
        });
    }
    let (recordings, nadir, oblique) =
        without_shared_images(root, recordings, nadir, oblique, &mut problems);
    let panorama_ids: HashSet<&str> = recordings
        .iter()
        .map(|r| r.item.image_id.as_str())
        .collect();
    for a in nadir.iter().chain(&oblique) {
        if panorama_ids.contains(a.item.image_id.as_str()) {
            problems.push(Problem::warning(
                &a.file,
                Some(a.row),
                Some("image_id"),
                format!(
                    "'{}' is also the id of a panorama in mm/recordings.csv",
                    a.item.image_id
                ),
                "give aerial images and panoramas distinct ids to keep reports unambiguous",
            ));
        }
    }

    let checkpoints = if root.join(CHECKPOINTS).is_file() {
        let points = read_checkpoint_rows(root, Path::new(CHECKPOINTS), &mut problems);
        check_checkpoints(&recordings, points, &mut problems)
    } else {
        Vec::new()
    };
    let observations = if root.join(OBSERVATIONS).is_file() {
        if root.join(CHECKPOINTS).is_file() {
            let points: HashSet<&str> = checkpoints
                .iter()
                .map(|c| c.item.point_id.as_str())
                .collect();
            read_observation_rows(
                root,
                Path::new(OBSERVATIONS),
                &points,
                &panorama_ids,
                &mut problems,
            )
        } else {
            problems.push(
                Problem::error(
                    CHECKPOINTS,
                    None,
                    None,
                    "does not exist, so control/observations.csv cannot be used",
                    "add the surveyed points to control/checkpoints.csv",
                )
                .with_kind(ProblemKind::Missing),
            );
            Vec::new()
        }
    } else {
        Vec::new()
    };

    fn split<T>(rows: Vec<Sourced<T>>) -> (Vec<T>, Vec<usize>) {
        rows.into_iter().map(|r| (r.item, r.row)).unzip()
    }
    let (recordings, recording_rows) = split(recordings);
    let (nadir, nadir_rows) = split(nadir);
    let (oblique, oblique_rows) = split(oblique);
    let (checkpoints, checkpoint_rows) = split(checkpoints);
    let (observations, observation_rows) = split(observations);
    let campaign = Campaign {
        root: root.to_path_buf(),
        name,
        crs,
        frame,
        recordings,
        nadir,
        oblique,
        checkpoints,
        observations,
        orthophoto,
        dtm,
    };
    sort_problems(&mut problems);
    let sourced = SourcedCampaign {
        campaign,
        rows: SourceRows {
            recordings: recording_rows,
            nadir: nadir_rows,
            oblique: oblique_rows,
            checkpoints: checkpoint_rows,
            observations: observation_rows,
        },
    };
    Ok((sourced, problems))
}

type Aerials = Vec<Sourced<AerialImage>>;

/// Drop every row whose image file is also another row's image (see `plausibility::shared_images`).
fn without_shared_images(
    root: &Path,
    recordings: Vec<Sourced<Recording>>,
    nadir: Aerials,
    oblique: Aerials,
    problems: &mut Vec<Problem>,
) -> (Vec<Sourced<Recording>>, Aerials, Aerials) {
    let mut uses: Vec<ImageUse> = recordings
        .iter()
        .map(|r| ImageUse {
            file: r.file.clone(),
            row: r.row,
            path: root.join(PANORAMAS).join(&r.item.file),
        })
        .collect();
    for (csv, rows) in [(NADIR, &nadir), (OBLIQUE, &oblique)] {
        let dir = root.join(Path::new(csv).parent().unwrap_or(Path::new("")));
        uses.extend(rows.iter().map(|r| ImageUse {
            file: r.file.clone(),
            row: r.row,
            path: dir.join(&r.item.file),
        }));
    }
    let shared: HashSet<(PathBuf, usize)> = shared_images(&uses, problems).into_iter().collect();
    let keep = |file: &Path, row: usize| !shared.contains(&(file.to_path_buf(), row));
    (
        recordings
            .into_iter()
            .filter(|r| keep(&r.file, r.row))
            .collect(),
        nadir.into_iter().filter(|r| keep(&r.file, r.row)).collect(),
        oblique
            .into_iter()
            .filter(|r| keep(&r.file, r.row))
            .collect(),
    )
}

/// Order problems by file (in reading order) and row, keeping the order of problems on the same row.
pub fn sort_problems(problems: &mut [Problem]) {
    const ORDER: [&str; 6] = [TOML, RECORDINGS, NADIR, OBLIQUE, CHECKPOINTS, OBSERVATIONS];
    problems.sort_by_key(|p| {
        let rank = ORDER
            .iter()
            .position(|f| p.file == Path::new(f))
            .unwrap_or(ORDER.len());
        (rank, p.row.unwrap_or(0))
    });
}

/// `frame` of `campaign.toml`: `"projected"` (the default) or `"cartesian"`; anything else is an error and the
/// default is used.
fn read_frame(table: &toml::Table, problems: &mut Vec<Problem>) -> CoordinateFrame {
    let hint = "write frame = \"projected\" (map coordinates of crs, the default) or frame = \"cartesian\"";
    match table.get("frame") {
        None => CoordinateFrame::default(),
        Some(toml::Value::String(s)) if s == "projected" => CoordinateFrame::Projected,
        Some(toml::Value::String(s)) if s == "cartesian" => CoordinateFrame::Cartesian,
        Some(other) => {
            problems.push(Problem::error(
                TOML,
                None,
                Some("frame"),
                format!("{other} is not a coordinate frame skytie knows"),
                hint,
            ));
            CoordinateFrame::default()
        }
    }
}

/// `name` and `crs` of `campaign.toml` (empty strings when missing, with a problem), and its text and table
/// when it parses.
fn read_toml(
    root: &Path,
    problems: &mut Vec<Problem>,
) -> (String, String, Option<(String, toml::Table)>) {
    const HINT: &str = "write campaign.toml with name = \"...\" and crs = \"EPSG:...\"";
    let text = match std::fs::read_to_string(root.join(TOML)) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            problems.push(
                Problem::error(TOML, None, None, "does not exist", HINT)
                    .with_kind(ProblemKind::Missing),
            );
            return (String::new(), String::new(), None);
        }
        Err(e) => {
            problems.push(Problem::error(
                TOML,
                None,
                None,
                format!("cannot be read ({e})"),
                "save it as UTF-8 text and make it readable",
            ));
            return (String::new(), String::new(), None);
        }
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let table: toml::Table = match toml::from_str(text) {
        Ok(t) => t,
        Err(e) => {
            let row = e.span().map(|s| {
                text.as_bytes()[..s.start.min(text.len())]
                    .iter()
                    .filter(|&&b| b == b'\n')
                    .count()
                    + 1
            });
            problems.push(Problem::error(
                TOML,
                row,
                None,
                format!("is not valid TOML ({})", e.message()),
                HINT,
            ));
            return (String::new(), String::new(), None);
        }
    };
    let mut key = |k: &str| -> String {
        match table.get(k) {
            Some(toml::Value::String(s)) if !s.trim().is_empty() => s.clone(),
            Some(toml::Value::String(_)) => {
                problems.push(Problem::error(TOML, None, Some(k), "is empty", HINT));
                String::new()
            }
            Some(other) => {
                problems.push(Problem::error(
                    TOML,
                    None,
                    Some(k),
                    format!("is of type {}, not a string", other.type_str()),
                    format!("write {k} = \"...\" (quoted)"),
                ));
                String::new()
            }
            None => {
                problems.push(Problem::error(
                    TOML,
                    None,
                    Some(k),
                    "required key is missing",
                    HINT,
                ));
                String::new()
            }
        }
    };
    let (name, crs) = (key("name"), key("crs"));
    (name, crs, Some((text.to_string(), table)))
}

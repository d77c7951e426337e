//! Reading a whole campaign folder (campaign-format.md) with validation: every bad row is skipped with a
//! [`Problem`] naming file, row and field, the rest is returned. Images are not decoded (see `check`), only
//! their existence is checked.

use super::model::{AerialImage, Campaign, Observation, Recording};
use super::problem::Problem;
use super::read_aerial::read_aerial_rows;
use super::read_control::{read_checkpoint_rows, read_observation_rows};
use super::read_recordings::{read_recording_rows, sort_by_time};
use super::unique::{keep_unique, Sourced};
use crate::params::StageId;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// The stage's identity in cache keys; bump the version whenever its output for the same inputs and parameters
/// changes.
pub const STAGE: StageId = StageId {
    name: "load",
    version: "1",
};

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

/// The campaign plus the row each item came from (for checks that report on rows later).
pub(crate) struct SourcedCampaign {
    pub campaign: Campaign,
    /// Parallel to `campaign.recordings`, `.nadir`, `.oblique`, `.observations`.
    pub recording_rows: Vec<usize>,
    pub nadir_rows: Vec<usize>,
    pub oblique_rows: Vec<usize>,
    pub observation_rows: Vec<usize>,
}

/// Read and validate the campaign in `root`. `Err` only when nothing usable exists; otherwise the valid rows
/// (recordings sorted by time) and every problem found, in file order.
pub fn read_campaign(root: &Path) -> Result<(Campaign, Vec<Problem>), CampaignError> {
    read_sourced(root).map(|(s, problems)| (s.campaign, problems))
}

pub(crate) fn read_sourced(root: &Path) -> Result<(SourcedCampaign, Vec<Problem>), CampaignError> {
    std::fs::read_dir(root).map_err(|source| CampaignError::Unreadable {
        path: root.to_path_buf(),
        source,
    })?;
    if !root.join(TOML).is_file() && !root.join(RECORDINGS).is_file() {
        return Err(CampaignError::NotACampaign(root.to_path_buf()));
    }
    let mut problems = Vec::new();
    let (name, crs) = read_toml(root, &mut problems);

    let mut recordings = if root.join(RECORDINGS).is_file() {
        read_recording_rows(
            root,
            Path::new(RECORDINGS),
            Some(Path::new(PANORAMAS)),
            &mut problems,
        )
    } else {
        problems.push(Problem::error(
            RECORDINGS,
            None,
            None,
            "does not exist",
            "put one row per panorama into mm/recordings.csv",
        ));
        Vec::new()
    };
    sort_by_time(&mut recordings);

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
            problems.push(Problem::error(
                rel,
                None,
                None,
                format!("does not exist although {}/ does", folder.display()),
                "add cameras.csv describing the images, or remove the folder",
            ));
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
        read_checkpoint_rows(root, Path::new(CHECKPOINTS), &mut problems)
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
            problems.push(Problem::error(
                CHECKPOINTS,
                None,
                None,
                "does not exist, so control/observations.csv cannot be used",
                "add the surveyed points to control/checkpoints.csv",
            ));
            Vec::new()
        }
    } else {
        Vec::new()
    };

    let split = |rows: Vec<Sourced<AerialImage>>| -> (Vec<AerialImage>, Vec<usize>) {
        rows.into_iter().map(|r| (r.item, r.row)).unzip()
    };
    let (recordings, recording_rows): (Vec<Recording>, Vec<usize>) =
        recordings.into_iter().map(|r| (r.item, r.row)).unzip();
    let (nadir, nadir_rows) = split(nadir);
    let (oblique, oblique_rows) = split(oblique);
    let (observations, observation_rows): (Vec<Observation>, Vec<usize>) =
        observations.into_iter().map(|r| (r.item, r.row)).unzip();
    let campaign = Campaign {
        root: root.to_path_buf(),
        name,
        crs,
        recordings,
        nadir,
        oblique,
        checkpoints: checkpoints.into_iter().map(|r| r.item).collect(),
        observations,
    };
    sort_problems(&mut problems);
    let sourced = SourcedCampaign {
        campaign,
        recording_rows,
        nadir_rows,
        oblique_rows,
        observation_rows,
    };
    Ok((sourced, problems))
}

/// Order problems by file (in reading order) and row, keeping the order of problems on the same row.
pub(crate) fn sort_problems(problems: &mut [Problem]) {
    const ORDER: [&str; 6] = [TOML, RECORDINGS, NADIR, OBLIQUE, CHECKPOINTS, OBSERVATIONS];
    problems.sort_by_key(|p| {
        let rank = ORDER
            .iter()
            .position(|f| p.file == Path::new(f))
            .unwrap_or(ORDER.len());
        (rank, p.row.unwrap_or(0))
    });
}

/// `name` and `crs` of `campaign.toml` (empty strings when missing, with a problem).
fn read_toml(root: &Path, problems: &mut Vec<Problem>) -> (String, String) {
    const HINT: &str = "write campaign.toml with name = \"...\" and crs = \"EPSG:...\"";
    let text = match std::fs::read_to_string(root.join(TOML)) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            problems.push(Problem::error(TOML, None, None, "does not exist", HINT));
            return (String::new(), String::new());
        }
        Err(e) => {
            problems.push(Problem::error(
                TOML,
                None,
                None,
                format!("cannot be read ({e})"),
                "save it as UTF-8 text and make it readable",
            ));
            return (String::new(), String::new());
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
            return (String::new(), String::new());
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
    (key("name"), key("crs"))
}

//! `skytie check`: the validation the run applies, at once for the whole campaign: the rows
//! ([`read_sourced`]: values, ranges, plausibility across rows), then every image probed by content in
//! parallel ([`super::images`]: format, size vs its row, structural scan for truncation — fast at any image
//! size, no pixel decoded), results in a fixed order. `--deep` also decodes every image in full.

use super::images::{apply_image_checks, image_jobs, ProbeOutcome};
use super::problem::{Problem, ProblemKind, Severity};
use super::read::{read_sourced, sort_problems, CampaignError};
use crate::imaging::io::load_gray;
use crate::imaging::probe::{probe, ImageHeader, ProbeError};
use rayon::prelude::*;
use std::path::Path;

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

/// Check the campaign in `root` completely, reading every image's header and structure (not its pixels);
/// never panics on user data.
pub fn check_campaign(root: &Path) -> CheckReport {
    check_campaign_with(root, false)
}

/// [`check_campaign`]; with `deep`, every image that passes the structural scan is also decoded in full.
pub fn check_campaign_with(root: &Path, deep: bool) -> CheckReport {
    let (sourced, mut problems) = match read_sourced(root) {
        Ok(r) => r,
        Err(e) => return not_a_campaign(root, &e),
    };
    let jobs = image_jobs(&sourced);
    let outcomes: Vec<ProbeOutcome> = jobs
        .par_iter()
        .map(|job| {
            let path = root.join(&job.rel_path);
            let header = probe(&path)?;
            if deep {
                decode_fully(&path, &header)?;
            }
            Ok(header)
        })
        .collect();
    let sourced = apply_image_checks(sourced, &jobs, &outcomes, &mut problems);
    sort_problems(&mut problems);
    let c = &sourced.campaign;
    CheckReport {
        problems,
        recordings: c.recordings.len(),
        nadir: c.nadir.len(),
        oblique: c.oblique.len(),
        checkpoints: c.checkpoints.len(),
        observations: c.observations.len(),
    }
}

/// Decode the whole image (`check --deep`): the decoder's complaint about the pixel data, if any.
pub fn decode_fully(path: &Path, header: &ImageHeader) -> Result<(), ProbeError> {
    load_gray(path)
        .map(drop)
        .map_err(|e| ProbeError::Undecodable {
            format: header.format,
            detail: e.message,
        })
}

fn not_a_campaign(root: &Path, e: &CampaignError) -> CheckReport {
    let (message, hint) = match e {
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
    CheckReport {
        problems: vec![
            Problem::error(root, None, None, message, hint).with_kind(ProblemKind::Missing)
        ],
        recordings: 0,
        nadir: 0,
        oblique: 0,
        checkpoints: 0,
        observations: 0,
    }
}

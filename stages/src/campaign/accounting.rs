//! Counting what validation dropped, for `metrics.json` (`campaign.input_errors_by_kind`,
//! `campaign.dropped_rows`) and the run's last line: every error makes its row unusable, so the rows dropped
//! per file are the distinct rows with an error; an error without a row concerns a whole file.

use super::problem::{Problem, Severity};
use std::collections::{BTreeMap, BTreeSet};

/// Counts of a campaign's input problems.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct InputAccount {
    pub errors: usize,
    pub warnings: usize,
    /// Errors per [`ProblemKind`](super::ProblemKind) name.
    pub errors_by_kind: BTreeMap<String, usize>,
    /// Per file (relative to the campaign root, `/`-separated): rows left out because of an error.
    pub dropped_rows: BTreeMap<String, usize>,
    /// Files with an error that is not tied to one row (the file, or part of it, could not be used).
    pub files_with_errors: Vec<String>,
}

impl InputAccount {
    pub fn of(problems: &[Problem]) -> Self {
        let mut a = InputAccount::default();
        let mut rows: BTreeSet<(String, usize)> = BTreeSet::new();
        let mut files: BTreeSet<String> = BTreeSet::new();
        for p in problems {
            if p.severity == Severity::Warning {
                a.warnings += 1;
                continue;
            }
            a.errors += 1;
            *a.errors_by_kind
                .entry(p.kind.name().to_string())
                .or_default() += 1;
            let file = p.file.to_string_lossy().replace('\\', "/");
            match p.row {
                Some(row) => {
                    rows.insert((file, row));
                }
                None => {
                    files.insert(file);
                }
            }
        }
        for (file, _) in rows {
            *a.dropped_rows.entry(file).or_default() += 1;
        }
        a.files_with_errors = files.into_iter().collect();
        a
    }

    /// Total rows dropped over all files.
    pub fn rows_dropped(&self) -> usize {
        self.dropped_rows.values().sum()
    }
}

//! What an import read, converted and skipped, per source file: counts, and every skipped row with file,
//! line, field and reason. Written next to the campaign as `import_report.txt` and printed by the CLI.

use crate::campaign::{Problem, Severity};
use std::fmt;
use std::path::PathBuf;

/// One source (an orientation file, a trajectory with its events, a point list).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SourceReport {
    /// What it is, e.g. `aerial nadir (pix4d)`.
    pub name: String,
    pub file: PathBuf,
    /// Rows/records read from the file.
    pub read: usize,
    /// Items written into the campaign.
    pub converted: usize,
    /// Problems; errors are skipped rows, warnings kept ones.
    pub problems: Vec<Problem>,
    /// How the data were converted (CRS, heights, conventions).
    pub notes: Vec<String>,
}

impl SourceReport {
    /// A report for `name` reading `file`.
    pub fn new(name: impl Into<String>, file: impl Into<PathBuf>) -> Self {
        Self {
            name: name.into(),
            file: file.into(),
            ..Self::default()
        }
    }

    /// Rows skipped (errors that belong to a row, plus whole-file errors).
    pub fn skipped(&self) -> usize {
        self.problems
            .iter()
            .filter(|p| p.severity == Severity::Error)
            .count()
    }
}

/// The whole import.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImportReport {
    pub sources: Vec<SourceReport>,
}

impl ImportReport {
    /// Total skipped items.
    pub fn skipped(&self) -> usize {
        self.sources.iter().map(SourceReport::skipped).sum()
    }
}

impl fmt::Display for ImportReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for s in &self.sources {
            writeln!(
                f,
                "{}: {} — read {}, converted {}, skipped {}",
                s.name,
                s.file.display(),
                s.read,
                s.converted,
                s.skipped()
            )?;
            for n in &s.notes {
                writeln!(f, "  note: {n}")?;
            }
            for p in &s.problems {
                writeln!(f, "  {p}")?;
            }
        }
        Ok(())
    }
}

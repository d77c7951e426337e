//! A problem found in a campaign: which file, row and field, what is wrong and what to do about it.
//!
//! Rows are 1-based line numbers in the file, comments and header included (what an editor shows).

use std::fmt;
use std::path::PathBuf;

/// Errors make the item unusable (it is skipped); warnings are suspicious but the item is kept.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum Severity {
    Error,
    Warning,
}

/// One finding, e.g. `mm/recordings.csv:14: field 'x': 'abc' is not a number — write a decimal number with
/// '.' as decimal mark`.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Problem {
    pub severity: Severity,
    /// Relative to the campaign root, e.g. `mm/recordings.csv`.
    pub file: PathBuf,
    /// 1-based line number in `file`, if the problem belongs to one line.
    pub row: Option<usize>,
    /// Column (CSV) or key (TOML) name, if the problem belongs to one field.
    pub field: Option<String>,
    /// What is wrong.
    pub message: String,
    /// What to do about it.
    pub hint: String,
}

impl Problem {
    /// An error in `file` (relative to the campaign root).
    pub fn error(
        file: impl Into<PathBuf>,
        row: Option<usize>,
        field: Option<&str>,
        message: impl Into<String>,
        hint: impl Into<String>,
    ) -> Self {
        Self::new(
            Severity::Error,
            file.into(),
            row,
            field,
            message.into(),
            hint.into(),
        )
    }

    /// A warning in `file` (relative to the campaign root).
    pub fn warning(
        file: impl Into<PathBuf>,
        row: Option<usize>,
        field: Option<&str>,
        message: impl Into<String>,
        hint: impl Into<String>,
    ) -> Self {
        Self::new(
            Severity::Warning,
            file.into(),
            row,
            field,
            message.into(),
            hint.into(),
        )
    }

    fn new(
        severity: Severity,
        file: PathBuf,
        row: Option<usize>,
        field: Option<&str>,
        message: String,
        hint: String,
    ) -> Self {
        Self {
            severity,
            file,
            row,
            field: field.map(str::to_string),
            message,
            hint,
        }
    }

    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Forward slashes on every platform: the campaign layout is written that way in the format.
        let file = self.file.to_string_lossy().replace('\\', "/");
        write!(f, "{file}")?;
        if let Some(row) = self.row {
            write!(f, ":{row}")?;
        }
        write!(f, ": ")?;
        if self.severity == Severity::Warning {
            write!(f, "warning: ")?;
        }
        if let Some(field) = &self.field {
            write!(f, "field '{field}': ")?;
        }
        write!(f, "{}", self.message)?;
        if !self.hint.is_empty() {
            write!(f, " — {}", self.hint)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_names_file_row_field_and_hint() {
        let p = Problem::error(
            "mm/recordings.csv",
            Some(14),
            Some("x"),
            "'abc' is not a number",
            "write a decimal number with '.' as decimal mark",
        );
        assert_eq!(
            p.to_string(),
            "mm/recordings.csv:14: field 'x': 'abc' is not a number — write a decimal number with '.' as decimal mark"
        );
        let w = Problem::warning("campaign.toml", None, None, "missing", "");
        assert_eq!(w.to_string(), "campaign.toml: warning: missing");
    }
}

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

/// What sort of problem it is (counted per kind in `metrics.json`, `campaign.input_errors_by_kind`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum ProblemKind {
    /// A required file or column is missing, or a file cannot be read.
    Missing,
    /// Not valid CSV/TOML/UTF-8, or a row with the wrong number of cells.
    Syntax,
    /// A cell that is empty, not a number, not finite or outside its defined range.
    #[default]
    Value,
    /// A value that is valid on its own but implausible (position jumps, far outside the campaign, absurd σ,
    /// focal length or size).
    Implausible,
    /// An id or image used by more than one row.
    Duplicate,
    /// An id that refers to nothing usable.
    Reference,
    /// A file path that leaves the campaign folder.
    Path,
    /// An image file that is missing.
    ImageMissing,
    /// An image that is not JPEG/PNG/TIFF, or of a kind the decoders do not read.
    ImageFormat,
    /// An image file that is cut off or structurally damaged.
    ImageDamaged,
    /// An image whose size is wrong (not 2:1, not what its row says, or absurd).
    ImageSize,
    /// An image that does not decode (`skytie check --deep` and the run).
    ImageDecode,
}

impl ProblemKind {
    /// The snake_case name used in metrics.
    pub fn name(self) -> &'static str {
        match self {
            ProblemKind::Missing => "missing",
            ProblemKind::Syntax => "syntax",
            ProblemKind::Value => "value",
            ProblemKind::Implausible => "implausible",
            ProblemKind::Duplicate => "duplicate",
            ProblemKind::Reference => "reference",
            ProblemKind::Path => "path",
            ProblemKind::ImageMissing => "image_missing",
            ProblemKind::ImageFormat => "image_format",
            ProblemKind::ImageDamaged => "image_damaged",
            ProblemKind::ImageSize => "image_size",
            ProblemKind::ImageDecode => "image_decode",
        }
    }
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
    /// What sort of problem (default: a bad value).
    #[serde(default)]
    pub kind: ProblemKind,
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
        Self {
            severity: Severity::Warning,
            ..Self::error(file, row, field, message, hint)
        }
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
            kind: ProblemKind::Value,
        }
    }

    /// The same problem, of sort `kind`.
    pub fn with_kind(mut self, kind: ProblemKind) -> Self {
        self.kind = kind;
        self
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

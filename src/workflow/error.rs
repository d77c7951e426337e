//! Errors of workflow files: every message carries the file, 1-based line and column of the offending key or
//! value, so editors and terminals can jump to it (`workflows/x.toml:12:5: unknown key ...`).

use std::fmt;
use std::path::PathBuf;

/// One problem in a workflow file (or in a file it includes).
///
/// `line` and `column` are 1-based (column counts characters, as editors do). `line == 0` means the problem has
/// no position inside the file (e.g. the file cannot be read); Display then prints `file: message`.
/// When several problems were found at once, the first is in the fields and the others follow in `message`,
/// one per line, each in the same `file:line:col: message` form.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WorkflowError {
    pub file: PathBuf,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

impl WorkflowError {
    /// An error at a position of a file.
    pub fn at(
        file: impl Into<PathBuf>,
        line: usize,
        column: usize,
        message: impl Into<String>,
    ) -> Self {
        WorkflowError {
            file: file.into(),
            line,
            column,
            message: message.into(),
        }
    }

    /// An error about a whole file (no position).
    pub fn in_file(file: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        WorkflowError {
            file: file.into(),
            line: 0,
            column: 0,
            message: message.into(),
        }
    }

    /// Joins several errors into one: the first one's position, the others appended as extra lines.
    pub(crate) fn combine(mut errors: Vec<WorkflowError>) -> Option<WorkflowError> {
        if errors.is_empty() {
            return None;
        }
        let rest = errors.split_off(1);
        let mut first = errors.pop()?;
        for e in rest {
            first.message.push('\n');
            first.message.push_str(&e.to_string());
        }
        Some(first)
    }
}

impl fmt::Display for WorkflowError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}: {}", self.file.display(), self.message)
        } else {
            write!(
                f,
                "{}:{}:{}: {}",
                self.file.display(),
                self.line,
                self.column,
                self.message
            )
        }
    }
}

impl std::error::Error for WorkflowError {}

/// A range-check failure reported by `StageParams::validate`.
///
/// `field` is the dotted path of the parameter inside the stage table (`"threshold"`, `"patch.extent_m"`);
/// `message` states the allowed range (`"must be in (0, 1]"`). The same type as the photogrammetry crate's
/// `Violation`, shared through `skytie_util` (the engine does not import that crate).
pub use skytie_util::violation::Violation as ParamError;

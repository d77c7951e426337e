//! Delimited text tables of other software (comma, semicolon, tab or blank separated; `#` comments; an
//! optional header) with the 1-based line number of every row, and columns addressed by header name or by
//! 1-based position, so that a user's column mapping can name either.

use crate::campaign::Problem;
use std::path::{Path, PathBuf};

/// How cells are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Delimiter {
    Comma,
    Semicolon,
    Tab,
    /// One or more spaces or tabs.
    Whitespace,
}

impl Delimiter {
    fn split<'a>(&self, line: &'a str) -> Vec<&'a str> {
        match self {
            Self::Comma => line.split(',').map(str::trim).collect(),
            Self::Semicolon => line.split(';').map(str::trim).collect(),
            Self::Tab => line.split('\t').map(str::trim).collect(),
            Self::Whitespace => line.split_whitespace().collect(),
        }
    }
}

/// A text table in memory.
#[derive(Debug, Clone)]
pub struct TextTable {
    /// The file as the user named it (for messages).
    pub file: PathBuf,
    /// Header cells, lower-cased (empty when the table has no header).
    pub header: Vec<String>,
    /// Data rows: 1-based line number and cells.
    pub rows: Vec<(usize, Vec<String>)>,
}

impl TextTable {
    /// Read `path`; with `has_header` the first non-comment line is the header. Lines starting with `#`
    /// (after blanks) and blank lines are skipped; `comment_header` also takes the header from the last
    /// comment line before the data when the table has no plain header (Metashape writes it so).
    pub fn read(
        path: &Path,
        delimiter: Delimiter,
        has_header: bool,
        comment_header: bool,
    ) -> Result<Self, Problem> {
        let bytes = std::fs::read(path).map_err(|e| super::unreadable(path, &e))?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let line = 1 + e.as_bytes()[..e.utf8_error().valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            Problem::error(
                path,
                Some(line),
                None,
                "is not UTF-8 text",
                "save the file as UTF-8 (or ASCII) text",
            )
        })?;
        Ok(Self::parse(
            path,
            &text,
            delimiter,
            has_header,
            comment_header,
        ))
    }

    /// Parse text already in memory (see [`Self::read`]).
    pub fn parse(
        path: &Path,
        text: &str,
        delimiter: Delimiter,
        has_header: bool,
        comment_header: bool,
    ) -> Self {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut header = Vec::new();
        let mut last_comment: Option<String> = None;
        let mut rows = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let t = line.trim();
            if t.is_empty() {
                continue;
            }
            if let Some(c) = t.strip_prefix('#') {
                last_comment = Some(c.trim().to_string());
                continue;
            }
            if header.is_empty() && rows.is_empty() {
                if has_header {
                    header = lower(delimiter.split(t));
                    continue;
                }
                if comment_header {
                    if let Some(c) = &last_comment {
                        header = lower(delimiter.split(c));
                        // Metashape separates its commented header by ", " even in tab files.
                        if header.len() <= 1 {
                            header = lower(Delimiter::Comma.split(c));
                        }
                    }
                }
            }
            rows.push((
                i + 1,
                delimiter.split(t).into_iter().map(str::to_string).collect(),
            ));
        }
        Self {
            file: path.to_path_buf(),
            header,
            rows,
        }
    }

    /// The 0-based index of a column named by header name (case-insensitive) or by 1-based position
    /// (`"3"`); `Err` with a problem naming the column otherwise.
    pub fn column(&self, name: &str) -> Result<usize, Problem> {
        let key = name.trim().to_ascii_lowercase();
        if let Some(i) = self.header.iter().position(|h| *h == key) {
            return Ok(i);
        }
        if let Ok(n) = key.parse::<usize>() {
            if n >= 1 {
                return Ok(n - 1);
            }
        }
        let known = if self.header.is_empty() {
            "the file has no header: name columns by their 1-based position".to_string()
        } else {
            format!("the header has: {}", self.header.join(", "))
        };
        Err(Problem::error(
            &self.file,
            None,
            Some(name),
            format!("column '{name}' does not exist"),
            format!("fix the column mapping ({known})"),
        ))
    }
}

fn lower(cells: Vec<&str>) -> Vec<String> {
    cells.into_iter().map(|c| c.to_ascii_lowercase()).collect()
}

/// Typed access to one row's cells with problems naming file, line and field.
pub struct RowReader<'a> {
    pub file: &'a Path,
    pub line: usize,
    pub cells: &'a [String],
    pub problems: Vec<Problem>,
}

impl<'a> RowReader<'a> {
    /// A reader of one row.
    pub fn new(file: &'a Path, line: usize, cells: &'a [String]) -> Self {
        Self {
            file,
            line,
            cells,
            problems: Vec::new(),
        }
    }

    fn cell(&mut self, index: usize, field: &str) -> Option<&'a str> {
        let cells = self.cells;
        match cells.get(index) {
            Some(c) if !c.is_empty() => Some(c.as_str()),
            _ => {
                self.error(
                    field,
                    format!("is missing (the row has {} cells)", cells.len()),
                    "give every row all mapped columns",
                );
                None
            }
        }
    }

    /// The text of column `index`.
    pub fn text(&mut self, index: usize, field: &str) -> String {
        self.cell(index, field).unwrap_or_default().to_string()
    }

    /// A finite number in column `index` (NaN and infinities are errors).
    pub fn number(&mut self, index: usize, field: &str) -> f64 {
        let Some(c) = self.cell(index, field) else {
            return f64::NAN;
        };
        match c.parse::<f64>() {
            Ok(v) if v.is_finite() => v,
            _ => {
                self.error(
                    field,
                    format!("'{c}' is not a finite number"),
                    "write a decimal number with '.' as decimal mark",
                );
                f64::NAN
            }
        }
    }

    /// Record an error on `field`.
    pub fn error(&mut self, field: &str, message: impl Into<String>, hint: impl Into<String>) {
        self.problems.push(Problem::error(
            self.file,
            Some(self.line),
            Some(field),
            message,
            hint,
        ));
    }

    /// True when no cell had a problem.
    pub fn ok(&self) -> bool {
        self.problems.is_empty()
    }
}

//! Reading one campaign CSV table (campaign-format.md, "CSV files") with row numbers an editor shows.
//!
//! UTF-8 (a leading byte-order mark is tolerated), comma separated, LF or CRLF line ends, header row
//! required, columns in any order (names matched case-insensitively, surrounding spaces ignored), unknown
//! columns ignored, lines starting with `#` are comments anywhere (also before the header). "Row" is the
//! 1-based line number in the file, comments and header included. [`Fields`] parses one row's cells into
//! typed values, recording a [`Problem`] naming file, row and field for every bad cell (all of them, not
//! just the first), so a caller can skip the row and still report everything at once.

use super::problem::{Problem, ProblemKind, Severity};
use super::unique::Sourced;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A parsed table: header column positions and the data rows with their line numbers.
pub(crate) struct Table {
    /// Relative to the campaign root (for messages).
    pub file: PathBuf,
    columns: HashMap<String, usize>,
    pub records: Vec<Record>,
}

/// One data row.
pub(crate) struct Record {
    /// 1-based line number where the row starts.
    pub row: usize,
    pub fields: Vec<String>,
}

const NUMBER_HINT: &str = "write a decimal number with '.' as decimal mark";

/// Read `root/rel` as a table that must have the `required` columns. Returns `None` (with problems) when the
/// file cannot be read, has no header, or lacks required columns; rows whose cell count differs from the
/// header or that are not UTF-8 are reported and left out.
pub(crate) fn read_table(
    root: &Path,
    rel: &Path,
    required: &[&str],
    problems: &mut Vec<Problem>,
) -> Option<Table> {
    parse_table(root, rel, required, problems).unwrap_or_else(|fatal| {
        problems.push(fatal);
        None
    })
}

/// A problem of `rel` that is about no one field: of line `row`, or of the whole file.
fn line_problem(
    rel: &Path,
    row: Option<usize>,
    kind: ProblemKind,
    message: impl Into<String>,
    hint: impl Into<String>,
) -> Problem {
    Problem::error(rel, row, None, message, hint).with_kind(kind)
}

/// [`read_table`], with the problem that ends the reading (the file cannot be read, is not valid CSV or has
/// no header) as `Err`.
fn parse_table(
    root: &Path,
    rel: &Path,
    required: &[&str],
    problems: &mut Vec<Problem>,
) -> Result<Option<Table>, Problem> {
    let bytes = std::fs::read(root.join(rel)).map_err(|e| {
        line_problem(
            rel,
            None,
            ProblemKind::Missing,
            format!("cannot be read ({e})"),
            "check that the file exists and is readable",
        )
    })?;
    let body = bytes
        .strip_prefix(b"\xEF\xBB\xBF".as_slice())
        .unwrap_or(&bytes);
    // The csv crate's line counter skips comment lines, so comments and blank lines are removed here and
    // each kept line remembers its line number in the file.
    let (data, kept_line_rows) = without_comment_lines(body);
    let newline_offsets: Vec<usize> = data
        .iter()
        .enumerate()
        .filter(|(_, &b)| b == b'\n')
        .map(|(i, _)| i)
        .collect();
    let row_at = |byte: u64| -> usize {
        // A record's position may lie before the line end of the previous record: skip line-end bytes.
        let mut start = byte as usize;
        while start < data.len() && matches!(data[start], b'\r' | b'\n') {
            start += 1;
        }
        let line_index = newline_offsets.partition_point(|&nl| nl < start);
        kept_line_rows.get(line_index).copied().unwrap_or(0)
    };
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(data.as_slice());
    let mut header: Option<(usize, Vec<String>)> = None;
    let mut records = Vec::new();
    let mut row_problems = Vec::new();
    let mut byte_record = csv::ByteRecord::new();
    loop {
        match reader.read_byte_record(&mut byte_record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                let row = e.position().map(|p| row_at(p.byte()));
                let message = format!("is not valid CSV ({e})");
                return Err(line_problem(
                    rel,
                    row,
                    ProblemKind::Syntax,
                    message,
                    "fix the quoting of this row",
                ));
            }
        }
        let row = byte_record.position().map_or(0, |p| row_at(p.byte()));
        let cells: Result<Vec<String>, _> = byte_record
            .iter()
            .map(|c| std::str::from_utf8(c).map(str::to_string))
            .collect();
        let Ok(cells) = cells else {
            let hint = "save the file as UTF-8";
            problems.push(line_problem(
                rel,
                Some(row),
                ProblemKind::Syntax,
                "is not valid UTF-8",
                hint,
            ));
            if header.is_none() {
                return Ok(None);
            }
            continue;
        };
        match &header {
            None => header = Some((row, cells)),
            Some((_, names)) => {
                if cells.len() != names.len() {
                    row_problems.push(line_problem(
                        rel,
                        Some(row),
                        ProblemKind::Syntax,
                        format!("has {} cells but the header has {} columns; row skipped", cells.len(), names.len()),
                        "give every row one cell per header column; quote values that contain commas",
                    ));
                    continue;
                }
                records.push(Record { row, fields: cells });
            }
        }
    }
    let Some((header_row, names)) = header else {
        let hint = format!(
            "write a header row with the columns {}",
            required.join(", ")
        );
        let message = "is empty (no header row)";
        return Err(line_problem(rel, None, ProblemKind::Syntax, message, hint));
    };
    let mut columns = HashMap::new();
    let mut usable = true;
    for (i, name) in names.iter().enumerate() {
        let key = name.to_ascii_lowercase();
        if let Some(first) = columns.insert(key.clone(), i) {
            if is_known(&key, required) {
                problems.push(
                    Problem::error(
                        rel,
                        Some(header_row),
                        Some(&key),
                        format!(
                            "column appears twice (columns {} and {}); file skipped",
                            first + 1,
                            i + 1
                        ),
                        "keep one column of each name",
                    )
                    .with_kind(ProblemKind::Duplicate),
                );
                usable = false;
            }
        }
    }
    for col in required {
        if !columns.contains_key(*col) {
            problems.push(Problem::error(
                rel,
                Some(header_row),
                Some(col),
                "required column is missing; file skipped",
                format!("add a '{col}' column to the header (row {header_row}) and a value to every row"),
            ).with_kind(ProblemKind::Missing));
            usable = false;
        }
    }
    // A skipped file's rows are not reported one by one: the header error covers them.
    if usable {
        problems.extend(row_problems);
    }
    Ok(usable.then(|| Table {
        file: rel.to_path_buf(),
        columns,
        records,
    }))
}

/// `body` without comment lines (first byte `#`) and blank lines, outside quoted cells; plus, for every
/// line kept, its 1-based line number in `body`.
fn without_comment_lines(body: &[u8]) -> (Vec<u8>, Vec<usize>) {
    let mut data = Vec::with_capacity(body.len());
    let mut rows = Vec::new();
    let mut in_quotes = false;
    for (index, line) in body.split_inclusive(|&b| b == b'\n').enumerate() {
        let blank = line.iter().all(|b| b.is_ascii_whitespace());
        if !in_quotes && (line.first() == Some(&b'#') || blank) {
            continue;
        }
        let quotes = line.iter().filter(|&&b| b == b'"').count();
        if quotes % 2 == 1 {
            in_quotes = !in_quotes;
        }
        data.extend_from_slice(line);
        rows.push(index + 1);
    }
    (data, rows)
}

fn is_known(key: &str, required: &[&str]) -> bool {
    required.contains(&key) || OPTIONAL_COLUMNS.contains(&key)
}

/// Optional columns of any campaign table: a duplicate of one of these is as ambiguous as of a required one.
const OPTIONAL_COLUMNS: &[&str] = &[
    "sigma_xy", "sigma_z", "yaw", "pitch", "roll", "k1", "k2", "p1", "p2", "sigma_px",
];

/// The rows of the table `root/rel` (which must have the `required` columns), each made by `row` from its
/// fields, in file order with their row numbers: a row is kept when `row` returns it and none of its fields had
/// an error. A missing or unreadable table gives no rows; every problem goes to `problems`.
pub(crate) fn read_rows<T>(
    root: &Path,
    rel: &Path,
    required: &[&str],
    problems: &mut Vec<Problem>,
    mut row: impl FnMut(&mut Fields<'_>) -> Option<T>,
) -> Vec<Sourced<T>> {
    let Some(table) = read_table(root, rel, required, problems) else {
        return Vec::new();
    };
    let mut rows = Vec::with_capacity(table.records.len());
    for record in &table.records {
        let mut f = table.fields(record, problems);
        let item = row(&mut f);
        if let (true, Some(item)) = (f.ok, item) {
            rows.push(Sourced {
                item,
                file: rel.to_path_buf(),
                row: record.row,
            });
        }
    }
    rows
}

impl Table {
    /// Typed access to one row; problems go to `problems`.
    pub fn fields<'a>(&'a self, record: &'a Record, problems: &'a mut Vec<Problem>) -> Fields<'a> {
        Fields {
            table: self,
            record,
            problems,
            ok: true,
        }
    }
}

/// Parses the cells of one row; every bad cell adds an error and clears `ok`.
pub(crate) struct Fields<'a> {
    table: &'a Table,
    record: &'a Record,
    problems: &'a mut Vec<Problem>,
    /// False once any cell of this row was rejected: the row must be skipped.
    pub ok: bool,
}

impl Fields<'_> {
    /// The cell of `column`, `None` if the table has no such column.
    pub fn raw(&self, column: &str) -> Option<&str> {
        self.table
            .columns
            .get(column)
            .map(|&i| self.record.fields[i].as_str())
    }

    /// The error `message` (with `hint`) in `column` of this row.
    fn problem_at(
        &self,
        column: &str,
        message: impl Into<String>,
        hint: impl Into<String>,
    ) -> Problem {
        let row = Some(self.record.row);
        Problem::error(&self.table.file, row, Some(column), message, hint)
    }

    /// Reject the row because of `column`.
    pub fn error(&mut self, column: &str, message: impl Into<String>, hint: impl Into<String>) {
        let problem = self.problem_at(column, message, hint);
        self.problems.push(problem);
        self.ok = false;
    }

    /// Reject the row because of `column`, with a problem of sort `kind`.
    pub fn error_of(
        &mut self,
        kind: ProblemKind,
        column: &str,
        message: impl Into<String>,
        hint: impl Into<String>,
    ) {
        self.error(column, message, hint);
        if let Some(p) = self.problems.last_mut() {
            p.kind = kind;
        }
    }

    /// Keep the row but report something suspicious in `column`.
    pub fn warning(&mut self, column: &str, message: impl Into<String>, hint: impl Into<String>) {
        let problem = self.problem_at(column, message, hint);
        self.problems.push(Problem {
            severity: Severity::Warning,
            ..problem
        });
    }

    /// A required non-empty text cell (ids, file names).
    pub fn text(&mut self, column: &str) -> String {
        match self.raw(column) {
            Some(s) if !s.is_empty() => s.to_string(),
            _ => {
                self.error(column, "is empty", format!("write a value for '{column}'"));
                String::new()
            }
        }
    }

    /// A required finite number; NaN (never a valid value, so later range checks stay silent) if rejected.
    pub fn number(&mut self, column: &str) -> f64 {
        match self.raw(column).map(str::to_string) {
            Some(s) if s.is_empty() => {
                self.error(column, "is empty", NUMBER_HINT);
                f64::NAN
            }
            Some(s) => self.parse_number(column, &s).unwrap_or(f64::NAN),
            None => {
                self.error(
                    column,
                    "required column is missing",
                    format!("add a '{column}' column"),
                );
                f64::NAN
            }
        }
    }

    /// An optional number: `None` when the column is absent or the cell empty, else it must be finite.
    pub fn optional_number(&mut self, column: &str) -> Option<f64> {
        match self.raw(column).map(str::to_string) {
            None => None,
            Some(s) if s.is_empty() => None,
            Some(s) => self.parse_number(column, &s),
        }
    }

    /// An optional number with a documented default.
    pub fn number_or(&mut self, column: &str, default: f64) -> f64 {
        self.optional_number(column).unwrap_or(default)
    }

    /// A required whole number of pixels ≥ 1.
    pub fn pixel_count(&mut self, column: &str) -> u32 {
        let Some(s) = self.raw(column).map(str::to_string) else {
            self.error(
                column,
                "required column is missing",
                format!("add a '{column}' column"),
            );
            return 0;
        };
        match s.parse::<u32>() {
            Ok(n) if n >= 1 => n,
            _ => {
                let shown = if s.is_empty() {
                    "is empty".to_string()
                } else {
                    format!("'{s}' is not a whole number of pixels ≥ 1")
                };
                self.error(
                    column,
                    shown,
                    "write the image size in pixels as a positive whole number",
                );
                0
            }
        }
    }

    fn parse_number(&mut self, column: &str, s: &str) -> Option<f64> {
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Some(v),
            Ok(_) => {
                self.error(column, format!("'{s}' is not a finite number"), NUMBER_HINT);
                None
            }
            Err(_) => {
                self.error(column, format!("'{s}' is not a number"), NUMBER_HINT);
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &[u8], required: &[&str]) -> (Option<Table>, Vec<Problem>) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("t.csv"), text).unwrap();
        let mut problems = Vec::new();
        let t = read_table(dir.path(), Path::new("t.csv"), required, &mut problems);
        (t, problems)
    }

    #[test]
    fn rows_are_editor_line_numbers_with_comments_bom_and_crlf() {
        let text = b"\xEF\xBB\xBF# comment 1\r\n#comment 2\r\nB, a ,extra\r\n1,2,3\r\n# mid\r\n\r\n4,5,6\r\n\"7\n8\",9,10\r\n11,12,13";
        let (t, problems) = read(text, &["a", "b"]);
        assert!(problems.is_empty(), "{problems:?}");
        let t = t.unwrap();
        let rows: Vec<usize> = t.records.iter().map(|r| r.row).collect();
        assert_eq!(rows, [4, 7, 8, 10]);
        let mut p = Vec::new();
        let mut f = t.fields(&t.records[1], &mut p);
        assert_eq!((f.number("a"), f.number("b")), (5.0, 4.0));
        assert_eq!(t.records[2].fields[0], "7\n8");
    }

    #[test]
    fn bad_cells_are_all_reported_with_row_and_field() {
        let (t, _) = read(b"id,x,y,z,w\n#c\np,abc,NaN,,inf\n", &["id", "x"]);
        let t = t.unwrap();
        let mut p = Vec::new();
        let mut f = t.fields(&t.records[0], &mut p);
        f.number("x");
        f.number("y");
        f.number("z");
        assert_eq!(f.optional_number("w"), None);
        assert!(!f.ok);
        let shown: Vec<String> = p.iter().map(|p| p.to_string()).collect();
        assert_eq!(shown[0], "t.csv:3: field 'x': 'abc' is not a number — write a decimal number with '.' as decimal mark");
        assert_eq!(shown[1], "t.csv:3: field 'y': 'NaN' is not a finite number — write a decimal number with '.' as decimal mark");
        assert_eq!(
            shown[2],
            "t.csv:3: field 'z': is empty — write a decimal number with '.' as decimal mark"
        );
        assert!(shown[3].starts_with("t.csv:3: field 'w': 'inf' is not a finite number"));
    }

    #[test]
    fn missing_columns_and_wrong_cell_counts() {
        let (t, p) = read(b"# c\nid,y\n1,2\n", &["id", "x", "z"]);
        assert!(t.is_none());
        assert_eq!(p.len(), 2);
        assert_eq!((p[0].row, p[0].field.as_deref()), (Some(2), Some("x")));
        assert_eq!((p[1].row, p[1].field.as_deref()), (Some(2), Some("z")));
        let (t, p) = read(b"id,x\n1,2\n1,2,3\n4\n5,6\n", &["id", "x"]);
        assert_eq!(t.unwrap().records.len(), 2);
        assert_eq!(p.iter().map(|p| p.row.unwrap()).collect::<Vec<_>>(), [3, 4]);
        let (t, p) = read(b"", &["id"]);
        assert!(t.is_none() && p.len() == 1 && p[0].message.contains("empty"));
    }
}

//! Reading one workflow file: TOML text → located value tree (`tree::Table`), with syntax errors reported at
//! their line and column. Byte offsets from the parser become 1-based line/column (column in characters).

use std::ops::Range;
use std::path::{Path, PathBuf};

use toml_edit::{ImDocument, InlineTable, Item, Key};

use super::error::WorkflowError;
use super::tree::{Entry, Loc, Node, Table, Value};

/// One source file of a workflow (the workflow file itself or an included file).
#[derive(Debug, Clone)]
pub(crate) struct SourceFile {
    /// The path as shown in messages (as given by the user, joined for includes).
    pub path: PathBuf,
    pub bytes: Vec<u8>,
}

/// Maps byte offsets of one text to 1-based (line, column).
struct LineIndex<'t> {
    text: &'t str,
    line_starts: Vec<usize>,
}

impl<'t> LineIndex<'t> {
    fn new(text: &'t str) -> Self {
        let mut line_starts = vec![0];
        line_starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        LineIndex { text, line_starts }
    }

    fn line_column(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let line = self.line_starts.partition_point(|&start| start <= offset) - 1;
        let start = self.line_starts[line];
        let column = self
            .text
            .get(start..offset)
            .map_or(offset - start, |s| s.chars().count());
        (line + 1, column + 1)
    }
}

/// Parses `text` (the content of source number `file_index`, shown as `path`) into a located table.
pub(crate) fn parse_source(
    text: &str,
    path: &Path,
    file_index: usize,
) -> Result<Table, WorkflowError> {
    let index = LineIndex::new(text);
    let document = ImDocument::parse(text).map_err(|e| {
        let (line, column) = e.span().map_or((1, 1), |s| index.line_column(s.start));
        let message = e.message().trim_end().replace('\n', " ");
        WorkflowError::at(path, line, column, format!("TOML syntax error: {message}"))
    })?;
    let converter = Converter {
        index: &index,
        path,
        file_index,
    };
    let root = document.as_table();
    converter.table(root.iter(), |k| root.key(k))
}

struct Converter<'a, 't> {
    index: &'a LineIndex<'t>,
    path: &'a Path,
    file_index: usize,
}

impl Converter<'_, '_> {
    fn loc(&self, span: Option<Range<usize>>, fallback_offset: usize) -> Loc {
        let (line, column) = self
            .index
            .line_column(span.map_or(fallback_offset, |s| s.start));
        Loc {
            file: self.file_index,
            line,
            column,
        }
    }

    fn error(&self, at: Loc, message: String) -> WorkflowError {
        WorkflowError::at(self.path, at.line, at.column, message)
    }

    fn table<'i, I, K>(&self, items: I, key_of: K) -> Result<Table, WorkflowError>
    where
        I: Iterator<Item = (&'i str, &'i Item)>,
        K: Fn(&str) -> Option<&'i Key>,
    {
        let mut table = Table::default();
        for (name, item) in items {
            let key_span = key_of(name).and_then(|k| k.span());
            let key_at = self.loc(key_span, 0);
            if let Some(node) = self.item(item, key_at)? {
                table.entries.push(Entry {
                    key: name.to_string(),
                    key_at,
                    node,
                });
            }
        }
        Ok(table)
    }

    fn inline_table(&self, t: &InlineTable, key_at: Loc) -> Result<Node, WorkflowError> {
        let at = t.span().map_or(key_at, |s| self.loc(Some(s), 0));
        let mut table = Table::default();
        for (name, value) in t.iter() {
            let entry_key_at = self.loc(t.key(name).and_then(|k| k.span()), 0);
            let node = self.value(value, entry_key_at)?;
            table.entries.push(Entry {
                key: name.to_string(),
                key_at: entry_key_at,
                node,
            });
        }
        Ok(Node {
            value: Value::Table(table),
            at,
        })
    }

    /// `key_at` is the position of the key owning this item: the fallback for implicit tables without a span.
    fn item(&self, item: &Item, key_at: Loc) -> Result<Option<Node>, WorkflowError> {
        Ok(Some(match item {
            Item::None => return Ok(None),
            Item::Value(v) => self.value(v, key_at)?,
            Item::Table(t) => {
                let at = t.span().map_or(key_at, |s| self.loc(Some(s), 0));
                let table = self.table(t.iter(), |k| t.key(k))?;
                Node {
                    value: Value::Table(table),
                    at,
                }
            }
            Item::ArrayOfTables(array) => {
                let at = array.span().map_or(key_at, |s| self.loc(Some(s), 0));
                let mut nodes = Vec::with_capacity(array.len());
                for t in array.iter() {
                    let t_at = t.span().map_or(at, |s| self.loc(Some(s), 0));
                    let table = self.table(t.iter(), |k| t.key(k))?;
                    nodes.push(Node {
                        value: Value::Table(table),
                        at: t_at,
                    });
                }
                Node {
                    value: Value::Array(nodes),
                    at,
                }
            }
        }))
    }

    fn value(&self, v: &toml_edit::Value, key_at: Loc) -> Result<Node, WorkflowError> {
        use toml_edit::Value as V;
        let at = v.span().map_or(key_at, |s| self.loc(Some(s), 0));
        let value = match v {
            V::String(s) => Value::String(s.value().clone()),
            V::Integer(i) => Value::Integer(*i.value()),
            V::Float(f) => Value::Float(*f.value()),
            V::Boolean(b) => Value::Boolean(*b.value()),
            V::Datetime(_) => {
                return Err(self.error(
                    at,
                    "date/time values are not used in workflows; write it as a quoted string if a stage expects text"
                        .into(),
                ))
            }
            V::Array(items) => {
                let mut nodes = Vec::with_capacity(items.len());
                for item in items.iter() {
                    nodes.push(self.value(item, at)?);
                }
                Value::Array(nodes)
            }
            V::InlineTable(t) => return self.inline_table(t, key_at),
        };
        Ok(Node { value, at })
    }
}

/// An error at `at`, naming the source file `at` points into.
pub(crate) fn error_at(
    sources: &[SourceFile],
    at: Loc,
    message: impl Into<String>,
) -> WorkflowError {
    let path = sources
        .get(at.file)
        .map_or_else(PathBuf::new, |s| s.path.clone());
    WorkflowError::at(path, at.line, at.column, message)
}

/// "line 12" for a position in `file`, "other.toml:12" for one in another file.
pub(crate) fn describe_position(sources: &[SourceFile], at: Loc, file: usize) -> String {
    if at.file == file {
        format!("line {}", at.line)
    } else {
        let path = sources
            .get(at.file)
            .map_or_else(PathBuf::new, |s| s.path.clone());
        format!("{}:{}", path.display(), at.line)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column_are_one_based_characters() {
        let index = LineIndex::new("ab\nçd = 1\n");
        assert_eq!(index.line_column(0), (1, 1));
        assert_eq!(index.line_column(3), (2, 1));
        // 'ç' is two bytes but one column
        assert_eq!(index.line_column(5), (2, 2));
    }

    #[test]
    fn keys_and_values_carry_positions() {
        let text = "a = 1\n[t.u]\n  x = \"s\"\n[[arr]]\ny = [1, 2.5]\n";
        let t = parse_source(text, Path::new("f.toml"), 3).unwrap();
        let a = t.get("a").unwrap();
        assert_eq!((a.key_at.line, a.key_at.column), (1, 1));
        assert_eq!((a.node.at.line, a.node.at.column), (1, 5));
        assert_eq!(a.node.at.file, 3);
        let Value::Table(tt) = &t.get("t").unwrap().node.value else {
            panic!("table")
        };
        let Value::Table(u) = &tt.get("u").unwrap().node.value else {
            panic!("table")
        };
        let x = u.get("x").unwrap();
        assert_eq!((x.key_at.line, x.key_at.column), (3, 3));
        assert_eq!(x.node.value, Value::String("s".into()));
        let Value::Array(arr) = &t.get("arr").unwrap().node.value else {
            panic!("array")
        };
        let Value::Table(first) = &arr[0].value else {
            panic!("table")
        };
        let y = first.get("y").unwrap();
        assert_eq!((y.node.at.line, y.node.at.column), (5, 5));
    }

    #[test]
    fn syntax_error_has_position() {
        let e = parse_source("a = 1\nb = = 2\n", Path::new("w.toml"), 0).unwrap_err();
        assert_eq!((e.line, e.column), (2, 5), "{e}");
        assert!(e.message.starts_with("TOML syntax error"), "{e}");
    }
}

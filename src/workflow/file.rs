//! Loading a workflow file together with the files it includes (`include = ["base.toml"]`): each file is parsed
//! into a located tree, included files are merged first (in the order listed) and the including file is merged
//! on top. Relative include paths are resolved against the including file's folder; cycles are errors that show
//! the chain. A file reached twice (diamond) is merged once, where it is first included. Keys that belong to one
//! file only (`include`, `name`) are not inherited; sweep variants accumulate.

use std::path::{Path, PathBuf};

use super::error::WorkflowError;
use super::source::{parse_source, SourceFile};
use super::tree::{Entry, Loc, Node, Table, Value};

/// Deepest include nesting accepted (a guard against runaway chains that are not cycles).
const MAX_INCLUDE_DEPTH: usize = 32;

/// The merged tree of a workflow and all files read for it (index 0 = the workflow file, then includes in the
/// order they were read).
#[derive(Debug, Clone)]
pub(crate) struct Loaded {
    pub sources: Vec<SourceFile>,
    pub document: Table,
}

/// Where a workflow's files are read from: the file system, or a set of files built into the program.
#[derive(Clone, Copy, Debug)]
pub enum WorkflowFiles {
    /// Files on disk; includes are resolved against the including file's folder.
    Disk,
    /// Files built into the program: (file name, text). Their paths are shown as `<built-in>/NAME`; an
    /// include names another built-in file.
    BuiltIn(&'static [(&'static str, &'static str)]),
}

/// The folder that built-in workflow files appear to live in (messages show `<built-in>/default.toml`).
pub const BUILT_IN_DIR: &str = "<built-in>";

impl WorkflowFiles {
    /// The canonical form of `path` (for cycle and diamond detection), or why it cannot be read.
    fn canonical(self, path: &Path) -> std::io::Result<PathBuf> {
        match self {
            WorkflowFiles::Disk => std::fs::canonicalize(path),
            WorkflowFiles::BuiltIn(files) => {
                let name = built_in_name(path);
                match files.iter().find(|(n, _)| Some(*n) == name.as_deref()) {
                    Some((n, _)) => Ok(Path::new(BUILT_IN_DIR).join(n)),
                    None => Err(std::io::Error::new(
                        std::io::ErrorKind::NotFound,
                        format!(
                            "no built-in workflow file of that name (built in: {})",
                            files.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                        ),
                    )),
                }
            }
        }
    }

    /// The bytes of a file given by its canonical path.
    fn read(self, canonical: &Path) -> std::io::Result<Vec<u8>> {
        match self {
            WorkflowFiles::Disk => std::fs::read(canonical),
            WorkflowFiles::BuiltIn(files) => {
                let name = built_in_name(canonical);
                files
                    .iter()
                    .find(|(n, _)| Some(*n) == name.as_deref())
                    .map(|(_, text)| text.as_bytes().to_vec())
                    .ok_or_else(|| std::io::Error::from(std::io::ErrorKind::NotFound))
            }
        }
    }
}

/// The file name of a path below [`BUILT_IN_DIR`] (`.` and `..` resolved), if it stays there.
fn built_in_name(path: &Path) -> Option<String> {
    let mut parts: Vec<String> = Vec::new();
    for c in path.components() {
        match c {
            std::path::Component::Normal(s) => parts.push(s.to_string_lossy().into_owned()),
            std::path::Component::ParentDir => {
                parts.pop()?;
            }
            _ => {}
        }
    }
    match parts.as_slice() {
        [dir, name] if dir == BUILT_IN_DIR => Some(name.clone()),
        _ => None,
    }
}

/// Loads the workflow whose text is `text` and which lives at `path`, reading its includes from `files`.
pub(crate) fn load_document(
    text: &str,
    path: &Path,
    files: WorkflowFiles,
) -> Result<Loaded, WorkflowError> {
    let mut loader = Loader {
        sources: Vec::new(),
        stack: Vec::new(),
        seen: Vec::new(),
        files,
    };
    let canonical = files.canonical(path).unwrap_or_else(|_| path.to_path_buf());
    let document = loader.load(text, path, canonical)?;
    Ok(Loaded {
        sources: loader.sources,
        document,
    })
}

struct Loader {
    sources: Vec<SourceFile>,
    /// The chain of files being loaded: (canonical path, path as shown).
    stack: Vec<(PathBuf, PathBuf)>,
    /// Canonical paths of all files read so far: a file reached twice (diamond includes) is merged once.
    seen: Vec<PathBuf>,
    files: WorkflowFiles,
}

impl Loader {
    fn load(
        &mut self,
        text: &str,
        shown: &Path,
        canonical: PathBuf,
    ) -> Result<Table, WorkflowError> {
        self.seen.push(canonical.clone());
        let file_index = self.sources.len();
        self.sources.push(SourceFile {
            path: shown.to_path_buf(),
            bytes: text.as_bytes().to_vec(),
        });
        let mut own = parse_source(text, shown, file_index)?;
        let includes = match own.remove("include") {
            Some(entry) => include_list(entry, shown)?,
            None => Vec::new(),
        };
        self.stack.push((canonical, shown.to_path_buf()));
        let mut merged = Table::default();
        for (include, at) in includes {
            let mut included = self.load_include(&include, at, shown)?;
            included.remove("name");
            merge_layer(&mut merged, included);
        }
        self.stack.pop();
        merge_layer(&mut merged, own);
        Ok(merged)
    }

    fn load_include(
        &mut self,
        include: &str,
        at: Loc,
        from: &Path,
    ) -> Result<Table, WorkflowError> {
        let error = |message: String| WorkflowError::at(from, at.line, at.column, message);
        let shown = from.parent().unwrap_or(Path::new("")).join(include);
        let canonical = self.files.canonical(&shown).map_err(|e| {
            error(format!(
                "cannot read included file '{include}' (looked for {}): {e}",
                shown.display()
            ))
        })?;
        if let Some(start) = self.stack.iter().position(|(c, _)| *c == canonical) {
            let mut chain: Vec<String> = self.stack[start..]
                .iter()
                .map(|(_, s)| s.display().to_string())
                .collect();
            chain.push(shown.display().to_string());
            return Err(error(format!(
                "include cycle: {}; remove one of these includes",
                chain.join(" -> ")
            )));
        }
        if self.seen.contains(&canonical) {
            return Ok(Table::default()); // already merged where it was first included
        }
        if self.stack.len() >= MAX_INCLUDE_DEPTH {
            return Err(error(format!(
                "includes nested deeper than {MAX_INCLUDE_DEPTH} files"
            )));
        }
        let bytes = self.files.read(&canonical).map_err(|e| {
            error(format!(
                "cannot read included file '{include}' ({}): {e}",
                shown.display()
            ))
        })?;
        let text = String::from_utf8(bytes).map_err(|_| {
            error(format!(
                "included file '{include}' is not UTF-8 text ({})",
                shown.display()
            ))
        })?;
        self.load(&text, &shown, canonical)
    }
}

/// The entries of `include = "a.toml"` or `include = ["a.toml", "b.toml"]` with their positions.
fn include_list(entry: Entry, file: &Path) -> Result<Vec<(String, Loc)>, WorkflowError> {
    let wrong = |at: Loc, found: &str| {
        WorkflowError::at(
            file,
            at.line,
            at.column,
            format!(
                "include must be a file path or an array of file paths (strings), found {found}"
            ),
        )
    };
    match entry.node.value {
        Value::String(s) => Ok(vec![(s, entry.node.at)]),
        Value::Array(items) => items
            .into_iter()
            .map(|n| match n.value {
                Value::String(s) => Ok((s, n.at)),
                other => Err(wrong(n.at, other.type_name())),
            })
            .collect(),
        other => Err(wrong(entry.node.at, other.type_name())),
    }
}

/// Merges one layer on top of `base` (see `Table::merge_from`), except that `[[sweep.variant]]` arrays of both
/// sides are concatenated (base first) so that files can add variants to the ones they include.
pub(crate) fn merge_layer(base: &mut Table, mut over: Table) {
    let base_variants = take_variants(base);
    let over_variants = take_variants(&mut over);
    base.merge_from(over);
    let combined = match (base_variants, over_variants) {
        (Some((mut b, _, _)), Some((o, key_at, at))) => {
            b.extend(o);
            Some((b, key_at, at))
        }
        (one, None) | (None, one) => one,
    };
    if let Some((nodes, key_at, at)) = combined {
        if let Some(Entry {
            node:
                Node {
                    value: Value::Table(sweep),
                    ..
                },
            ..
        }) = base.get_mut("sweep")
        {
            sweep.set(Entry {
                key: "variant".into(),
                key_at,
                node: Node {
                    value: Value::Array(nodes),
                    at,
                },
            });
        }
    }
}

/// Removes `sweep.variant` when it is an array, returning its items and positions.
fn take_variants(table: &mut Table) -> Option<(Vec<Node>, Loc, Loc)> {
    let Some(Entry {
        node: Node {
            value: Value::Table(sweep),
            ..
        },
        ..
    }) = table.get_mut("sweep")
    else {
        return None;
    };
    if !matches!(
        sweep.get("variant"),
        Some(Entry {
            node: Node {
                value: Value::Array(_),
                ..
            },
            ..
        })
    ) {
        return None;
    }
    let entry = sweep.remove("variant")?;
    match entry.node.value {
        Value::Array(nodes) => Some((nodes, entry.key_at, entry.node.at)),
        _ => None,
    }
}

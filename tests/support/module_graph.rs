//! A crate's module graph read from its source text, for the architecture test: which module files refer to
//! which modules (through `use` declarations and inline `crate::…` / `super::…` / `self::…` paths), and the
//! cycles among sibling modules.
//!
//! The unit is a module *file*: `src/dag/inputs.rs` is `dag::inputs`, `src/dag/mod.rs` is `dag`. A reference
//! from a file to a module counts for the pair of siblings under their lowest common ancestor: a file below
//! `dag::inputs` naming `dag::stage::X` gives the edge `inputs → stage` in the graph of `dag`'s children. A
//! name that a `mod.rs` re-exports from one of its children (`pub use child::Name`) resolves to that child.
//! References between a module and its own ancestors are not sibling edges (a parent declares its children).
#![allow(dead_code)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module path segments below the crate root, e.g. `["dag", "inputs"]`; the root is `[]`.
pub type ModPath = Vec<String>;

/// One crate's module files and their references.
pub struct ModuleGraph {
    /// Module path → the file that defines it.
    pub files: BTreeMap<ModPath, PathBuf>,
    /// Module path → the module paths its file refers to (resolved as far as the text allows).
    pub refs: BTreeMap<ModPath, BTreeSet<ModPath>>,
    /// Module path → names its file re-exports from a child (`pub use child::{A, B}`), name → child.
    reexports: BTreeMap<ModPath, BTreeMap<String, String>>,
    /// Module path → external crate names it refers to (`skytie_stages`, ...).
    pub externs: BTreeMap<ModPath, BTreeSet<String>>,
}

/// The source text without comments and string/char literals (replaced by spaces), so paths in docs and
/// messages are not mistaken for references.
pub fn strip_comments_and_strings(src: &str) -> String {
    let b = src.as_bytes();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if b[i] == b'r' && (b.get(i + 1) == Some(&b'"') || b.get(i + 1) == Some(&b'#')) {
            // Raw string r"…" or r#"…"#.
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&b'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&b'"') {
                out.push('r');
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= b.len() {
                    break;
                }
                if b[j] == b'"' && (0..hashes).all(|k| b.get(j + 1 + k) == Some(&b'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            out.push(' ');
            i = j;
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                if b[i] == b'\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push(' ');
        } else if b[i] == b'\'' {
            // A char literal ('a', '\n', '\u{..}') or a lifetime ('a): skip only char literals.
            let close = if b.get(i + 1) == Some(&b'\\') {
                src[i + 2..].find('\'').map(|k| i + 2 + k)
            } else if b.get(i + 2) == Some(&b'\'') {
                Some(i + 2)
            } else {
                // Multi-byte char literal?
                let rest = &src[i + 1..];
                let mut chars = rest.char_indices();
                match (chars.next(), chars.next()) {
                    (Some((_, c)), Some((k, '\''))) if c != '\'' => Some(i + 1 + k),
                    _ => None,
                }
            };
            match close {
                Some(c) => {
                    out.push(' ');
                    i = c + 1;
                }
                None => {
                    out.push('\'');
                    i += 1;
                }
            }
        } else {
            let ch = src[i..].chars().next().unwrap_or(' ');
            out.push(ch);
            i += ch.len_utf8();
        }
    }
    out
}

/// The module path a source file defines, relative to the crate's `src` folder.
fn module_path_of(src_root: &Path, file: &Path) -> Option<ModPath> {
    let rel = file.strip_prefix(src_root).ok()?;
    let mut parts: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop()?;
    let stem = last.strip_suffix(".rs")?;
    match stem {
        "lib" | "main" if parts.is_empty() => {}
        "mod" => {}
        _ => parts.push(stem.to_string()),
    }
    Some(parts)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// Expands a `use` tree (`a::{b, c::{d, e}}` → `a::b`, `a::c::d`, `a::c::e`).
fn expand_use_tree(tree: &str) -> Vec<String> {
    // Drop renames (`X as Y`) before folding white space away.
    let words: Vec<&str> = tree.split_whitespace().collect();
    let mut kept = String::new();
    let mut k = 0;
    while k < words.len() {
        if words[k] == "as" {
            k += 2;
            continue;
        }
        kept.push_str(words[k]);
        k += 1;
    }
    let tree = kept;
    let mut out = Vec::new();
    expand_into("", &tree, &mut out);
    out
}

fn expand_into(prefix: &str, tree: &str, out: &mut Vec<String>) {
    if let Some(open) = tree.find('{') {
        let head = &tree[..open];
        let close = tree.rfind('}').unwrap_or(tree.len());
        let inner = &tree[open + 1..close];
        let mut depth = 0;
        let mut start = 0;
        let base = format!("{prefix}{head}");
        for (k, c) in inner.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand_into(&base, &inner[start..k], out);
                    start = k + 1;
                }
                _ => {}
            }
        }
        expand_into(&base, &inner[start..], out);
    } else if !tree.is_empty() {
        out.push(format!("{prefix}{tree}"));
    }
}

/// Paths (`a::b::c`) written in `code` that start with `crate`, `super`, `self` or an external crate.
fn inline_paths(code: &str) -> Vec<String> {
    let b = code.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let is_start = (b[i].is_ascii_alphabetic() || b[i] == b'_')
            && (i == 0
                || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_' || b[i - 1] == b':'));
        if !is_start {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < b.len()
            && (b[j].is_ascii_alphanumeric()
                || b[j] == b'_'
                || (b[j] == b':' && b.get(j + 1) == Some(&b':')))
        {
            if b[j] == b':' {
                j += 2;
            } else {
                j += 1;
            }
        }
        let path = &code[i..j];
        if path.contains("::") {
            out.push(path.trim_end_matches(':').to_string());
        }
        i = j.max(i + 1);
    }
    out
}

impl ModuleGraph {
    /// Reads every `.rs` file below `src_root` (a crate's `src/`).
    pub fn read(src_root: &Path) -> ModuleGraph {
        let mut files = Vec::new();
        rust_files(src_root, &mut files);
        let mut graph = ModuleGraph {
            files: BTreeMap::new(),
            refs: BTreeMap::new(),
            reexports: BTreeMap::new(),
            externs: BTreeMap::new(),
        };
        let mut texts = BTreeMap::new();
        for f in &files {
            let Some(m) = module_path_of(src_root, f) else {
                continue;
            };
            let text = std::fs::read_to_string(f).unwrap_or_default();
            graph.files.insert(m.clone(), f.clone());
            texts.insert(m, strip_comments_and_strings(&text));
        }
        // Re-exports of children (`pub use child::…` / `pub use self::child::…`).
        for (m, code) in &texts {
            let mut map = BTreeMap::new();
            for stmt in use_statements(code)
                .into_iter()
                .filter(|(public, _)| *public)
            {
                for p in expand_use_tree(&stmt.1) {
                    let segs: Vec<&str> = p.split("::").filter(|s| !s.is_empty()).collect();
                    let segs: Vec<&str> = if segs.first() == Some(&"self") {
                        segs[1..].to_vec()
                    } else {
                        segs
                    };
                    if segs.len() >= 2 {
                        let mut child = m.clone();
                        child.push(segs[0].to_string());
                        if graph.files.contains_key(&child) {
                            let name = segs[segs.len() - 1];
                            if name != "*" && name != "self" {
                                map.insert(name.to_string(), segs[0].to_string());
                            }
                        }
                    }
                }
            }
            graph.reexports.insert(m.clone(), map);
        }
        for (m, code) in &texts {
            let mut targets = BTreeSet::new();
            let mut externs = BTreeSet::new();
            let mut paths: Vec<String> = use_statements(code)
                .into_iter()
                .flat_map(|(_, tree)| expand_use_tree(&tree))
                .collect();
            paths.extend(inline_paths(code));
            for p in paths {
                let segs: Vec<String> = p
                    .split("::")
                    .filter(|s| !s.is_empty())
                    .map(str::to_string)
                    .collect();
                if segs.is_empty() {
                    continue;
                }
                match graph.resolve(m, &segs) {
                    Resolved::Module(t) => {
                        targets.insert(t);
                    }
                    Resolved::Extern(name) => {
                        externs.insert(name);
                    }
                    Resolved::Unknown => {}
                }
            }
            targets.remove(m);
            graph.refs.insert(m.clone(), targets);
            graph.externs.insert(m.clone(), externs);
        }
        graph
    }

    fn resolve(&self, from: &ModPath, segs: &[String]) -> Resolved {
        // The module the path starts in.
        let (mut base, rest): (ModPath, &[String]) = match segs[0].as_str() {
            "crate" => (Vec::new(), &segs[1..]),
            "self" => (from.clone(), &segs[1..]),
            "super" => {
                let mut b = from.clone();
                let mut k = 0;
                while segs.get(k).map(String::as_str) == Some("super") {
                    b.pop();
                    k += 1;
                }
                (b, &segs[k..])
            }
            "skytie_stages" | "skytie_util" | "skytie" => return Resolved::Extern(segs[0].clone()),
            first => {
                // A child module named directly (`use child::X` in a parent, 2018 paths).
                let mut child = from.clone();
                child.push(first.to_string());
                if self.files.contains_key(&child) {
                    (child, &segs[1..])
                } else {
                    return Resolved::Unknown;
                }
            }
        };
        for s in rest {
            let mut next = base.clone();
            next.push(s.clone());
            if self.files.contains_key(&next) {
                base = next;
                continue;
            }
            if let Some(child) = self.reexports.get(&base).and_then(|r| r.get(s)) {
                base.push(child.clone());
            }
            break;
        }
        Resolved::Module(base)
    }

    /// Edges between siblings: parent module → (child → children it refers to).
    pub fn sibling_edges(&self) -> BTreeMap<ModPath, BTreeMap<String, BTreeSet<String>>> {
        let mut out: BTreeMap<ModPath, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
        for (from, targets) in &self.refs {
            for to in targets {
                let common = from.iter().zip(to).take_while(|(a, b)| a == b).count();
                if common >= from.len() || common >= to.len() {
                    continue; // ancestor or descendant
                }
                out.entry(from[..common].to_vec())
                    .or_default()
                    .entry(from[common].clone())
                    .or_default()
                    .insert(to[common].clone());
            }
        }
        out
    }

    /// Every cycle among siblings, as `parent: a → b → … → a` strings (one per strongly connected component of
    /// more than one module).
    pub fn sibling_cycles(&self) -> Vec<String> {
        let mut cycles = Vec::new();
        for (parent, edges) in self.sibling_edges() {
            for scc in strongly_connected(&edges) {
                if scc.len() > 1 {
                    let name = if parent.is_empty() {
                        "crate".to_string()
                    } else {
                        parent.join("::")
                    };
                    cycles.push(format!(
                        "{name}: {{{}}}",
                        scc.into_iter().collect::<Vec<_>>().join(", ")
                    ));
                }
            }
        }
        cycles
    }

    /// Files under `prefix` that refer to any module under one of `forbidden` (module paths) or to one of the
    /// `forbidden_externs` crates: `(file, what)`.
    pub fn forbidden_refs(
        &self,
        prefix: &[&str],
        forbidden: &[&[&str]],
        forbidden_externs: &[&str],
    ) -> Vec<(PathBuf, String)> {
        let mut out = Vec::new();
        for (m, targets) in &self.refs {
            if !m.starts_with(&prefix.iter().map(|s| s.to_string()).collect::<Vec<_>>()) {
                continue;
            }
            for t in targets {
                for f in forbidden {
                    let f: Vec<String> = f.iter().map(|s| s.to_string()).collect();
                    if t.starts_with(&f) {
                        out.push((self.files[m].clone(), format!("crate::{}", t.join("::"))));
                    }
                }
            }
            for e in &self.externs[m] {
                if forbidden_externs.contains(&e.as_str()) {
                    out.push((self.files[m].clone(), e.clone()));
                }
            }
        }
        out
    }
}

enum Resolved {
    Module(ModPath),
    Extern(String),
    Unknown,
}

/// `use` declarations: (is `pub`, the tree after `use`).
fn use_statements(code: &str) -> Vec<(bool, String)> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(k) = find_word(rest, "use") {
        let before = rest[..k].trim_end();
        let public = before.ends_with("pub") || before.ends_with(')') && before.contains("pub(");
        let after = &rest[k + 3..];
        let end = after.find(';').unwrap_or(after.len());
        out.push((public, after[..end].trim().to_string()));
        rest = &after[end.min(after.len())..];
    }
    out
}

fn find_word(text: &str, word: &str) -> Option<usize> {
    let b = text.as_bytes();
    let mut from = 0;
    while let Some(k) = text[from..].find(word) {
        let at = from + k;
        let ok_before = at == 0 || !(b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_');
        let after = at + word.len();
        let ok_after = after < b.len() && b[after].is_ascii_whitespace();
        if ok_before && ok_after {
            return Some(at);
        }
        from = at + word.len();
    }
    None
}

/// Tarjan's strongly connected components of a small graph given as adjacency sets.
fn strongly_connected(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<BTreeSet<String>> {
    let nodes: BTreeSet<&String> = edges.keys().chain(edges.values().flatten()).collect();
    let nodes: Vec<&String> = nodes.into_iter().collect();
    let index_of: BTreeMap<&String, usize> =
        nodes.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let n = nodes.len();
    let mut index = vec![usize::MAX; n];
    let mut low = vec![0; n];
    let mut on_stack = vec![false; n];
    let mut stack = Vec::new();
    let mut next = 0;
    let mut out = Vec::new();
    fn visit(
        v: usize,
        nodes: &[&String],
        edges: &BTreeMap<String, BTreeSet<String>>,
        index_of: &BTreeMap<&String, usize>,
        state: (
            &mut Vec<usize>,
            &mut Vec<usize>,
            &mut Vec<bool>,
            &mut Vec<usize>,
            &mut usize,
        ),
        out: &mut Vec<BTreeSet<String>>,
    ) {
        let (index, low, on_stack, stack, next) = state;
        index[v] = *next;
        low[v] = *next;
        *next += 1;
        stack.push(v);
        on_stack[v] = true;
        if let Some(succ) = edges.get(nodes[v]) {
            for w in succ {
                let w = index_of[w];
                if index[w] == usize::MAX {
                    visit(
                        w,
                        nodes,
                        edges,
                        index_of,
                        (
                            &mut *index,
                            &mut *low,
                            &mut *on_stack,
                            &mut *stack,
                            &mut *next,
                        ),
                        out,
                    );
                    low[v] = low[v].min(low[w]);
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
            }
        }
        if low[v] == index[v] {
            let mut scc = BTreeSet::new();
            while let Some(w) = stack.pop() {
                on_stack[w] = false;
                scc.insert(nodes[w].clone());
                if w == v {
                    break;
                }
            }
            out.push(scc);
        }
    }
    for v in 0..n {
        if index[v] == usize::MAX {
            visit(
                v,
                &nodes,
                edges,
                &index_of,
                (&mut index, &mut low, &mut on_stack, &mut stack, &mut next),
                &mut out,
            );
        }
    }
    out
}

//! Sweeps: named variants of a workflow, each a set of parameter overrides on top of the stage tables.
//!
//! ```toml
//! [[sweep.variant]]
//! name = "exp01"
//! "plane.max_angle_deg" = 2        # dotted path: stage, then parameter (nested tables allowed)
//! oblique.patch.extent_m = 12      # the same with a TOML dotted key
//! [sweep.variant.ortho]            # or a table form for several parameters of one stage
//! gsd_m = 0.05
//! ```
//! Every override is flattened to (stage, parameter path, value) so that merging is a per-leaf replacement:
//! untouched parameters keep the stage table's value (or the stage default).

use super::error::WorkflowError;
use super::source::{describe_position, error_at, SourceFile};
use super::suggest::did_you_mean;
use super::tree::{Entry, Loc, Node, Table, Value};

/// Keys of `[sweep]` itself.
pub(crate) const SWEEP_KEYS: &[&str] = &["base", "description", "variant"];

#[derive(Debug, Clone)]
pub(crate) struct Sweep {
    pub at: Loc,
    /// Informative: the name of the workflow the sweep builds on.
    pub base: Option<String>,
    pub variants: Vec<Variant>,
}

#[derive(Debug, Clone)]
pub(crate) struct Variant {
    pub name: String,
    pub name_at: Loc,
    pub description: Option<String>,
    pub overrides: Vec<Override>,
}

/// One overridden parameter: `stage` . `path` = `node`.
#[derive(Debug, Clone)]
pub(crate) struct Override {
    pub stage: String,
    pub path: Vec<String>,
    /// Position of the key that sets this leaf.
    pub key_at: Loc,
    pub node: Node,
}

impl Override {
    pub fn dotted(&self) -> String {
        let mut s = self.stage.clone();
        for p in &self.path {
            s.push('.');
            s.push_str(p);
        }
        s
    }
}

/// Reads the `sweep` entry. `stages` are the enabled stage names, `document` the merged workflow (for the
/// stage tables). All problems found are pushed to `errors`.
pub(crate) fn parse_sweep(
    entry: &Entry,
    stages: &[String],
    document: &Table,
    sources: &[SourceFile],
    errors: &mut Vec<WorkflowError>,
) -> Option<Sweep> {
    let Value::Table(table) = &entry.node.value else {
        errors.push(error_at(
            sources,
            entry.node.at,
            format!(
                "sweep must be a table ([sweep]), found {}",
                entry.node.value.type_name()
            ),
        ));
        return None;
    };
    let mut sweep = Sweep {
        at: entry.key_at,
        base: None,
        variants: Vec::new(),
    };
    for e in &table.entries {
        match e.key.as_str() {
            "base" | "description" => match &e.node.value {
                Value::String(s) => {
                    if e.key == "base" {
                        sweep.base = Some(s.clone());
                    }
                }
                other => errors.push(error_at(
                    sources,
                    e.node.at,
                    format!(
                        "sweep.{} must be a string, found {}",
                        e.key,
                        other.type_name()
                    ),
                )),
            },
            "variant" => match &e.node.value {
                Value::Array(items) => {
                    for (i, item) in items.iter().enumerate() {
                        if let Some(v) =
                            parse_variant(item, i + 1, stages, document, sources, errors)
                        {
                            if let Some(first) = sweep.variants.iter().find(|f| f.name == v.name) {
                                let first_at =
                                    describe_position(sources, first.name_at, v.name_at.file);
                                errors.push(error_at(
                                    sources,
                                    v.name_at,
                                    format!(
                                        "duplicate variant name '{}' (first declared at {first_at}); variant names must be unique",
                                        v.name
                                    ),
                                ));
                            } else {
                                sweep.variants.push(v);
                            }
                        }
                    }
                }
                other => errors.push(error_at(
                    sources,
                    e.node.at,
                    format!(
                        "sweep.variant must be an array of tables ([[sweep.variant]]), found {}",
                        other.type_name()
                    ),
                )),
            },
            other => errors.push(error_at(
                sources,
                e.key_at,
                format!(
                    "unknown key '{other}' in [sweep]{}",
                    did_you_mean(other, SWEEP_KEYS)
                ),
            )),
        }
    }
    Some(sweep)
}

/// A name usable as a folder name (a workflow's `OUT/<name>/`, a variant's `OUT/variants/<name>/`): letters,
/// digits, `_`, `-`, `.`; not starting with `.`.
pub(super) fn valid_folder_name(name: &str) -> bool {
    !name.is_empty()
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
}

fn parse_variant(
    node: &Node,
    number: usize,
    stages: &[String],
    document: &Table,
    sources: &[SourceFile],
    errors: &mut Vec<WorkflowError>,
) -> Option<Variant> {
    let Value::Table(table) = &node.value else {
        errors.push(error_at(
            sources,
            node.at,
            format!(
                "sweep variant #{number} must be a table, found {}",
                node.value.type_name()
            ),
        ));
        return None;
    };
    let name_entry = table.get("name");
    let (name, name_at) = match name_entry.map(|e| (&e.node.value, e.node.at)) {
        Some((Value::String(s), at)) if valid_folder_name(s) => (s.clone(), at),
        Some((Value::String(s), at)) => {
            errors.push(error_at(
                sources,
                at,
                format!(
                    "variant name {s:?} cannot be used as a folder name: use letters, digits, '_', '-' or '.' (not first)"
                ),
            ));
            return None;
        }
        Some((other, at)) => {
            errors.push(error_at(
                sources,
                at,
                format!("variant name must be a string, found {}", other.type_name()),
            ));
            return None;
        }
        None => {
            errors.push(error_at(
                sources,
                node.at,
                format!("sweep variant #{number} has no name: add name = \"...\" to it"),
            ));
            return None;
        }
    };
    let mut variant = Variant {
        name,
        name_at,
        description: None,
        overrides: Vec::new(),
    };
    for e in &table.entries {
        match e.key.as_str() {
            "name" => {}
            "description" => match &e.node.value {
                Value::String(s) => variant.description = Some(s.clone()),
                other => errors.push(error_at(
                    sources,
                    e.node.at,
                    format!(
                        "variant description must be a string, found {}",
                        other.type_name()
                    ),
                )),
            },
            _ => flatten(
                e,
                &[],
                None,
                &mut variant,
                stages,
                document,
                sources,
                errors,
            ),
        }
    }
    Some(variant)
}

/// Flattens one override entry (dotted key and/or nested tables) into leaf overrides of `variant`.
#[allow(clippy::too_many_arguments)]
fn flatten(
    entry: &Entry,
    prefix: &[String],
    stage_at: Option<Loc>,
    variant: &mut Variant,
    stages: &[String],
    document: &Table,
    sources: &[SourceFile],
    errors: &mut Vec<WorkflowError>,
) {
    let mut path = prefix.to_vec();
    for part in entry.key.split('.') {
        if part.is_empty() {
            errors.push(error_at(
                sources,
                entry.key_at,
                format!(
                    "override path '{}' has an empty part; write it as \"stage.parameter\"",
                    entry.key
                ),
            ));
            return;
        }
        path.push(part.to_string());
    }
    let stage_at = stage_at.unwrap_or(entry.key_at);
    if prefix.is_empty() && !stages.iter().any(|s| *s == path[0]) {
        errors.push(error_at(
            sources,
            stage_at,
            format!(
                "unknown stage '{}' in override of variant '{}' (enabled stages: {}){}",
                path[0],
                variant.name,
                stages.join(", "),
                did_you_mean(&path[0], stages)
            ),
        ));
        return;
    }
    if let Value::Table(children) = &entry.node.value {
        for child in &children.entries {
            flatten(
                child,
                &path,
                Some(stage_at),
                variant,
                stages,
                document,
                sources,
                errors,
            );
        }
        return;
    }
    if path.len() < 2 {
        errors.push(error_at(
            sources,
            entry.key_at,
            format!(
                "override '{}' in variant '{}' must name a parameter: write \"{}.<parameter>\" = value",
                path[0], variant.name, path[0]
            ),
        ));
        return;
    }
    let leaf = Override {
        stage: path[0].clone(),
        path: path[1..].to_vec(),
        key_at: entry.key_at,
        node: entry.node.clone(),
    };
    if let Some(first) = variant
        .overrides
        .iter()
        .find(|o| o.stage == leaf.stage && o.path == leaf.path)
    {
        let first_at = describe_position(sources, first.key_at, leaf.key_at.file);
        errors.push(error_at(
            sources,
            leaf.key_at,
            format!(
                "variant '{}' sets '{}' twice (first at {first_at})",
                variant.name,
                leaf.dotted()
            ),
        ));
        return;
    }
    if let Some(message) = blocked_by_scalar(document, &leaf) {
        errors.push(error_at(sources, leaf.key_at, message));
        return;
    }
    variant.overrides.push(leaf);
}

/// If the stage table holds a non-table value where the override path needs a table, says so.
fn blocked_by_scalar(document: &Table, leaf: &Override) -> Option<String> {
    let mut table = match document.get(&leaf.stage).map(|e| &e.node.value) {
        Some(Value::Table(t)) => t,
        _ => return None,
    };
    let mut label = leaf.stage.clone();
    for part in &leaf.path[..leaf.path.len() - 1] {
        match table.get(part).map(|e| &e.node.value) {
            Some(Value::Table(t)) => {
                table = t;
                label.push('.');
                label.push_str(part);
            }
            Some(other) => {
                return Some(format!(
                    "override '{}' goes through '{part}', which is {} in [{label}], not a table",
                    leaf.dotted(),
                    other.type_name()
                ))
            }
            None => return None,
        }
    }
    None
}

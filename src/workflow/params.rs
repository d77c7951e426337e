//! Stage parameters: the stage's table of the workflow with the chosen variant's overrides merged in, turned
//! into the stage's typed parameter struct and range-checked — every failure reported at its file:line:col.

use serde::de::DeserializeOwned;
use serde::Serialize;

use super::definition::Workflow;
use super::deserializer::{DeError, DeErrorKind, NodeDeserializer};
use super::error::{ParamError, WorkflowError};
use super::suggest::did_you_mean;
use super::sweep::Variant;
use super::tree::{Entry, Loc, Node, Table, Value};

/// A stage's parameter struct. Implementors use `#[serde(deny_unknown_fields, default)]` so that keys absent from
/// the workflow keep their `Default` value and misspelt keys are errors.
pub trait StageParams: DeserializeOwned + Serialize + Default + Clone {
    /// Range checks. Return every violated rule as (dotted field path, message stating the allowed range),
    /// e.g. `ParamError::new("threshold", "must be in (0, 1]")`.
    fn validate(&self) -> Result<(), Vec<ParamError>>;

    /// Top-level field names (for suggestions and for seeding); by default the keys of `Self::default()`
    /// serialised to a TOML table (fields that serialise to nothing, like `None`, are not listed).
    fn field_names() -> Vec<String> {
        default_field_names::<Self>()
    }
}

/// The keys of `P::default()` serialised to a TOML table, sorted (empty if it does not serialise to a table).
pub fn default_field_names<P: Serialize + Default>() -> Vec<String> {
    match toml::Value::try_from(P::default()) {
        Ok(toml::Value::Table(t)) => t.keys().cloned().collect(),
        _ => Vec::new(),
    }
}

impl Workflow {
    /// The parameters of `stage` for `variant`: the stage table with the variant's overrides merged in (deep
    /// merge: an override replaces one parameter, untouched parameters keep the table's value or the default),
    /// deserialised into `P`, then `P::validate()`. If `P` has a top-level integer field `seed` that neither the
    /// table nor the variant sets, it gets the workflow's `seed`. `variant` "default" is the workflow without
    /// overrides, also in a sweep that does not declare a variant of that name (e.g. for stages no variant varies).
    pub fn params<P: StageParams>(&self, stage: &str, variant: &str) -> Result<P, WorkflowError> {
        let variant_def = self.variant(variant)?;
        let mut node = self.merged_stage_table(stage, variant_def)?;
        self.inject_seed::<P>(&mut node);
        let path = vec![stage.to_string()];
        let params = P::deserialize(NodeDeserializer::new(&node, path))
            .map_err(|e| self.deserialize_error(e, node.at, variant_def))?;
        if let Err(problems) = params.validate() {
            return Err(self.validation_error(&params, problems, stage, &node, variant_def));
        }
        Ok(params)
    }

    /// The stage table with the variant's overrides merged in, as plain TOML (no defaults filled in).
    pub fn stage_table(&self, stage: &str, variant: &str) -> Result<toml::Table, WorkflowError> {
        let node = self.merged_stage_table(stage, self.variant(variant)?)?;
        match node.value.to_plain() {
            toml::Value::Table(t) => Ok(t),
            _ => Ok(toml::Table::new()),
        }
    }

    /// Where stage `stage` is configured: its table, else its entry in `stages`, else the file start.
    fn stage_loc(&self, stage: &str) -> Loc {
        if let Some(e) = self.document.get(stage) {
            return e.node.at;
        }
        self.stages.iter().position(|s| s == stage).map_or(
            Loc {
                file: 0,
                line: 1,
                column: 1,
            },
            |i| self.stage_at[i],
        )
    }

    fn merged_stage_table(
        &self,
        stage: &str,
        variant: Option<&Variant>,
    ) -> Result<Node, WorkflowError> {
        let mut node = match self.document.get(stage) {
            Some(e) if matches!(e.node.value, Value::Table(_)) => e.node.clone(),
            _ => Node {
                value: Value::Table(Table::default()),
                at: self.stage_loc(stage),
            },
        };
        let Value::Table(table) = &mut node.value else {
            unreachable!("constructed as a table above")
        };
        for o in variant
            .iter()
            .flat_map(|v| v.overrides.iter())
            .filter(|o| o.stage == stage)
        {
            if !set_path(table, &o.path, o.node.clone(), o.key_at) {
                return Err(self.error(
                    o.key_at,
                    format!(
                        "override '{}' goes through a parameter that is not a table",
                        o.dotted()
                    ),
                ));
            }
        }
        Ok(node)
    }

    fn inject_seed<P: StageParams>(&self, node: &mut Node) {
        let Value::Table(table) = &mut node.value else {
            return;
        };
        if table.get("seed").is_some() || !P::field_names().iter().any(|f| f == "seed") {
            return;
        }
        let default_is_integer = matches!(
            toml::Value::try_from(P::default()),
            Ok(toml::Value::Table(t)) if matches!(t.get("seed"), Some(toml::Value::Integer(_)))
        );
        if default_is_integer {
            let at = self.seed_at.unwrap_or(node.at);
            let seed = i64::try_from(self.seed).unwrap_or(i64::MAX);
            table.entries.push(Entry {
                key: "seed".into(),
                key_at: at,
                node: Node {
                    value: Value::Integer(seed),
                    at,
                },
            });
        }
    }

    fn deserialize_error(
        &self,
        e: DeError,
        table_at: Loc,
        variant: Option<&Variant>,
    ) -> WorkflowError {
        let at = e.at.unwrap_or(table_at);
        let table = format!("[{}]", e.path.join("."));
        let value = value_label(&e.path);
        let mut message = match &e.kind {
            DeErrorKind::UnknownField { field, expected } => {
                let hint = did_you_mean(field, expected.iter());
                if hint.is_empty() && !expected.is_empty() {
                    format!(
                        "unknown key '{field}' in {table} (valid keys: {})",
                        expected.join(", ")
                    )
                } else {
                    format!("unknown key '{field}' in {table}{hint}")
                }
            }
            DeErrorKind::MissingField(field) => {
                format!("missing key '{field}' in {table}: this parameter has no default, set it")
            }
            DeErrorKind::DuplicateField(field) => format!("key '{field}' is set twice in {table}"),
            DeErrorKind::InvalidType { found, expected } => {
                format!("{value}: wrong type: expected {expected}, found {found}")
            }
            DeErrorKind::InvalidValue { found, expected } => {
                format!("{value}: invalid value: expected {expected}, found {found}")
            }
            DeErrorKind::InvalidLength { len, expected } => {
                format!("{value}: has {len} elements, expected {expected}")
            }
            DeErrorKind::UnknownVariant { variant, expected } => format!(
                "{value}: unknown value '{variant}' (allowed: {}){}",
                expected.join(", "),
                did_you_mean(variant, expected.iter())
            ),
            DeErrorKind::Custom(text) => format!("{value}: {text}"),
        };
        message.push_str(&set_by_variant(variant, at));
        self.error(at, message)
    }

    fn validation_error<P: StageParams>(
        &self,
        params: &P,
        problems: Vec<ParamError>,
        stage: &str,
        node: &Node,
        variant: Option<&Variant>,
    ) -> WorkflowError {
        let as_toml = toml::Value::try_from(params).ok();
        let mut errors = Vec::with_capacity(problems.len());
        for problem in &problems {
            let mut path = vec![stage.to_string()];
            path.extend(problem.field.split('.').map(str::to_string));
            let written = find_path(node, &path[1..]);
            let (at, shown) = match written {
                Some(n) => (n.at, n.value.to_toml()),
                None => {
                    let default = as_toml
                        .as_ref()
                        .and_then(|t| plain_path(t, &path[1..]))
                        .map_or_else(
                            || "(not set)".to_string(),
                            |v| format!("{} (default)", v.to_string().trim()),
                        );
                    (node.at, default)
                }
            };
            let message = format!(
                "{} = {shown}: {}{}",
                value_label(&path),
                problem.message,
                set_by_variant(variant, at)
            );
            errors.push(self.error(at, message));
        }
        WorkflowError::combine(errors).unwrap_or_else(|| {
            self.error(
                node.at,
                format!("[{stage}]: parameters rejected by the stage's checks"),
            )
        })
    }
}

/// `[a.b] c` for the path a.b.c; `[a]` for a single part.
fn value_label(path: &[String]) -> String {
    match path.split_last() {
        Some((last, table)) if !table.is_empty() => format!("[{}] {last}", table.join(".")),
        Some((last, _)) => format!("[{last}]"),
        None => String::new(),
    }
}

/// `" (set by variant 'v')"` when `at` is one of the variant's overrides.
fn set_by_variant(variant: Option<&Variant>, at: Loc) -> String {
    match variant {
        Some(v)
            if v.overrides
                .iter()
                .any(|o| o.key_at == at || o.node.at == at) =>
        {
            format!(" (set by variant '{}')", v.name)
        }
        _ => String::new(),
    }
}

/// Sets `path` in `table` to `leaf`, creating intermediate tables; false if the path runs through a non-table.
fn set_path(table: &mut Table, path: &[String], leaf: Node, key_at: Loc) -> bool {
    let Some((first, rest)) = path.split_first() else {
        return false;
    };
    if rest.is_empty() {
        table.set(Entry {
            key: first.clone(),
            key_at,
            node: leaf,
        });
        return true;
    }
    if table.get(first).is_none() {
        let empty = Node {
            value: Value::Table(Table::default()),
            at: key_at,
        };
        table.entries.push(Entry {
            key: first.clone(),
            key_at,
            node: empty,
        });
    }
    match table.get_mut(first).map(|e| &mut e.node.value) {
        Some(Value::Table(inner)) => set_path(inner, rest, leaf, key_at),
        _ => false,
    }
}

fn find_path<'a>(node: &'a Node, path: &[String]) -> Option<&'a Node> {
    let Some((first, rest)) = path.split_first() else {
        return Some(node);
    };
    match &node.value {
        Value::Table(t) => find_path(&t.get(first)?.node, rest),
        _ => None,
    }
}

fn plain_path<'a>(value: &'a toml::Value, path: &[String]) -> Option<&'a toml::Value> {
    let Some((first, rest)) = path.split_first() else {
        return Some(value);
    };
    plain_path(value.as_table()?.get(first)?, rest)
}

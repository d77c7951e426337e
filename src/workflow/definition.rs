//! The `Workflow`: a loaded, checked workflow file — which campaign, which pipeline, which stages (in order),
//! each stage's parameter table, and the sweep variants. Loading checks everything that can be checked without
//! the stages' parameter types; `Workflow::params` (in `params.rs`) checks the rest per stage and variant.

use std::path::{Path, PathBuf};

use super::campaign_source::CampaignSource;
use super::error::WorkflowError;
use super::file::{load_document, WorkflowFiles, BUILT_IN_DIR};
use super::source::{describe_position, error_at, SourceFile};
use super::suggest::did_you_mean;
use super::sweep::{parse_sweep, valid_folder_name, Sweep};
use super::tree::{Entry, Loc, Table, Value};

/// Keys of a workflow file that are not stage tables.
pub const TOP_LEVEL_KEYS: &[&str] = &[
    "name",
    "description",
    "include",
    "campaign",
    "seed",
    "pipeline",
    "stages",
    "sweep",
];

/// Pipeline used when a workflow does not name one.
pub const DEFAULT_PIPELINE: &str = "skytie";

/// The single variant of a workflow without a sweep.
pub const DEFAULT_VARIANT: &str = "default";

/// A loaded workflow (see `workflows/README.md` for the file format).
#[derive(Debug, Clone)]
pub struct Workflow {
    /// `name = "..."`, or the workflow file's stem.
    pub name: String,
    /// `description = "..."` (informative).
    pub description: Option<String>,
    /// The workflow file as given.
    pub path: PathBuf,
    /// blake3 of the workflow file's bytes; when it includes other files, blake3 over all files read (each as
    /// shown path, NUL, length as u64 LE, bytes; in reading order), so editing an included file changes it too.
    pub file_hash: [u8; 32],
    pub campaign: CampaignSource,
    /// `seed = N` (default 0): seed of a synthetic campaign, and of randomised stages that do not set their own.
    pub seed: u64,
    /// `pipeline = "..."`, default "skytie".
    pub pipeline: String,
    /// Enabled stages, in file order.
    pub stages: Vec<String>,
    /// All files read: the workflow file first, then included files in reading order.
    pub sources: Vec<PathBuf>,
    pub(crate) files: Vec<SourceFile>,
    /// The merged document (stage tables are read from it).
    pub(crate) document: Table,
    /// Position of each entry of `stages`.
    pub(crate) stage_at: Vec<Loc>,
    pub(crate) seed_at: Option<Loc>,
    pub(crate) sweep: Option<Sweep>,
}

impl Workflow {
    /// Whether the workflow's `stages` list enables `stage`.
    pub fn enables(&self, stage: &str) -> bool {
        self.stages.iter().any(|s| s == stage)
    }

    /// Reads and checks a workflow file (and the files it includes).
    pub fn load(path: &Path) -> Result<Workflow, WorkflowError> {
        let bytes = std::fs::read(path).map_err(|e| {
            WorkflowError::in_file(
                path,
                format!("cannot read workflow file: {e} (check the path)"),
            )
        })?;
        let text = String::from_utf8(bytes).map_err(|e| {
            WorkflowError::in_file(path, format!("workflow file is not UTF-8 text: {e}"))
        })?;
        Workflow::parse(&text, path)
    }

    /// Checks a workflow given as text; `path` is where it lives (names it in messages, and relative `include`
    /// and campaign paths are resolved against its folder).
    pub fn parse(text: &str, path: &Path) -> Result<Workflow, WorkflowError> {
        Workflow::parse_from(text, path, WorkflowFiles::Disk)
    }

    /// A workflow built into the program: `name` (`default` or `default.toml`) among `files` (file name,
    /// text); its includes name other files of the set. Messages show `<built-in>/NAME.toml`.
    pub fn built_in(
        name: &str,
        files: &'static [(&'static str, &'static str)],
    ) -> Result<Workflow, WorkflowError> {
        let file = if name.ends_with(".toml") {
            name.to_string()
        } else {
            format!("{name}.toml")
        };
        let path = Path::new(BUILT_IN_DIR).join(&file);
        let Some((_, text)) = files.iter().find(|(n, _)| *n == file) else {
            return Err(WorkflowError::in_file(
                &path,
                format!(
                    "no built-in workflow '{name}' (built in: {})",
                    files
                        .iter()
                        .map(|(n, _)| n.trim_end_matches(".toml"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        };
        Workflow::parse_from(text, &path, WorkflowFiles::BuiltIn(files))
    }

    fn parse_from(
        text: &str,
        path: &Path,
        source: WorkflowFiles,
    ) -> Result<Workflow, WorkflowError> {
        let loaded = load_document(text, path, source)?;
        let mut files = loaded.sources;
        let file_hash = hash_sources(&files);
        for f in &mut files {
            f.bytes = Vec::new(); // hashed; keep only the paths for messages
        }
        interpret(loaded.document, files, path, file_hash)
    }

    /// Variant names: `["default"]` without a sweep, else the declared variants in order.
    pub fn variants(&self) -> Vec<String> {
        match &self.sweep {
            Some(sweep) if !sweep.variants.is_empty() => {
                sweep.variants.iter().map(|v| v.name.clone()).collect()
            }
            _ => vec![DEFAULT_VARIANT.to_string()],
        }
    }

    /// Whether the workflow declares sweep variants.
    pub fn is_sweep(&self) -> bool {
        self.sweep.as_ref().is_some_and(|s| !s.variants.is_empty())
    }

    /// The informative `[sweep] base = "..."`, if any.
    pub fn sweep_base(&self) -> Option<&str> {
        self.sweep.as_ref().and_then(|s| s.base.as_deref())
    }

    /// The `description` of a variant, if it has one.
    pub fn variant_description(&self, variant: &str) -> Option<&str> {
        let sweep = self.sweep.as_ref()?;
        sweep
            .variants
            .iter()
            .find(|v| v.name == variant)?
            .description
            .as_deref()
    }

    /// The overrides of a variant as (dotted parameter path, value written as TOML), in file order
    /// (empty for "default" of a workflow without sweep). Useful as columns of a sweep summary.
    pub fn variant_overrides(&self, variant: &str) -> Result<Vec<(String, String)>, WorkflowError> {
        Ok(match self.variant(variant)? {
            Some(v) => v
                .overrides
                .iter()
                .map(|o| (o.dotted(), o.node.value.to_toml()))
                .collect(),
            None => Vec::new(),
        })
    }

    /// Replaces the campaign (`--campaign DIR`); the path is used as given (relative to the current directory).
    pub fn override_campaign(&mut self, dir: PathBuf) {
        self.campaign = CampaignSource::Path(dir);
    }

    /// Checks `stages` against the stage names a pipeline knows; errors point at the unknown entry.
    pub fn check_stage_names(&self, known: &[&str]) -> Result<(), WorkflowError> {
        let errors: Vec<WorkflowError> = self
            .stages
            .iter()
            .zip(&self.stage_at)
            .filter(|(s, _)| !known.contains(&s.as_str()))
            .map(|(s, at)| {
                self.error(
                    *at,
                    format!(
                        "unknown stage '{s}' for pipeline '{}' (its stages: {}){}",
                        self.pipeline,
                        known.join(", "),
                        did_you_mean(s, known)
                    ),
                )
            })
            .collect();
        WorkflowError::combine(errors).map_or(Ok(()), Err)
    }

    /// The variant named `variant`: `None` for "default" (the workflow without overrides; in a sweep too, unless
    /// the sweep declares a variant of that name).
    pub(crate) fn variant(
        &self,
        variant: &str,
    ) -> Result<Option<&super::sweep::Variant>, WorkflowError> {
        match &self.sweep {
            Some(sweep) if !sweep.variants.is_empty() => {
                let found = sweep.variants.iter().find(|v| v.name == variant);
                if found.is_none() && variant == DEFAULT_VARIANT {
                    return Ok(None); // the unvaried workflow, also available in a sweep
                }
                found.map(Some).ok_or_else(|| {
                    let names: Vec<&str> = sweep.variants.iter().map(|v| v.name.as_str()).collect();
                    self.error(
                        sweep.at,
                        format!(
                            "unknown variant '{variant}' (variants: {}){}",
                            names.join(", "),
                            did_you_mean(variant, &names)
                        ),
                    )
                })
            }
            _ if variant == DEFAULT_VARIANT => Ok(None),
            _ => Err(WorkflowError::in_file(
                &self.path,
                format!("unknown variant '{variant}': this workflow has no sweep, its only variant is 'default'"),
            )),
        }
    }

    pub(crate) fn error(&self, at: Loc, message: impl Into<String>) -> WorkflowError {
        error_at(&self.files, at, message)
    }
}

fn hash_sources(files: &[SourceFile]) -> [u8; 32] {
    if let [only] = files {
        return *blake3::hash(&only.bytes).as_bytes();
    }
    let mut hasher = blake3::Hasher::new();
    for f in files {
        hasher.update(f.path.to_string_lossy().as_bytes());
        hasher.update(&[0]);
        hasher.update(&(f.bytes.len() as u64).to_le_bytes());
        hasher.update(&f.bytes);
    }
    *hasher.finalize().as_bytes()
}

/// Stage names: identifiers (letters, digits, `_`, `-`), not a top-level key.
fn valid_stage_name(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-'))
}

/// Turns the merged document into a `Workflow`, collecting every problem found.
fn interpret(
    document: Table,
    files: Vec<SourceFile>,
    path: &Path,
    file_hash: [u8; 32],
) -> Result<Workflow, WorkflowError> {
    let mut errors = Vec::new();
    let at = |loc: Loc, msg: String| error_at(&files, loc, msg);
    let string_of = |e: &Entry, errors: &mut Vec<WorkflowError>| -> Option<String> {
        match &e.node.value {
            Value::String(s) => Some(s.clone()),
            other => {
                errors.push(at(
                    e.node.at,
                    format!("{} must be a string, found {}", e.key, other.type_name()),
                ));
                None
            }
        }
    };

    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    let mut name = stem;
    if let Some(e) = document.get("name") {
        if let Some(s) = string_of(e, &mut errors) {
            if valid_folder_name(&s) {
                name = s;
            } else {
                errors.push(at(
                    e.node.at,
                    format!("name {s:?} cannot be used as a folder name: use letters, digits, '_', '-' or '.' (not first)"),
                ));
            }
        }
    }
    let description = document
        .get("description")
        .and_then(|e| string_of(e, &mut errors));

    let mut seed = 0u64;
    let mut seed_at = None;
    if let Some(e) = document.get("seed") {
        seed_at = Some(e.node.at);
        match e.node.value {
            Value::Integer(i) if i >= 0 => seed = i as u64,
            Value::Integer(i) => {
                errors.push(at(e.node.at, format!("seed = {i}: must be an integer ≥ 0")))
            }
            ref other => errors.push(at(
                e.node.at,
                format!("seed must be an integer ≥ 0, found {}", other.type_name()),
            )),
        }
    }

    let mut pipeline = DEFAULT_PIPELINE.to_string();
    if let Some(e) = document.get("pipeline") {
        match string_of(e, &mut errors) {
            Some(s) if !s.is_empty() => pipeline = s,
            Some(_) => errors.push(at(
                e.node.at,
                "pipeline must not be empty (default: \"skytie\")".into(),
            )),
            None => {}
        }
    }

    let (stages, stage_at) = read_stages(&document, &files, path, &mut errors);

    let mut campaign = None;
    match document.get("campaign") {
        Some(e) => {
            if let Some(text) = string_of(e, &mut errors) {
                let file_dir = files.get(e.node.at.file).and_then(|f| f.path.parent()).unwrap_or(Path::new(""));
                match CampaignSource::parse(&text, file_dir, seed) {
                    Ok(c) => campaign = Some(c),
                    Err(message) => errors.push(at(e.node.at, message)),
                }
            }
        }
        None => errors.push(WorkflowError::at(
            path,
            1,
            1,
            "missing key 'campaign': add campaign = \"path/to/campaign\" (relative to this file) or \"synth:demo\"",
        )),
    }

    let mut sweep = None;
    if let Some(e) = document.get("sweep") {
        let errors_before = errors.len();
        sweep = parse_sweep(e, &stages, &document, &files, &mut errors);
        if let Some(s) = &sweep {
            if s.variants.is_empty() && errors.len() == errors_before {
                errors.push(at(
                    e.key_at,
                    "[sweep] declares no variants: add [[sweep.variant]] tables with a name each, or remove [sweep]".into(),
                ));
            }
        }
    }

    // Everything else must be the parameter table of an enabled stage.
    for e in &document.entries {
        if TOP_LEVEL_KEYS.contains(&e.key.as_str()) {
            continue;
        }
        let candidates = || {
            TOP_LEVEL_KEYS
                .iter()
                .map(|s| s.to_string())
                .chain(stages.iter().cloned())
        };
        let is_stage = stages.contains(&e.key);
        match (&e.node.value, is_stage) {
            (Value::Table(_), true) => {}
            (other, true) => errors.push(at(
                e.node.at,
                format!(
                    "'{}' is a stage: its parameters go in a table [{}], found {}",
                    e.key,
                    e.key,
                    other.type_name()
                ),
            )),
            (Value::Table(_), false) => errors.push(at(
                e.key_at,
                format!(
                    "unknown stage '{}': a parameter table needs its stage listed in `stages` (enabled: {}){}",
                    e.key,
                    stages.join(", "),
                    did_you_mean(&e.key, candidates())
                ),
            )),
            (_, false) => errors.push(at(
                e.key_at,
                format!("unknown key '{}' at the top level{}", e.key, did_you_mean(&e.key, candidates())),
            )),
        }
    }

    // Report in file order; problems without a real position (missing keys) last.
    let (missing, mut located): (Vec<_>, Vec<_>) = errors
        .into_iter()
        .partition(|e| e.message.starts_with("missing key"));
    located.sort_by(|a, b| {
        (a.file != path, &a.file, a.line, a.column).cmp(&(
            b.file != path,
            &b.file,
            b.line,
            b.column,
        ))
    });
    located.extend(missing);
    if let Some(e) = WorkflowError::combine(located) {
        return Err(e);
    }
    let Some(campaign) = campaign else {
        return Err(WorkflowError::at(path, 1, 1, "missing key 'campaign'"));
    };
    Ok(Workflow {
        name,
        description,
        path: path.to_path_buf(),
        file_hash,
        campaign,
        seed,
        pipeline,
        stages,
        sources: files.iter().map(|f| f.path.clone()).collect(),
        files,
        document,
        stage_at,
        seed_at,
        sweep,
    })
}

/// Reads `stages = [...]`: a non-empty array of distinct stage names.
fn read_stages(
    document: &Table,
    files: &[SourceFile],
    path: &Path,
    errors: &mut Vec<WorkflowError>,
) -> (Vec<String>, Vec<Loc>) {
    let mut stages: Vec<String> = Vec::new();
    let mut stage_at: Vec<Loc> = Vec::new();
    let Some(e) = document.get("stages") else {
        errors.push(WorkflowError::at(
            path,
            1,
            1,
            "missing key 'stages': list the stages to run, e.g. stages = [\"ortho\", \"mm_match\", \"adjust\"]",
        ));
        return (stages, stage_at);
    };
    let Value::Array(items) = &e.node.value else {
        errors.push(error_at(
            files,
            e.node.at,
            format!(
                "stages must be an array of stage names, found {}",
                e.node.value.type_name()
            ),
        ));
        return (stages, stage_at);
    };
    if items.is_empty() {
        errors.push(error_at(
            files,
            e.node.at,
            "stages is empty: list at least one stage to run",
        ));
    }
    for item in items {
        match &item.value {
            Value::String(s) if TOP_LEVEL_KEYS.contains(&s.as_str()) => errors.push(error_at(
                files,
                item.at,
                format!("'{s}' is a reserved key, not a stage name"),
            )),
            Value::String(s) if !valid_stage_name(s) => errors.push(error_at(
                files,
                item.at,
                format!("stage name {s:?} is not an identifier (letters, digits, '_', '-')"),
            )),
            Value::String(s) => {
                if let Some(i) = stages.iter().position(|x| x == s) {
                    let first = describe_position(files, stage_at[i], item.at.file);
                    errors.push(error_at(
                        files,
                        item.at,
                        format!("stage '{s}' is listed twice (first at {first})"),
                    ));
                } else {
                    stages.push(s.clone());
                    stage_at.push(item.at);
                }
            }
            other => errors.push(error_at(
                files,
                item.at,
                format!(
                    "stages must contain stage names (strings), found {}",
                    other.type_name()
                ),
            )),
        }
    }
    (stages, stage_at)
}

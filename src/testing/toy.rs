//! Toy stages: parse a number from a file, scale it (with optional rounding, for early-cutoff tests), sum a
//! collection, and generate a folder of item files (the stand-in for the synthetic campaign generator).
//! Every stage can sleep per node and can be told to fail or panic on one item.

use crate::dag::{Handle, InputsOf, NodeCtx, RawFile, RunResult, Stage, StageError};
use crate::workflow::{ParamError, StageParams};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Fault injection and pacing shared by all toy stages.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Faults {
    /// Milliseconds each node sleeps (lets tests kill a run mid-way).
    pub sleep_ms: u64,
    /// Item label that returns an error (`*` = every item).
    pub fail_item: String,
    /// Item label that panics (`*` = every item).
    pub panic_item: String,
}

impl Faults {
    fn apply(&self, ctx: &NodeCtx) -> Result<(), StageError> {
        if self.sleep_ms > 0 {
            std::thread::sleep(std::time::Duration::from_millis(self.sleep_ms));
        }
        let hits = |pattern: &str| pattern == "*" || (!pattern.is_empty() && pattern == ctx.item());
        if hits(&self.fail_item) {
            return Err(StageError::new(format!(
                "toy failure injected on item {}",
                ctx.item()
            )));
        }
        if hits(&self.panic_item) {
            panic!("toy panic injected on item {}", ctx.item());
        }
        Ok(())
    }
}

/// Reads one number from a text file.
pub struct ToyParse;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ToyParseParams {
    /// Pacing and fault injection: `[stage.faults]` in a workflow.
    pub faults: Faults,
}

impl Stage for ToyParse {
    crate::stage_items!("toy_parse", "1", ToyParseParams => f64, inputs: RawFile);
    fn run(&self, p: &ToyParseParams, file: InputsOf<Self>, ctx: &NodeCtx) -> RunResult<Self> {
        p.faults.apply(ctx)?;
        let text = std::fs::read_to_string(&file.path)
            .map_err(|e| StageError::new(format!("{}: cannot read: {e}", file.path.display())))?;
        text.trim().parse::<f64>().map_err(|e| {
            StageError::new(format!(
                "{}: expected one number, found {:?} ({e})",
                file.path.display(),
                text.trim()
            ))
        })
    }
}

/// Multiplies a number by `factor`, then rounds to a multiple of `quantum` (0 = no rounding).
pub struct ToyScale;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ToyScaleParams {
    pub factor: f64,
    pub quantum: f64,
    /// Pacing and fault injection: `[stage.faults]` in a workflow.
    pub faults: Faults,
}

impl Default for ToyScaleParams {
    fn default() -> Self {
        ToyScaleParams {
            factor: 2.0,
            quantum: 0.0,
            faults: Faults::default(),
        }
    }
}

impl Stage for ToyScale {
    crate::stage_items!("toy_scale", "1", ToyScaleParams => f64, inputs: Handle<f64>);
    fn run(&self, p: &ToyScaleParams, v: InputsOf<Self>, ctx: &NodeCtx) -> RunResult<Self> {
        p.faults.apply(ctx)?;
        let x = *v * p.factor;
        Ok(if p.quantum > 0.0 {
            (x / p.quantum).round() * p.quantum
        } else {
            x
        })
    }
}

/// A version-bumped twin of [`ToyScale`] (same name, VERSION "2") for stage-version tests.
pub struct ToyScaleV2;

impl Stage for ToyScaleV2 {
    crate::stage_items!("toy_scale", "2", ToyScaleParams => f64, inputs: Handle<f64>);
    fn run(&self, p: &ToyScaleParams, v: InputsOf<Self>, ctx: &NodeCtx) -> RunResult<Self> {
        ToyScale.run(p, v, ctx)
    }
}

/// Sum and count of a collection of numbers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToySummary {
    pub sum: f64,
    pub count: u64,
}
crate::serde_artifact!(ToySummary);

/// Sums a collection (a global node).
pub struct ToySum;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ToySumParams {
    pub offset: f64,
    /// Pacing and fault injection: `[stage.faults]` in a workflow.
    pub faults: Faults,
}

impl Stage for ToySum {
    crate::stage_items!("toy_sum", "1", ToySumParams => ToySummary, inputs: Vec<Handle<f64>>);
    fn run(&self, p: &ToySumParams, values: InputsOf<Self>, ctx: &NodeCtx) -> RunResult<Self> {
        p.faults.apply(ctx)?;
        // Sequential sum in input order: deterministic whatever the thread count.
        let sum = values.iter().map(|v| **v).sum::<f64>() + p.offset;
        Ok(ToySummary {
            sum,
            count: values.len() as u64,
        })
    }
}

/// A generated folder inside the cache (the output of [`ToyGen`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToyDir {
    pub path: String,
    pub files: Vec<String>,
}
crate::serde_artifact!(ToyDir);

/// Writes `count` item files `items/item_NNN.txt` holding numbers derived from `seed` (the stand-in for
/// the synthetic campaign generator: a node whose output decides the next part of the graph).
pub struct ToyGen;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ToyGenParams {
    pub count: u32,
    pub seed: u64,
    /// Pacing and fault injection: `[stage.faults]` in a workflow.
    pub faults: Faults,
}

impl Default for ToyGenParams {
    fn default() -> Self {
        ToyGenParams {
            count: 4,
            seed: 1,
            faults: Faults::default(),
        }
    }
}

impl Stage for ToyGen {
    crate::stage_items!("toy_gen", "1", ToyGenParams => ToyDir, inputs: ());
    fn run(&self, p: &ToyGenParams, _: InputsOf<Self>, ctx: &NodeCtx) -> RunResult<Self> {
        p.faults.apply(ctx)?;
        let tmp = ctx.output_dir_tmp()?;
        let mut files = Vec::new();
        for i in 0..p.count {
            let name = format!("item_{i:03}.txt");
            let value = (p.seed.wrapping_mul(31).wrapping_add(i as u64 * 7)) % 100;
            write_item(&tmp.join("items"), &name, value as f64)?;
            files.push(format!("items/{name}"));
        }
        Ok(ToyDir {
            path: ctx.output_dir().to_string_lossy().into_owned(),
            files,
        })
    }
    fn cached_output_ok(&self, out: &ToyDir, _ctx: &NodeCtx) -> bool {
        out.files
            .iter()
            .all(|f| Path::new(&out.path).join(f).is_file())
    }
}

/// Write one toy item file (atomically).
pub fn write_item(dir: &Path, name: &str, value: f64) -> std::io::Result<PathBuf> {
    let p = dir.join(name);
    skytie_util::fsutil::atomic_write(&p, format!("{value}\n").as_bytes())?;
    Ok(p)
}

/// The item files of a toy campaign folder (`<dir>/items/*.txt`), sorted by name.
pub fn list_items(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let items = dir.join("items");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&items)
        .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", items.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "txt"))
        .collect();
    files.sort();
    Ok(files)
}

/// Item label of a toy item file: its stem.
pub fn item_label(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

impl StageParams for ToyParseParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        Ok(())
    }
}

impl StageParams for ToyScaleParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        let mut errors = Vec::new();
        if !self.factor.is_finite() {
            errors.push(ParamError::new("factor", "must be a finite number"));
        }
        if !(self.quantum >= 0.0 && self.quantum.is_finite()) {
            errors.push(ParamError::new("quantum", "must be >= 0 (0 = no rounding)"));
        }
        if errors.is_empty() {
            Ok(())
        } else {
            Err(errors)
        }
    }
}

impl StageParams for ToySumParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        if self.offset.is_finite() {
            Ok(())
        } else {
            Err(vec![ParamError::new("offset", "must be a finite number")])
        }
    }
}

impl StageParams for ToyGenParams {
    fn validate(&self) -> Result<(), Vec<ParamError>> {
        if self.count <= 100_000 {
            Ok(())
        } else {
            Err(vec![ParamError::new("count", "must be in [0, 100000]")])
        }
    }
}

//! Shared helpers of the engine tests: toy campaigns in temp folders, a toy DAG builder, one-call runs.
#![allow(dead_code)]

use skytie::dag::{Dag, DagBuilder, Handle, Mode, Outcome, RawFile};
use skytie::testing::harness::SilentEngine;
use skytie::testing::toy::{
    write_item, ToyParse, ToyParseParams, ToyScale, ToyScaleParams, ToyScaleV2, ToySum,
    ToySumParams, ToySummary,
};
use std::path::{Path, PathBuf};

/// Write items `item_000.txt …` with `values` into `<dir>/items/`; returns the paths.
pub fn make_items(dir: &Path, values: &[f64]) -> Vec<PathBuf> {
    values
        .iter()
        .enumerate()
        .map(|(i, v)| write_item(&dir.join("items"), &format!("item_{i:03}.txt"), *v).unwrap())
        .collect()
}

/// Parameters of the toy DAG.
#[derive(Clone, Default)]
pub struct ToyConfig {
    pub parse: ToyParseParams,
    pub scale: ToyScaleParams,
    pub sum: ToySumParams,
    /// Use the version-2 twin of toy_scale.
    pub scale_v2: bool,
}

/// Add parse → scale per item and one sum to `b`; returns the sum's handle (requested).
pub fn add_toy(b: &mut DagBuilder, items: &[PathBuf], cfg: &ToyConfig) -> Handle<ToySummary> {
    let mut hs = Vec::new();
    for f in items {
        let label = f.file_stem().unwrap().to_string_lossy().into_owned();
        let p = b
            .add(ToyParse, &label, cfg.parse.clone(), RawFile(f.clone()))
            .unwrap();
        let s = if cfg.scale_v2 {
            b.add(ToyScaleV2, &label, cfg.scale.clone(), p).unwrap()
        } else {
            b.add(ToyScale, &label, cfg.scale.clone(), p).unwrap()
        };
        hs.push(s);
    }
    let h = b.add(ToySum, "", cfg.sum.clone(), hs).unwrap();
    b.request(h);
    h
}

/// A temporary folder holding the toy item files with `values` (see [`make_items`]), and the path of a cache
/// folder inside it.
pub fn toy_workspace(values: &[f64]) -> (tempfile::TempDir, PathBuf, Vec<PathBuf>) {
    let dir = tempfile::tempdir().unwrap();
    let items = make_items(dir.path(), values);
    let cache = dir.path().join("cache");
    (dir, cache, items)
}

/// The toy DAG of one configuration.
pub fn toy_dag(items: &[PathBuf], cfg: &ToyConfig) -> (Dag, Handle<ToySummary>) {
    let mut b = DagBuilder::new();
    let h = add_toy(&mut b, items, cfg);
    (b.build(), h)
}

/// Execute `dag` against the cache at `cache` (silent progress).
pub fn run(cache: &Path, dag: &Dag, mode: Mode) -> Outcome {
    SilentEngine::open(cache).unwrap().execute(dag, mode)
}

/// Builds the toy DAG of one configuration and runs it against the cache at `cache`: the outcome and the sum's
/// handle.
pub fn run_toy(cache: &Path, items: &[PathBuf], cfg: &ToyConfig) -> (Outcome, Handle<ToySummary>) {
    let (dag, h) = toy_dag(items, cfg);
    (run(cache, &dag, Mode::Run), h)
}

/// Executed count per stage name of an outcome, as (parse, scale, sum).
pub fn executed(o: &Outcome) -> (usize, usize, usize) {
    (
        o.executed_of("toy_parse"),
        o.executed_of("toy_scale"),
        o.executed_of("toy_sum"),
    )
}
pub mod module_graph;

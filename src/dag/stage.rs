//! The `Stage` trait: one typed, cacheable computation of the dataflow DAG, and the context a node runs in.
//!
//! A stage is a plain Rust type. Its cache identity is `NAME` + `VERSION` + the canonical encoding of its
//! `Params` + the content hashes of its inputs (see `dag::key`). Bump `VERSION` whenever the code changes
//! what the stage computes: that re-runs exactly this stage's nodes (and dependents whose inputs change).

use crate::codec::Artifact;
use crate::dag::error::StageError;
use crate::dag::inputs::InputSet;
use crate::dag::progress::Progress;
use crate::hashing::NodeKey;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Declares a [`Stage`]'s name, version and its parameter, output and input types in one line:
/// `skytie::stage_items!("toy_sum", "1", ToySumParams => ToySummary, inputs: Vec<Handle<f64>>);`
/// inside `impl Stage for …`.
#[macro_export]
macro_rules! stage_items {
    ($name:expr, $version:expr, $params:ty => $output:ty, inputs: $inputs:ty) => {
        const NAME: &'static str = $name;
        const VERSION: &'static str = $version;
        type Params = $params;
        type Output = $output;
        type Inputs = $inputs;
    };
}

/// A typed DAG computation. See the module documentation.
pub trait Stage: Send + Sync + 'static {
    /// Stable stage name (used in keys, workflows, metrics: keep it snake_case).
    const NAME: &'static str;
    /// Version of the stage's semantics; part of every key of this stage.
    const VERSION: &'static str;
    /// Parameters, deserialised from the workflow and canonically encoded into the key.
    type Params: Serialize + DeserializeOwned + Clone + Send + Sync + 'static;
    /// The artifact this stage produces (stored in the cache).
    type Output: Artifact;
    /// The typed inputs: a `Handle<T>`, `RawFile`, `Vec<…>` of those, tuples of those, or `()`.
    type Inputs: InputSet;

    /// Compute the output. Errors (and panics, which the executor catches) mark the node failed; a failed
    /// node is never stored, its dependents are skipped.
    fn run(
        &self,
        params: &Self::Params,
        inputs: <Self::Inputs as InputSet>::Values,
        ctx: &NodeCtx,
    ) -> Result<Self::Output, StageError>;

    /// Called on a cache hit of an output that is needed: return false if the output refers to something
    /// outside the store that is gone (e.g. a generated folder was deleted), and the node is recomputed.
    fn cached_output_ok(&self, _output: &Self::Output, _ctx: &NodeCtx) -> bool {
        true
    }
}

/// The input values `Stage::run` of `S` receives (what its `Inputs` resolve to).
pub type InputsOf<S> = <<S as Stage>::Inputs as InputSet>::Values;

/// What `Stage::run` of `S` returns.
pub type RunResult<S> = Result<<S as Stage>::Output, StageError>;

/// What a running node may know about itself, and where it reports progress within itself.
pub struct NodeCtx<'a> {
    pub(crate) stage: &'static str,
    pub(crate) item: String,
    pub(crate) key: NodeKey,
    pub(crate) cache_root: PathBuf,
    pub(crate) progress: Option<&'a Progress>,
}

impl NodeCtx<'_> {
    /// Reports how far a long node is: `done` of `total` steps (e.g. images rendered). A stage with a single
    /// node shows it as its bar (items, rate, ETA); for stages of many nodes the bar counts nodes and this is
    /// ignored.
    pub fn report_steps(&self, done: u64, total: u64) {
        if let Some(p) = self.progress {
            p.node_steps(self.stage, done, total);
        }
    }

    /// Stage name.
    pub fn stage(&self) -> &'static str {
        self.stage
    }
    /// The node's item label (e.g. `rec 0012`), empty for global nodes.
    pub fn item(&self) -> &str {
        &self.item
    }
    /// The node's cache key.
    pub fn key(&self) -> NodeKey {
        self.key
    }
    /// A deterministic per-node seed derived from a base seed and the item label (never from thread
    /// order), for stages that draw random numbers.
    pub fn item_seed(&self, base_seed: u64) -> u64 {
        let mut h = blake3::Hasher::new();
        h.update(b"skytie item seed\0");
        h.update(&base_seed.to_le_bytes());
        h.update(self.stage.as_bytes());
        h.update(&[0]);
        h.update(self.item.as_bytes());
        let b = h.finalize();
        u64::from_le_bytes(b.as_bytes()[..8].try_into().expect("8 bytes"))
    }
    /// The folder a node producing files owns: `<cache root>/dirs/<key hex>/`. The stage writes into
    /// [`NodeCtx::output_dir_tmp`]; the executor renames it here only after the stage succeeded, so a folder
    /// at this path is always complete. Record this path (not the temporary one) in the output artifact.
    pub fn output_dir(&self) -> PathBuf {
        dirs_root(&self.cache_root).join(self.key.to_string())
    }
    /// A fresh, empty temporary folder (created on first call) the stage writes its files into.
    pub fn output_dir_tmp(&self) -> std::io::Result<PathBuf> {
        let p = tmp_dir_for(&self.cache_root, &self.key);
        if p.exists() {
            std::fs::remove_dir_all(&p)?;
        }
        std::fs::create_dir_all(&p)?;
        Ok(p)
    }

    /// A folder for work in progress that must survive an interrupted run of this node (e.g. the finished images
    /// of a long synthetic render), `<cache>/dirs/.partial-<key>`: not emptied at the start, unlike
    /// [`NodeCtx::output_dir_tmp`]. The stage removes it when it has finished.
    pub fn partial_dir(&self) -> PathBuf {
        dirs_root(&self.cache_root).join(format!(".partial-{}", self.key))
    }
}

pub(crate) fn dirs_root(cache_root: &Path) -> PathBuf {
    cache_root.join("dirs")
}

pub(crate) fn tmp_dir_for(cache_root: &Path, key: &NodeKey) -> PathBuf {
    dirs_root(cache_root).join(format!(".tmp-{}-{}", key, std::process::id()))
}

//! A node of the DAG with its stage type erased, so nodes of many stage types live in one graph.

use crate::codec::{Artifact, CodecError};
use crate::dag::error::StageError;
use crate::dag::inputs::{InputRef, InputSet, InputValue};
use crate::dag::stage::{NodeCtx, Stage};
use std::any::Any;
use std::io::{self, Read, Write};
use std::sync::Arc;

/// A node's output value, type-erased.
pub type AnyValue = Arc<dyn Any + Send + Sync>;

/// The operations the executor needs on a node, independent of its stage type.
pub(crate) trait ErasedStage: Send + Sync {
    fn run(&self, inputs: &[InputValue], ctx: &NodeCtx) -> Result<AnyValue, StageError>;
    /// Streams the encoding of `value` to `sink` (the store writes it straight into the entry file).
    fn encode_to(&self, value: &AnyValue, sink: &mut dyn Write) -> io::Result<()>;
    /// Decodes a value from the next `len` bytes of `source` (the store reads it straight from the file).
    fn decode_from(&self, source: &mut dyn Read, len: u64) -> Result<AnyValue, CodecError>;
    fn cached_output_ok(&self, value: &AnyValue, ctx: &NodeCtx) -> bool;
}

/// A stage together with its params and input handles.
pub(crate) struct TypedNode<S: Stage> {
    pub stage: S,
    pub params: S::Params,
    pub inputs: S::Inputs,
}

fn wrong_type<S: Stage>() -> StageError {
    StageError::new(format!(
        "internal error: value of the wrong type for stage {} (please report)",
        S::NAME
    ))
}

impl<S: Stage> ErasedStage for TypedNode<S> {
    fn run(&self, inputs: &[InputValue], ctx: &NodeCtx) -> Result<AnyValue, StageError> {
        let mut it = inputs.iter();
        let values = self.inputs.take_values(&mut it)?;
        let out = self.stage.run(&self.params, values, ctx)?;
        Ok(Arc::new(out))
    }
    fn encode_to(&self, value: &AnyValue, sink: &mut dyn Write) -> io::Result<()> {
        let v = value
            .downcast_ref::<S::Output>()
            .ok_or_else(|| io::Error::other(wrong_type::<S>().message))?;
        v.encode_to(sink)
    }
    fn decode_from(&self, source: &mut dyn Read, len: u64) -> Result<AnyValue, CodecError> {
        Ok(Arc::new(S::Output::decode_from(source, len)?))
    }
    fn cached_output_ok(&self, value: &AnyValue, ctx: &NodeCtx) -> bool {
        match value.downcast_ref::<S::Output>() {
            Some(v) => self.stage.cached_output_ok(v, ctx),
            None => false,
        }
    }
}

/// Everything the engine knows about one node.
pub struct Node {
    pub stage: &'static str,
    pub version: &'static str,
    /// Item label (`rec 0012`, `pair 3-4`), empty for global nodes.
    pub item: String,
    /// Variants of a sweep that use this node (a node shared by variants lists all of them).
    pub variants: Vec<String>,
    /// Canonical params bytes (part of the key), shared by the nodes with equal params.
    pub params_bytes: Arc<[u8]>,
    /// The same params as JSON, to tell which field changed.
    pub params_json: Arc<serde_json::Value>,
    /// Labelled input edges, in the order the stage receives them (labels are shared between nodes).
    pub inputs: Vec<(Arc<str>, InputRef)>,
    pub(crate) erased: Box<dyn ErasedStage>,
    /// The caller wants this node's value after the run.
    pub requested: bool,
}

impl Node {
    /// Human identity, independent of variant and key: `stage[item]` or `stage` for global nodes.
    pub fn identity(&self) -> String {
        if self.item.is_empty() {
            self.stage.to_string()
        } else {
            format!("{}[{}]", self.stage, self.item)
        }
    }
    /// Ids of the nodes this node reads (each once, ascending).
    pub fn upstream_ids(&self) -> Vec<usize> {
        let mut ids: Vec<usize> = self.inputs.iter().filter_map(|(_, r)| r.node()).collect();
        ids.sort_unstable();
        ids.dedup();
        ids
    }
}

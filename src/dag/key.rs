//! A node's cache key: stage name, stage version, canonical params and the CONTENT hashes of its inputs.
//!
//! Using the inputs' content hashes (not their keys) gives early cutoff: an upstream node that re-runs
//! but produces identical bytes leaves its consumers' keys unchanged, so they stay cached.

use crate::dag::node::Node;
use crate::hashing::{ContentHash, KeyBuilder, NodeKey};

/// The key of `node` given the content hashes of its inputs, in `node.inputs` order.
pub fn node_key(node: &Node, input_hashes: &[ContentHash]) -> NodeKey {
    debug_assert_eq!(node.inputs.len(), input_hashes.len());
    let mut kb = KeyBuilder::new(node.stage, node.version).params(&node.params_bytes);
    for ((label, _), hash) in node.inputs.iter().zip(input_hashes) {
        kb = kb.input(label, hash);
    }
    kb.finish()
}

//! skytie engine: typed dataflow DAG with content-addressed caching, workflows, CLI support.
pub mod codec;
pub mod hashing;
pub mod workflow;
pub mod store;
pub mod cache_cmd;

//! skytie engine: typed dataflow DAG with content-addressed caching, workflows, CLI support.
//!
//! Layers: [`hashing`] / [`codec`] / [`store`] (content-addressed artifacts), [`workflow`] (TOML workflows
//! and sweeps), [`dag`] (typed stages, graph building, keys, executor, sessions and pipelines),
//! [`progress`](dag::progress) / [`metrics`] / [`provenance`] / [`plan`] / [`explain`] (what a run reports), [`report`] (the HTML report), [`eval`] (the held-out evaluation), [`cli`] (the
//! `skytie` command), [`testing`] (toy stages and the `toy` pipeline used by tests and benchmarks).
pub mod cache_cmd;
pub mod cli;
pub mod codec;
pub mod dag;
pub mod eval;
pub mod explain;
pub mod exports;
pub mod hashing;
pub mod metrics;
pub mod nodes;
pub mod pipelines;
pub mod plan;
pub mod provenance;
pub mod report;
pub mod store;
pub mod testing;
pub mod workflow;

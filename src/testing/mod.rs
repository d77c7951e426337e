//! Toy stages and the `toy` pipeline, used by the engine's tests, the benchmark and the CLI tests (a
//! workflow with `pipeline = "toy"`). They exercise every engine feature (raw-file inputs, per-item and
//! global nodes, collections, generated folders, failures, panics, sleeps) without photogrammetry. `city`
//! builds a DAG of toy stages shaped like a city campaign, for the engine benchmark at scale; `harness` opens
//! a cache for a test or benchmark in one call and reads the process' CPU time and memory.

pub mod city;
pub mod harness;
pub mod toy;
pub mod toy_pipeline;

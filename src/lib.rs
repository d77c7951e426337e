//! skytie engine: typed dataflow DAG with content-addressed caching, workflows, CLI support.

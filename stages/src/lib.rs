//! skytie-stages: all of skytie's photogrammetry, independent of the caching engine.
//!
//! Layers (bottom to top): [`geometry`] (cameras, rotations, triangulation, 2-D transforms),
//! [`imaging`] (image buffers, sampling, filters), [`campaign`] (the input/output contract of
//! `docs/campaign-format.md`), [`synth`] (the synthetic campaign generator). The engine in the
//! root crate wraps the stages built from these as cached DAG nodes.

pub mod adjustment;
pub mod campaign;
pub mod correction;
pub mod correspondence;
pub mod crs;
pub mod estimators;
pub mod export;
pub mod features;
pub mod formats;
pub mod geometry;
pub mod imaging;
pub mod import;
pub mod matching;
pub mod nadir;
pub mod oblique;
pub mod orthophoto;
pub mod params;
pub mod positions;
pub mod ratio;
pub mod rng;
pub mod synth;

/// Atomic file replacement (from `skytie-util`, shared with the engine).
pub use skytie_util::fsutil;

//! Pipelines built from the real stages (`pipeline = "skytie"`, the default). The `toy` pipeline used by the
//! engine's own tests lives in `crate::testing`.

pub mod adjust;
pub mod nadir;
pub mod oblique;
pub mod skytie;

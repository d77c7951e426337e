//! The campaign contract (shared/docs/campaign-format.md): model, reading with validation, writers.

pub mod model;

pub use model::{AerialImage, AerialKind, Campaign, CheckPoint, Observation, Recording};

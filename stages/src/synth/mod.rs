//! The synthetic urban campaign: a procedural street scene (by "scene": [`scene`], [`noise`], [`texture`])
//! rendered into mobile-mapping panoramas and aerial nadir/oblique frames, with recorded tables made erroneous
//! by a named error [`profile`], true poses, check points and their observations, written in the campaign
//! format (docs/campaign-format.md). It is skytie's embedded default data and the judge of every stage.
//!
//! Entry points: [`generate`](mod@generate) / [`generate_preset`] (or the two steps [`render_campaign`] and
//! [`apply_profile`]); the pieces ([`render`], [`aerial_plan`], [`trajectory`], [`profile`], [`control`],
//! [`postprocess`], [`vehicle`]) are public for tests and benchmarks.

pub mod noise;
pub mod scene;
pub mod texture;

pub mod aerial_plan;
pub mod control;
pub mod error;
pub mod generate;
pub mod options;
pub mod orthophoto;
pub mod output;
pub mod plan;
pub mod postprocess;
pub mod preset;
pub mod profile;
pub mod render;
pub mod render_store;
pub mod rng;
pub mod scene_truth;
pub mod sizes;
pub mod test_texture;
pub mod trajectory;
pub mod vehicle;

pub use error::SynthError;
pub use generate::{
    apply_profile, generate, generate_preset, generate_resumable, render_campaign, SynthOptions,
    SynthSummary,
};
pub use preset::{Preset, PresetParams};
pub use profile::{Component, Profile};
pub use render::{render_frame, render_panorama, render_panorama_with_vehicle};

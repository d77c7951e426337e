//! The nadir pipeline (thesis chapter 3): ortho-projection of panoramas, MM-to-MM matching, the initial KAZE
//! transform to aerial nadir patches, phase-correlation refinement and aerial control points.

pub mod aerial_overlap;
pub mod aerial_patch;
pub mod baseline;
pub mod control_points;
pub mod footprint_index;
pub mod grading;
pub mod initial_transform;
pub mod mm_matching;
pub mod neighbour_transform;
pub mod ortho;
pub mod ortho_mask;
pub mod parallax_check;
pub mod peak_support;
pub mod refine;
pub mod registration;
pub mod summary;
pub mod transform_agreement;
pub mod translation_consensus;
pub mod vehicle_detect;
pub mod vehicle_mask;

pub use ortho::{ortho_project, ortho_project_whole, OrthoGeoref, OrthoImage, OrthoParams};
pub use registration::{
    AerialMatch, AerialRefinement, InitialTransform, MmWindowMatch, PairMethod, PairReport,
    RecordingControl, RefinementMisses, TransformOutcome, ViewGround,
};
pub use vehicle_mask::VehicleMask;

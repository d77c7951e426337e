//! The nadir pipeline's nodes (thesis chapter 3): ortho-projection, MM-to-MM matching, the aerial-oriented
//! orthos, initial transforms and their agreement, phase-correlation refinement (or the chapter-2 baseline),
//! aerial control points, the summary and the grading on truth; the recording vehicle found in the panoramas.

pub mod baseline;
pub mod control;
pub mod dtm;
pub mod grade;
pub mod mm_match;
pub mod options;
pub mod ortho;
pub mod ortho_aerial;
pub mod orthophoto;
pub mod orthophoto_ortho;
pub mod orthophoto_points;
pub mod orthophoto_summary;
pub mod peak_support;
pub mod refine;
pub mod summary;
pub mod transform;
pub mod transform_agreement;
pub mod vehicle;
